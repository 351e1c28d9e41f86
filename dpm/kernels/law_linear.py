"""Linear spring-dashpot contact law (Cundall & Strack 1979; DPM thesis, Samiei 2012 §2.6.1).

Normal:      F_n = max(0, k_n delta + c_n delta'),   c_n = 2 zeta sqrt(m* k_n)
Tangential:  spring-dashpot with history and Coulomb limit
             (:func:`.tangential.spring_coulomb`: sliding shortens the spring to
             carry at most mu F_n alone, never lengthens it; spring plus dashpot are
             limited to mu F_n), k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_n)

The damping ratio zeta is solved in the object layer so that the restitution coefficient
*with the attractive force cut off* equals the one the user set (Schwager & Poschel 2007:
e = exp(-beta t_c), t_c = (pi - 2 atan(beta/omega)) / omega, beta = zeta omega_0,
omega = omega_0 sqrt(1 - zeta^2)).

Slots: normal (k_n, zeta); tangential :func:`.tangential.linear_tangential`.
Normal part (:class:`dpm.impact.parts.NormalPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``, q its slots of the pair
row, h the offset of its history in ``hist[k]``; k_n the stiffness a tangential part may
scale with.
"""

import math

from .config import inline_jit


@inline_jit
def linear_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """F_n = max(0, k_n d + 2 zeta sqrt(m* k_n) d'); q = (k_n, zeta); returns (F_n, k_n)."""
    kn = q[0]
    cn = 2.0 * q[1] * math.sqrt(meff * kn)
    fn = kn * delta + cn * ddelta
    if fn < 0.0:
        fn = 0.0
    return fn, kn
