"""Maw linear spring: linear spring-dashpot with a Hertz-equivalent stiffness."""

from __future__ import annotations

import math

from ..material import effective_young
from ..parameters import Parameter
from .base import COMMON, ImpactModel, hertz_beta, hertz_equivalent_stiffness
from .linear import cutoff_contact_time, damping_ratio_for_restitution


class MawLinearSpring(ImpactModel):
    """Linear spring-dashpot whose stiffness stores a Hertz contact's energy at speed v.

    DPM thesis Samiei 2012 §2.6.2, eqs. 2.29-2.35; Maw, Barber & Fawcett 1976; Di Renzo &
    Di Maio 2004.

    The normal spring stores at maximum compression the energy of a Hertz contact hit at the
    characteristic impact speed v, so it has the Hertz largest overlap at that speed:
        k_n = 16/15 sqrt(R*) E* (15 m* v^2 / (16 sqrt(R*) E*))^(1/5)
        F_n = max(0, k_n d + c_n d'),  c_n = 2 zeta sqrt(m* k_n)
    Tangential spring-dashpot with slip history and Coulomb limit:
        F_t = -(k_t s + c_t v_t) limited to mu F_n,   k_t = kappa k_n,
        c_t = 2 zeta_t sqrt(m* k_t),  zeta_t = -ln e_t / sqrt(ln^2 e_t + pi^2)  (eq. 2.34)

    v is ``impact_velocity`` or, if not given, the scene's characteristic impact speed
    (largest initial speed or free-fall speed over the scene's height). k_n is evaluated per
    contact with its own m* and R*. zeta is solved for the set restitution with the
    attractive force cut off (as the linear model); the elastic contact lasts pi sqrt(m*/k_n)
    and reaches d_max = v sqrt(m*/k_n) = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5) (Hertz's).
    Requires young and poisson on both materials.
    """

    name = "maw_linear_spring"
    kernel = ("dpm.kernels.law_maw", "maw_linear_spring")
    history_slots = 3  # the tangential spring
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

    def _speed(self, speed: float) -> float:
        v = self.params["impact_velocity"]
        return float(speed if v is None else v)

    def pair_row(self, a, b, context):
        es = effective_young(a, b)
        v = self._speed(context.impact_speed)
        c = (16.0 / 15.0) ** 0.8 * es**0.8 * v**0.4
        et = self.params["tangential_restitution"]
        zeta_t = hertz_beta(float(self.params["restitution"] if et is None else et))
        return self._row(c, self.damping_ratio, self.params["friction"],
                         self.params["tangential_stiffness_ratio"], zeta_t,
                         stiffness=hertz_equivalent_stiffness(context.meff, context.reff, es, v))

    def stiffness(self, a, b, meff: float, reff: float, speed: float) -> float:
        """k_n [N/m] of a contact with m* = meff, R* = reff (speed: the scene's)."""
        return hertz_equivalent_stiffness(meff, reff, effective_young(a, b), self._speed(speed))

    def contact_time(self, a, b, meff, reff, speed):
        kn = self.stiffness(a, b, meff, reff, speed)
        return cutoff_contact_time(self.damping_ratio, math.sqrt(kn / meff))
