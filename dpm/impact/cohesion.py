"""Hertz-Mindlin with linear cohesion (cohesion energy density)."""

from __future__ import annotations

from ..material import effective_shear, effective_young
from ..parameters import Parameter
from .base import COMMON, hertz_equivalent_stiffness
from .hertz_mindlin import HertzMindlin


class LinearCohesion(HertzMindlin):
    """Hertz-Mindlin plus cohesion k_c times the contact area (cohesion energy density).

    EDEM "Linear Cohesion"; LIGGGHTS ``cohesion sjkr`` (a simplified JKR).

        F_n = max(0, F_HM) - k_c pi R* d        (pi R* d: Hertz contact area pi a^2)

    F_HM is :class:`HertzMindlin`'s normal force (restitution sets its damping as there);
    k_c [J/m3] is the cohesion energy density. Unloaded, a pair rests at the overlap
        d_eq = (3 pi k_c / (4 E*))^2 R*,
    and a pair colliding slower than a critical speed stays stuck. The attraction acts only
    while the bodies overlap (the engine sees no contact at a separation), so it is a short-
    range cohesion; a JKR neck that survives past d = 0 would need detection at a distance.
    Tangential: Mindlin spring with Coulomb limit mu max(0, F_HM).
    """

    name = "linear_cohesion"
    kernel = ("dpm.kernels.law_linear_cohesion", "linear_cohesion")
    parameters = {
        **COMMON,
        "cohesion_energy_density": Parameter(low=0.0, unit="J/m3",
                                             doc="cohesion energy density k_c"),
    }

    def pair_row(self, a, b, context):
        es = effective_young(a, b)
        return self._row(es, effective_shear(a, b), self.beta, self.params["friction"],
                         self.params["cohesion_energy_density"],
                         stiffness=hertz_equivalent_stiffness(context.meff, context.reff, es,
                                                              context.impact_speed))
