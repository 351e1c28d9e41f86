"""JKR adhesion (Johnson, Kendall & Roberts 1971): an elastic adhesive contact that acts at a
separation, with hysteresis. The equations are in :mod:`dpm.kernels.law_jkr`."""

from __future__ import annotations

import math

from ..errors import ParameterError
from ..material import effective_shear, effective_young
from ..parameters import Parameter
from .base import COMMON, ImpactModel
from .collision import hertz_scales, tsuji_beta_for_restitution, tsuji_collision
from .hertz_mindlin import HertzNormalBase
from .parts import TangentialPart

WORK_OF_ADHESION = Parameter(low=0.0, low_open=True, unit="J/m2",
                             doc="work of adhesion W (2 gamma for two like surfaces)")


def _beta(model) -> float:
    e = float(model.params["restitution"])
    return 0.0 if e >= 1.0 else tsuji_beta_for_restitution(e)


def critical_overlap(work_of_adhesion: float, estar: float, reff: float) -> float:
    """d_c = -3/4 (pi^2 W^2 R* / E*^2)^(1/3) [m] (negative): where a JKR contact breaks
    under displacement control."""
    return -0.75 * (math.pi ** 2 * work_of_adhesion ** 2 * reff / estar ** 2) ** (1.0 / 3.0)


class JKRNormal(HertzNormalBase):
    """JKR elasticity with Tsuji's damping on the contact radius (EDEM's "Hertz-Mindlin
    with JKR"):

        d   = a^2/R* - sqrt(2 pi W a/E*)
        F_n = 4 E* a^3/(3 R*) - sqrt(8 pi W E* a^3) + 2 sqrt(5/6) beta sqrt(2 E* a m*) d'

    kept from d = 0 on approach until d < d_c on separation (the attached flag in the
    history); interaction range ``|d_c|`` at R* = r_max. Slots (E*, W, beta); k_n passed on:
    S_n = 2 E* a.
    """

    name = "jkr"
    slots = ("E*", "W", "beta")
    history = 1
    function = ("dpm.kernels.law_jkr", "jkr_normal")
    attached = ("dpm.kernels.law_jkr", "jkr_attached")
    universal = False
    parameters = {"restitution": COMMON["restitution"], "work_of_adhesion": WORK_OF_ADHESION}

    def values(self, model, a, b, context):
        return (effective_young(a, b), float(model.params["work_of_adhesion"]), _beta(model))

    def reach(self, model, a, b, rmax):
        return -critical_overlap(float(model.params["work_of_adhesion"]),
                                 effective_young(a, b), rmax)

    def contact_time(self, model, a, b, meff, reff, speed):
        # the Hertz collision's duration: the adhesive neck adds to the stiffness at small
        # overlaps but the Rayleigh and Hertz limits of the time-step check still apply
        _, tau = hertz_scales(meff, reff, effective_young(a, b), speed)
        return tau * tsuji_collision(_beta(model))[1]


class JKRTangential(TangentialPart):
    """Mindlin's spring on the JKR contact radius with Tsuji's dashpot and the Thornton &
    Yin (1991) limit: k_t = 8 G* a, c_t = 2 sqrt(5/6) beta sqrt(k_t m*),
    ``|F_t| <= mu (F_n + 2 F_c)``. Slots (G*, beta, mu, E*, W)."""

    name = "jkr_mindlin"
    slots = ("G*", "beta", "mu", "E*", "W")
    history = 3
    function = ("dpm.kernels.law_jkr", "jkr_tangential")
    universal = False
    needs_elastic_constants = True
    parameters = {"restitution": COMMON["restitution"], "friction": COMMON["friction"],
                  "work_of_adhesion": WORK_OF_ADHESION}

    def values(self, model, a, b, context):
        return (effective_shear(a, b), _beta(model), float(model.params["friction"]),
                effective_young(a, b), float(model.params["work_of_adhesion"]))


class JKR(ImpactModel):
    """JKR adhesive elastic contact with damping and friction (Johnson, Kendall & Roberts
    1971; Thornton & Yin 1991; EDEM "Hertz-Mindlin with JKR")::

        d   = a^2/R* - sqrt(2 pi W a/E*)                        (contact radius a)
        F_n = 4 E* a^3/(3 R*) - sqrt(8 pi W E* a^3) + 2 sqrt(5/6) beta sqrt(2 E* a m*) d'
        k_t = 8 G* a,  c_t = 2 sqrt(5/6) beta sqrt(k_t m*),  |F_t| <= mu (F_n + 2 F_c)

    A pair makes contact at d = 0 and keeps it at a separation until d < d_c =
    -3/4 (pi^2 W^2 R*/E*^2)^(1/3); under force control it separates at the pull-off force
    F_c = 3/2 pi W R*. ``work_of_adhesion`` W [J/m2] is 2 gamma for two like surfaces
    (gamma the surface energy; gamma_1 + gamma_2 - gamma_12 for two materials).
    ``restitution`` sets beta as in :class:`~dpm.impact.hertz_mindlin.HertzMindlin`
    (the restitution measured at a given speed is lower: the neck takes energy); 1 for an
    elastic contact. Rolling resistance is not offered (the rolling parts take the
    repulsive load; with adhesion that is not yet defined here). Requires young and
    poisson on both materials. Parts: :class:`JKRNormal` x :class:`JKRTangential`.

    The engine finds contacts as far as the scene's largest ``|d_c|`` beyond touching (the
    neighbour list, the boundary list and the MPI halo grow by it). The implicit
    integrators and the CUDA backend refuse it.
    """

    name = "jkr"
    kernel = ("dpm.impact.jkr", "jkr")
    normal = JKRNormal()
    tangential = JKRTangential()
    needs_elastic_constants = True
    parameters = {
        "restitution": Parameter(default=0.5, low=0.0, high=1.0, low_open=True,
                                 doc="normal coefficient of restitution of the damping "
                                     "(1: elastic)"),
        "friction": COMMON["friction"],
        "work_of_adhesion": WORK_OF_ADHESION,
        "rolling_friction": Parameter(default=0.0, low=0.0, high=0.0,
                                      doc="not offered with JKR (must be 0)"),
    }

    def __init__(self, call: str | None = None, **params) -> None:
        if float(params.get("rolling_friction", 0.0) or 0.0) > 0.0:
            raise ParameterError(f"{call or 'JKR()'}: rolling_friction="
                                 f"{params['rolling_friction']!r}; allowed: 0 (rolling "
                                 "resistance is not offered with JKR)")
        super().__init__(call, **params)
