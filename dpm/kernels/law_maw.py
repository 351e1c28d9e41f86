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

Slots: normal (C, zeta); tangential :func:`.tangential.maw_tangential`.
Normal part (:class:`dpm.impact.parts.NormalPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``, q its slots of the pair
row, h the offset of its history in ``hist[k]``; k_n the stiffness a tangential part may
scale with.
"""

import math

from .config import inline_jit


@inline_jit
def maw_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """k_n = C R*^(2/5) m*^(1/5), F_n = max(0, k_n d + 2 zeta sqrt(m* k_n) d');
    q = (C, zeta)."""
    kn = q[0] * reff**0.4 * meff**0.2
    fn = kn * delta + 2.0 * q[1] * math.sqrt(meff * kn) * ddelta
    if fn < 0.0:
        fn = 0.0
    return fn, kn
