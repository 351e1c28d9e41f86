"""Hooke's impact model: linear spring-dashpot with k_n = 4/3 E* R*."""

from __future__ import annotations

import math

from ..material import effective_young
from .base import COMMON
from .linear import TANGENTIAL, LinearSpringDashpot, cutoff_contact_time


class Hooke(LinearSpringDashpot):
    """Linear spring-dashpot with k_n = 4/3 E* R* from the elastic constants (Hooke).

    DPM thesis Samiei 2012 §2.6.3, eq. 2.36 (ERRATA: R*, not sqrt(R*)).

    Normal:      F_n = max(0, k_n d + c_n d'),  k_n = 4/3 E* R*,  c_n = 2 zeta sqrt(m* k_n)
    Tangential:  as :class:`LinearSpringDashpot`: spring k_t = kappa k_n with history,
                 dashpot c_t = 2 zeta_t sqrt(m* k_n), Coulomb limit mu F_n
                 (kappa = 0: the thesis' viscous F_t = min(c_t |v_t|, mu F_n)).

    k_n uses each contact's own R*, so small pairs are softer. zeta is solved so that the
    restitution with the attractive force cut off is the one set (as the linear model);
    duration, largest overlap and restitution are those of the linear model with this k_n.
    Parameters: restitution, friction, rolling_*, tangential_stiffness_ratio kappa
    (default 2/7), tangential_damping_ratio zeta_t (default: the normal zeta).
    Requires young and poisson on both materials.
    """

    name = "hooke"
    kernel = ("dpm.kernels.law_hooke", "hooke")
    needs_elastic_constants = True
    parameters = {**COMMON, **TANGENTIAL}

    def pair_row(self, a, b, context):
        es = effective_young(a, b)
        return self.linear_row(4.0 / 3.0 * es * context.reff, es)

    def contact_time(self, a, b, meff, reff, speed):
        kn = 4.0 / 3.0 * effective_young(a, b) * reff
        return cutoff_contact_time(self.damping_ratio, math.sqrt(kn / meff))
