"""Hertz-Mindlin with linear cohesion (cohesion energy density; EDEM "Linear Cohesion",
LIGGGHTS ``cohesion sjkr``).

    F_n = max(0, F_HM) - k_c A,    A = pi a^2 = pi R* delta  (Hertz contact area)
F_HM is the Hertz-Mindlin normal force of :mod:`.law_hertz_mindlin` (Tsuji damping with
the constant beta); k_c [J/m3 = N/m2] is the cohesion energy density. The cohesive part
attracts while the bodies overlap (F_n may be negative) and stops when they separate.
Free equilibrium overlap: 4/3 E* sqrt(R*) delta^(3/2) = k_c pi R* delta, i.e.
    delta_eq = (3 pi k_c / (4 E*))^2 R*
Tangential: Mindlin spring with history, Coulomb limit mu max(0, F_HM) (the repulsive part).

pair_params row: [E*, G*, beta, mu, k_c, (rolling), rolling model, mu_r]
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb

SQRT_5_6 = math.sqrt(5.0 / 6.0)


@inline_jit
def linear_cohesion(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    a = math.sqrt(reff * delta)
    kn = 4.0 / 3.0 * p[0] * a
    cn = 2.0 * SQRT_5_6 * p[2] * math.sqrt(2.0 * p[0] * a * meff)
    frep = kn * delta + cn * ddelta
    if frep < 0.0:
        frep = 0.0
    kt = 8.0 * p[1] * a
    ct = 2.0 * SQRT_5_6 * p[2] * math.sqrt(kt * meff)
    ftx, fty, ftz = spring_coulomb(kt, ct, p[3], frep, vtx, vty, vtz, nx, ny, nz, dt, hist, k)
    return frep - p[4] * math.pi * reff * delta, ftx, fty, ftz
