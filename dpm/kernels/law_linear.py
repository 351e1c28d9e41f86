"""Linear spring-dashpot contact law (Cundall & Strack 1979; DPM thesis, Samiei 2012 §2.6.1).

Normal:      F_n = max(0, k_n delta + c_n delta'),   c_n = 2 zeta sqrt(m* k_n)
Tangential:  spring-dashpot with history and Coulomb limit
             (:func:`.tangential.spring_coulomb`: while sliding the spring alone
             carries mu F_n), k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_n)

The damping ratio zeta is solved in the object layer so that the restitution coefficient
*with the attractive force cut off* equals the one the user set (Schwager & Poschel 2007:
e = exp(-beta t_c), t_c = (pi - 2 atan(beta/omega)) / omega, beta = zeta omega_0,
omega = omega_0 sqrt(1 - zeta^2)).

pair_params row: [k_n, zeta, mu, kappa, zeta_t, 0, rolling model, mu_r]
(slots 6, 7: rolling resistance model and coefficient, read by the step)
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb


@inline_jit
def linear_spring_dashpot(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    kn = p[0]
    cn = 2.0 * p[1] * math.sqrt(meff * kn)
    fn = kn * delta + cn * ddelta
    if fn < 0.0:
        fn = 0.0
    kt = p[3] * kn
    ct = 2.0 * p[4] * math.sqrt(meff * kn)
    ftx, fty, ftz = spring_coulomb(kt, ct, p[2], fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k)
    return fn, ftx, fty, ftz
