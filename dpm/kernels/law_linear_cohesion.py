"""Hertz-Mindlin with linear cohesion (cohesion energy density; EDEM "Linear Cohesion",
LIGGGHTS ``cohesion sjkr``).

    F_n = max(0, F_HM) - k_c A,    A = pi a^2 = pi R* delta  (Hertz contact area)
F_HM is the Hertz-Mindlin normal force of :mod:`.law_hertz_mindlin` (Tsuji damping with
the constant beta); k_c [J/m3 = N/m2] is the cohesion energy density. The cohesive part
attracts while the bodies overlap (F_n may be negative) and stops when they separate.
Free equilibrium overlap: 4/3 E* sqrt(R*) delta^(3/2) = k_c pi R* delta, i.e.
    delta_eq = (3 pi k_c / (4 E*))^2 R*
Tangential: Mindlin spring with history, Coulomb limit mu max(0, F_HM) (the repulsive part).

Adhesion part (:class:`dpm.impact.parts.AdhesionPart`):
``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> F_a``, subtracted from F_n after the
tangential part saw the repulsive force. Slots: (k_c,).
"""

import math

from .config import inline_jit


@inline_jit
def linear_cohesion_adhesion(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """F_a = k_c pi R* d (the attraction; F_n = F_rep - F_a); q = (k_c,)."""
    return q[0] * math.pi * reff * delta
