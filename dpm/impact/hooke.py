"""Hooke's impact model: linear spring-dashpot with k_n = 4/3 E* R*."""

from __future__ import annotations

import math

from ..material import effective_young
from .base import COMMON
from .linear import (
    TANGENTIAL,
    LinearSpringDashpot,
    LinearTangential,
    _restitution_zeta,
    cutoff_contact_time,
)
from .parts import NormalPart


class HookeNormal(NormalPart):
    """Linear spring-dashpot with k_n = 4/3 E* R* (DPM thesis §2.6.3, eq. 2.36; ERRATA: R*,
    not sqrt(R*)), the contact's own R*:

        F_n = max(0, k_n d + c_n d'),  c_n = 2 zeta sqrt(m* k_n)

    zeta as :class:`~dpm.impact.linear.LinearNormal`. Slots (E*, zeta). Requires young and
    poisson.
    """

    name = "hooke"
    slots = ("E*", "zeta")
    function = ("dpm.kernels.law_hooke", "hooke_normal")
    parameters = {"restitution": COMMON["restitution"]}
    needs_elastic_constants = True

    def values(self, model, a, b, context):
        return effective_young(a, b), _restitution_zeta(model)

    def stiffness(self, model, a, b, context):
        return 4.0 / 3.0 * effective_young(a, b) * context.reff

    def contact_time(self, model, a, b, meff, reff, speed):
        kn = 4.0 / 3.0 * effective_young(a, b) * reff
        return cutoff_contact_time(_restitution_zeta(model), math.sqrt(kn / meff))


class Hooke(LinearSpringDashpot):
    """Linear spring-dashpot with k_n = 4/3 E* R* from the elastic constants (Hooke).

    DPM thesis Samiei 2012 §2.6.3, eq. 2.36 (ERRATA: R*, not sqrt(R*)). Tangential as
    :class:`LinearSpringDashpot`::

        Normal:      F_n = max(0, k_n d + c_n d'),  k_n = 4/3 E* R*,  c_n = 2 zeta sqrt(m* k_n)
        Tangential:  spring k_t = kappa k_n with history,
                     dashpot c_t = 2 zeta_t sqrt(m* k_n), Coulomb limit mu F_n
                     (kappa = 0: the thesis' viscous F_t = min(c_t |v_t|, mu F_n)).

    k_n uses each contact's own R*, so small pairs are softer. zeta is solved so that the
    restitution with the attractive force cut off is the one set (as the linear model);
    duration, largest overlap and restitution are those of the linear model with this k_n.
    Parameters: restitution, friction, rolling_*, tangential_stiffness_ratio kappa
    (default 2/7), tangential_damping_ratio zeta_t (default: the normal zeta).
    Requires young and poisson on both materials.
    Parts: :class:`HookeNormal` x :class:`~dpm.impact.linear.LinearTangential`.
    """

    name = "hooke"
    kernel = ("dpm.kernels.law_hooke", "hooke")
    normal = HookeNormal()
    tangential = LinearTangential()
    needs_elastic_constants = True
    parameters = {**COMMON, **TANGENTIAL}
