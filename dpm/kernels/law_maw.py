"""Maw linear spring: a linear spring-dashpot with the stiffness of an equivalent Hertz contact.

DPM thesis (Samiei 2012) §2.6.2, eq. 2.29 (after Di Renzo & Di Maio 2004, Maw et al. 1976):
the spring stores at maximum compression the strain energy of a Hertz contact hit at the
characteristic impact speed v,
    k_n = 16/15 sqrt(R*) E* (15 m* v^2 / (16 sqrt(R*) E*))^(1/5)
        = C R*^(2/5) m*^(1/5),        C = (16/15)^(4/5) E*^(4/5) v^(2/5)
    F_n = max(0, k_n delta + c_n delta'),   c_n = 2 zeta sqrt(m* k_n)
Tangential spring-dashpot with slip history and Coulomb limit (eq. 2.33, 2.34):
    k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_t),  zeta_t = -ln e_t / sqrt(ln^2 e_t + pi^2)
m* and R* are the contact's own: each pair gets the energy-equivalent spring of its size.

pair_params row: [C, zeta, mu, kappa, zeta_t, (rolling), rolling model, mu_r]
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb


@inline_jit
def maw_linear_spring(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    kn = p[0] * reff**0.4 * meff**0.2
    fn = kn * delta + 2.0 * p[1] * math.sqrt(meff * kn) * ddelta
    if fn < 0.0:
        fn = 0.0
    kt = p[3] * kn
    ct = 2.0 * p[4] * math.sqrt(meff * kt)
    ftx, fty, ftz = spring_coulomb(kt, ct, p[2], fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k)
    return fn, ftx, fty, ftz
