"""Hertz-Mindlin with linear cohesion (cohesion energy density)."""

from __future__ import annotations

from ..parameters import Parameter
from .base import COMMON
from .hertz_mindlin import HertzMindlin
from .parts import AdhesionPart


class LinearCohesionAdhesion(AdhesionPart):
    """Cohesion proportional to the Hertz contact area (EDEM "Linear Cohesion"; LIGGGHTS
    ``cohesion sjkr``): F_a = k_c pi R* d, F_n = F_rep - F_a while the bodies overlap.
    Slots (k_c,); parameter ``cohesion_energy_density`` k_c [J/m3]."""

    name = "linear_cohesion"
    slots = ("k_c",)
    function = ("dpm.kernels.law_linear_cohesion", "linear_cohesion_adhesion")
    parameters = {"cohesion_energy_density": Parameter(low=0.0, unit="J/m3",
                                                       doc="cohesion energy density k_c")}

    def values(self, model, a, b, context):
        return (float(model.params["cohesion_energy_density"]),)


class LinearCohesion(HertzMindlin):
    """Hertz-Mindlin plus cohesion k_c times the contact area (cohesion energy density).

    EDEM "Linear Cohesion"; LIGGGHTS ``cohesion sjkr`` (a simplified JKR)::

        F_n = max(0, F_HM) - k_c pi R* d        (pi R* d: Hertz contact area pi a^2)

    F_HM is :class:`HertzMindlin`'s normal force (restitution sets its damping as there);
    k_c [J/m3] is the cohesion energy density. Unloaded, a pair rests at the overlap
    d_eq = (3 pi k_c / (4 E*))^2 R*, and a pair colliding slower than a critical speed
    stays stuck. The attraction acts only while the bodies overlap (the engine sees no
    contact at a separation), so it is a short-range cohesion; a JKR neck that survives
    past d = 0 would need detection at a distance.
    Tangential: Mindlin spring with Coulomb limit mu max(0, F_HM).
    Parts: :class:`~dpm.impact.hertz_mindlin.HertzTsujiNormal` x
    :class:`~dpm.impact.hertz_mindlin.MindlinTsujiTangential` x
    :class:`LinearCohesionAdhesion`.
    """

    name = "linear_cohesion"
    kernel = ("dpm.kernels.law_linear_cohesion", "linear_cohesion")
    adhesion = LinearCohesionAdhesion()
    parameters = {
        **COMMON,
        "cohesion_energy_density": Parameter(low=0.0, unit="J/m3",
                                             doc="cohesion energy density k_c"),
    }
