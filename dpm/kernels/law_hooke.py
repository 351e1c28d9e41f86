"""Hooke's law: a linear spring-dashpot whose stiffness comes from the elastic constants.

DPM thesis (Samiei 2012) §2.6.3, eq. 2.36 (ERRATA: k = 4/3 E* R*, not sqrt(R*)):
    k_n = 4/3 E* R*            F_n = max(0, k_n delta + c_n delta'),  c_n = 2 zeta sqrt(m* k_n)
Tangential as the linear spring-dashpot (:mod:`.law_linear`):
    k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_n), history and Coulomb limit mu F_n
(kappa = 0 gives the thesis' purely viscous F_t = min(c_t |v_t|, mu F_n)).
R* and m* are the contact's own, so the stiffness follows the size of each pair.

Slots: normal (E*, zeta); tangential :func:`.tangential.linear_tangential`.
Normal part (:class:`dpm.impact.parts.NormalPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``, q its slots of the pair
row, h the offset of its history in ``hist[k]``; k_n the stiffness a tangential part may
scale with.
"""

import math

from .config import inline_jit


@inline_jit
def hooke_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """k_n = 4/3 E* R*, F_n = max(0, k_n d + 2 zeta sqrt(m* k_n) d'); q = (E*, zeta)."""
    kn = 4.0 / 3.0 * q[0] * reff
    sq = math.sqrt(meff * kn)
    fn = kn * delta + 2.0 * q[1] * sq * ddelta
    if fn < 0.0:
        fn = 0.0
    return fn, kn
