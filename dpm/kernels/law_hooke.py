"""Hooke's law: a linear spring-dashpot whose stiffness comes from the elastic constants.

DPM thesis (Samiei 2012) §2.6.3, eq. 2.36 (ERRATA: k = 4/3 E* R*, not sqrt(R*)):
    k_n = 4/3 E* R*            F_n = max(0, k_n delta + c_n delta'),  c_n = 2 zeta sqrt(m* k_n)
Tangential as the linear spring-dashpot (:mod:`.law_linear`):
    k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_n), history and Coulomb limit mu F_n
(kappa = 0 gives the thesis' purely viscous F_t = min(c_t |v_t|, mu F_n)).
R* and m* are the contact's own, so the stiffness follows the size of each pair.

pair_params row: [E*, zeta, mu, kappa, zeta_t, (rolling), rolling model, mu_r]
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb


@inline_jit
def hooke(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    kn = 4.0 / 3.0 * p[0] * reff
    sq = math.sqrt(meff * kn)
    fn = kn * delta + 2.0 * p[1] * sq * ddelta
    if fn < 0.0:
        fn = 0.0
    ftx, fty, ftz = spring_coulomb(p[3] * kn, 2.0 * p[4] * sq, p[2], fn, vtx, vty, vtz,
                                   nx, ny, nz, dt, hist, k)
    return fn, ftx, fty, ftz
