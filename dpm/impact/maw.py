"""Maw linear spring: linear spring-dashpot with a Hertz-equivalent stiffness."""

from __future__ import annotations

import math

from ..material import effective_young
from ..parameters import Parameter
from .base import COMMON, ImpactModel, hertz_beta, hertz_equivalent_stiffness
from .linear import _restitution_zeta, cutoff_contact_time, damping_ratio_for_restitution
from .parts import NormalPart, TangentialPart


def _speed(model, speed: float) -> float:
    v = model.params["impact_velocity"]
    return float(speed if v is None else v)


class MawNormal(NormalPart):
    """Linear spring-dashpot whose stiffness stores a Hertz contact's energy at speed v
    (DPM thesis §2.6.2, eq. 2.29; Maw, Barber & Fawcett 1976; Di Renzo & Di Maio 2004):

        k_n = 16/15 sqrt(R*) E* (15 m* v^2 / (16 sqrt(R*) E*))^(1/5) = C R*^(2/5) m*^(1/5)
        F_n = max(0, k_n d + c_n d'),  c_n = 2 zeta sqrt(m* k_n)

    with C = (16/15)^(4/5) E*^(4/5) v^(2/5), per contact. Slots (C, zeta); parameters
    ``impact_velocity`` (default: the scene's), ``restitution``.
    """

    name = "maw"
    slots = ("C", "zeta")
    function = ("dpm.kernels.law_maw", "maw_normal")
    needs_elastic_constants = True
    parameters = {
        "restitution": COMMON["restitution"],
        "impact_velocity": Parameter(default=None, low=0.0, low_open=True, unit="m/s",
                                     doc="characteristic impact speed v (default: the "
                                         "scene's)"),
    }

    def values(self, model, a, b, context):
        v = _speed(model, context.impact_speed)
        c = (16.0 / 15.0) ** 0.8 * effective_young(a, b) ** 0.8 * v**0.4
        return c, _restitution_zeta(model)

    def stiffness(self, model, a, b, context):
        return hertz_equivalent_stiffness(context.meff, context.reff, effective_young(a, b),
                                          _speed(model, context.impact_speed))

    def contact_time(self, model, a, b, meff, reff, speed):
        kn = hertz_equivalent_stiffness(meff, reff, effective_young(a, b), _speed(model, speed))
        return cutoff_contact_time(_restitution_zeta(model), math.sqrt(kn / meff))


class MawTangential(TangentialPart):
    """Tangential spring-dashpot of DPM thesis eqs. 2.33-2.34::

        F_t = -(k_t s + c_t v_t), |F_t| <= mu F_n,  k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_t)
        zeta_t = -ln e_t / sqrt(ln^2 e_t + pi^2)

    Slots (mu, kappa, zeta_t); ``tangential_restitution`` e_t defaults to the restitution.
    """

    name = "maw_spring_coulomb"
    slots = ("mu", "kappa", "zeta_t")
    history = 3
    function = ("dpm.kernels.tangential", "maw_tangential")
    parameters = {
        "friction": COMMON["friction"],
        "tangential_stiffness_ratio": Parameter(default=2.0 / 7.0, low=0.0, doc="k_t / k_n"),
        "tangential_restitution": Parameter(default=None, low=0.0, high=1.0, low_open=True,
                                            doc="e_t of the tangential dashpot (default: "
                                                "restitution)"),
    }

    def values(self, model, a, b, context):
        et = model.params["tangential_restitution"]
        return (float(model.params["friction"]),
                float(model.params["tangential_stiffness_ratio"]),
                hertz_beta(float(model.params["restitution"] if et is None else et)))


class MawLinearSpring(ImpactModel):
    """Linear spring-dashpot whose stiffness stores a Hertz contact's energy at speed v.

    DPM thesis Samiei 2012 §2.6.2, eqs. 2.29-2.35; Maw, Barber & Fawcett 1976; Di Renzo &
    Di Maio 2004.

    The normal spring stores at maximum compression the energy of a Hertz contact hit at the
    characteristic impact speed v, so it has the Hertz largest overlap at that speed::

        k_n = 16/15 sqrt(R*) E* (15 m* v^2 / (16 sqrt(R*) E*))^(1/5)
        F_n = max(0, k_n d + c_n d'),  c_n = 2 zeta sqrt(m* k_n)

    Tangential spring-dashpot with slip history and Coulomb limit::

        F_t = -(k_t s + c_t v_t) limited to mu F_n,   k_t = kappa k_n,
        c_t = 2 zeta_t sqrt(m* k_t),  zeta_t = -ln e_t / sqrt(ln^2 e_t + pi^2)  (eq. 2.34)

    v is ``impact_velocity`` or, if not given, the scene's characteristic impact speed
    (largest initial speed or free-fall speed over the scene's height). k_n is evaluated per
    contact with its own m* and R*. zeta is solved for the set restitution with the
    attractive force cut off (as the linear model); the elastic contact lasts pi sqrt(m*/k_n)
    and reaches d_max = v sqrt(m*/k_n) = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5) (Hertz's).
    Requires young and poisson on both materials.
    Parts: :class:`MawNormal` x :class:`MawTangential`.
    """

    name = "maw_linear_spring"
    kernel = ("dpm.kernels.law_maw", "maw_linear_spring")
    normal = MawNormal()
    tangential = MawTangential()
    needs_elastic_constants = True
    parameters = {
        **COMMON,
        "impact_velocity": Parameter(default=None, low=0.0, low_open=True, unit="m/s",
                                     doc="characteristic impact speed v (default: the "
                                         "scene's)"),
        "tangential_stiffness_ratio": Parameter(default=2.0 / 7.0, low=0.0, doc="k_t / k_n"),
        "tangential_restitution": Parameter(default=None, low=0.0, high=1.0, low_open=True,
                                            doc="e_t of the tangential dashpot (default: "
                                                "restitution)"),
    }

    @property
    def damping_ratio(self) -> float:
        return damping_ratio_for_restitution(float(self.params["restitution"]))

    def stiffness(self, a, b, meff: float, reff: float, speed: float) -> float:
        """k_n [N/m] of a contact with m* = meff, R* = reff (speed: the scene's)."""
        return hertz_equivalent_stiffness(meff, reff, effective_young(a, b), _speed(self, speed))
