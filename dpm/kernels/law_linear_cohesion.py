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
from .law_hertz_mindlin import hertz_mindlin


@inline_jit
def linear_cohesion(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``:
    the Hertz-Mindlin force (friction limited by its repulsive part) minus the cohesion
    p[4] pi R* delta."""
    frep, ftx, fty, ftz = hertz_mindlin(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff,
                                        reff, dt, hist, k)
    return frep - p[4] * math.pi * reff * delta, ftx, fty, ftz
