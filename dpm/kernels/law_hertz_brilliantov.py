"""Hertz-Brilliantov: Hertz elasticity with viscoelastic (velocity-dependent) damping.

DPM thesis (Samiei 2012) §2.6.4, eq. 2.37; Brilliantov, Spahn, Hertzsch & Poschel 1996
(PRE 53, 5382) with their 3/2 A absorbed into A:
    F_n = max(0, 4/3 E* sqrt(R*) (delta^(3/2) + A delta^(1/2) delta'))
A [s] is a material constant; the restitution then falls with impact speed,
1 - e = 1.1534 A (k/m*)^(2/5) v^(1/5) + O(A^2),  k = 4/3 E* sqrt(R*)
(Ramirez, Poschel, Brilliantov & Schwager 1999; Schwager & Poschel 2008 for the cut-off).
Tangential: Mindlin no-slip spring k_t = 8 G* sqrt(R* delta) with history, optional dashpot
c_t = 2 zeta_t sqrt(m* k_t), Coulomb limit mu F_n (:mod:`.tangential`).

Slots: normal (E*, A); tangential :func:`.tangential.mindlin_tangential` (G*, mu, zeta_t).
Normal part (:class:`dpm.impact.parts.NormalPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``, q its slots of the pair
row, h the offset of its history in ``hist[k]``; k_n the stiffness a tangential part may
scale with.
"""

import math

from .config import inline_jit


@inline_jit
def brilliantov_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """F_n = max(0, 4/3 E* sqrt(R* d) (d + A d')); q = (E*, A); k_n = 2 E* sqrt(R* d)."""
    a = math.sqrt(reff * delta)
    fn = 4.0 / 3.0 * q[0] * a * (delta + q[1] * ddelta)
    if fn < 0.0:
        fn = 0.0
    return fn, 2.0 * q[0] * a
