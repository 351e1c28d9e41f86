"""Hertz-Brilliantov: Hertz elasticity with viscoelastic (velocity-dependent) damping.

DPM thesis (Samiei 2012) §2.6.4, eq. 2.37; Brilliantov, Spahn, Hertzsch & Poschel 1996
(PRE 53, 5382) with their 3/2 A absorbed into A:
    F_n = max(0, 4/3 E* sqrt(R*) (delta^(3/2) + A delta^(1/2) delta'))
A [s] is a material constant; the restitution then falls with impact speed,
1 - e = 1.1534 A (k/m*)^(2/5) v^(1/5) + O(A^2),  k = 4/3 E* sqrt(R*)
(Ramirez, Poschel, Brilliantov & Schwager 1999; Schwager & Poschel 2008 for the cut-off).
Tangential: Mindlin no-slip spring k_t = 8 G* sqrt(R* delta) with history, optional dashpot
c_t = 2 zeta_t sqrt(m* k_t), Coulomb limit mu F_n (:mod:`.tangential`).

pair_params row: [E*, G*, A, mu, zeta_t, (rolling), rolling model, mu_r]
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb


@inline_jit
def hertz_brilliantov(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    a = math.sqrt(reff * delta)
    fn = 4.0 / 3.0 * p[0] * a * (delta + p[2] * ddelta)
    if fn < 0.0:
        fn = 0.0
    kt = 8.0 * p[1] * a
    ct = 2.0 * p[4] * math.sqrt(kt * meff)
    ftx, fty, ftz = spring_coulomb(kt, ct, p[3], fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k)
    return fn, ftx, fty, ftz
