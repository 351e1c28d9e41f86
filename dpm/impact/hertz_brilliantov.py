"""Hertz-Brilliantov: Hertz contact with viscoelastic damping."""

from __future__ import annotations

import math

from ..errors import ParameterError
from ..material import effective_shear, effective_young
from ..parameters import Parameter
from .base import COMMON, ImpactModel
from .collision import brilliantov_collision, brilliantov_gamma_for_restitution, hertz_scales
from .hertz_mindlin import HertzNormalBase
from .parts import TangentialPart


def _dissipation(model, a, b, meff: float, reff: float, speed: float) -> float:
    """A [s]: given, or solved from the restitution for m* = meff, R* = reff."""
    p = model.params
    if p["dissipation"] is not None:
        return float(p["dissipation"])
    if not (math.isfinite(meff) and math.isfinite(reff)):
        return 0.0
    v = float(p["reference_speed"] or speed)
    k = 4.0 / 3.0 * effective_young(a, b) * math.sqrt(reff)
    gamma = brilliantov_gamma_for_restitution(float(p["restitution"]))
    return gamma * (meff / k) ** 0.4 * v**-0.2


class BrilliantovNormal(HertzNormalBase):
    """Hertz elasticity with viscoelastic damping (Brilliantov, Spahn, Hertzsch & Poschel
    1996, PRE 53, 5382; DPM thesis §2.6.4, eq. 2.37):

        F_n = max(0, 4/3 E* sqrt(R*) (d^(3/2) + A d^(1/2) d'))

    A [s] given (``dissipation``) or solved from ``restitution`` at ``reference_speed`` for
    the smallest bodies of the pair (Ramirez et al. 1999; Schwager & Poschel 2008 for the
    cut-off). Slots (E*, A); k_n passed on: S_n = 2 E* sqrt(R* d).
    """

    name = "brilliantov"
    slots = ("E*", "A")
    function = ("dpm.kernels.law_hertz_brilliantov", "brilliantov_normal")
    parameters = {
        "dissipation": Parameter(default=None, low=0.0, unit="s",
                                 doc="viscoelastic constant A"),
        "restitution": Parameter(default=None, low=0.0, high=1.0, low_open=True,
                                 doc="restitution at reference_speed (instead of A)"),
        "reference_speed": Parameter(default=None, low=0.0, low_open=True, unit="m/s",
                                     doc="impact speed of the given restitution (default: "
                                         "the scene's)"),
    }

    def values(self, model, a, b, context):
        return effective_young(a, b), _dissipation(model, a, b, context.meff, context.reff,
                                                   context.impact_speed)

    def contact_time(self, model, a, b, meff, reff, speed):
        es = effective_young(a, b)
        A = _dissipation(model, a, b, meff, reff, speed)
        k = 4.0 / 3.0 * es * math.sqrt(reff)
        gamma = A * (k / meff) ** 0.4 * max(speed, 1e-12) ** 0.2
        return hertz_scales(meff, reff, es, speed)[1] * brilliantov_collision(gamma)[1]


class MindlinTangential(TangentialPart):
    """Mindlin's no-slip spring with a viscous dashpot and a Coulomb limit (Mindlin 1949)::

        k_t = 8 G* sqrt(R* d),  c_t = 2 zeta_t sqrt(m* k_t),  |F_t| <= mu F_n

    Slots (G*, mu, zeta_t); ``tangential_damping_ratio`` zeta_t (default 0).
    """

    name = "mindlin"
    slots = ("G*", "mu", "zeta_t")
    history = 3
    function = ("dpm.kernels.tangential", "mindlin_tangential")
    needs_elastic_constants = True
    parameters = {
        "friction": COMMON["friction"],
        "tangential_damping_ratio": Parameter(default=0.0, low=0.0,
                                              doc="zeta_t of the tangential dashpot"),
    }

    def values(self, model, a, b, context):
        return (effective_shear(a, b), float(model.params["friction"]),
                float(model.params["tangential_damping_ratio"]))


class HertzBrilliantov(ImpactModel):
    """Hertz contact with viscoelastic damping: restitution falls with impact speed.

    DPM thesis Samiei 2012 §2.6.4, eq. 2.37; Brilliantov, Spahn, Hertzsch & Poschel 1996,
    PRE 53, 5382.

        F_n = max(0, k (d^(3/2) + A d^(1/2) d')),   k = 4/3 E* sqrt(R*)

    A [s] is a material constant (Brilliantov's 3/2 A); the restitution falls with the impact
    speed: e = f(gamma), gamma = A (k/m*)^(2/5) v^(1/5), with
    1 - e = 1.1534 gamma - 0.7983 gamma^2 + ... for small gamma (Ramirez et al. 1999,
    PRE 60, 4465; the cut-off changes only higher orders, Schwager & Poschel 2008, PRE 78,
    051304); f is solved by ODE here (:mod:`dpm.impact.collision`).
    Elastic (A = 0): duration 2.868 (m*^2/(R* E*^2 v))^(1/5), d_max = (15 m* v^2/(16 E*
    sqrt(R*)))^(2/5).

    Give either ``dissipation`` = A, or ``restitution`` e at ``reference_speed`` (default:
    the scene's characteristic impact speed), from which A is solved for the smallest
    bodies of the pair; other speeds and sizes then follow the theory.
    Tangential: Mindlin spring k_t = 8 G* sqrt(R* d) with history, optional dashpot
    c_t = 2 zeta_t sqrt(m* k_t) (``tangential_damping_ratio``, default 0), Coulomb limit.
    Requires young and poisson on both materials.
    Parts: :class:`BrilliantovNormal` x :class:`MindlinTangential`.
    """

    name = "hertz_brilliantov"
    kernel = ("dpm.kernels.law_hertz_brilliantov", "hertz_brilliantov")
    normal = BrilliantovNormal()
    tangential = MindlinTangential()
    needs_elastic_constants = True
    parameters = {
        **{k: v for k, v in COMMON.items() if k != "restitution"},
        **BrilliantovNormal.parameters,  # dissipation, restitution, reference_speed
        "tangential_damping_ratio": Parameter(default=0.0, low=0.0,
                                              doc="zeta_t of the tangential dashpot"),
    }

    def __init__(self, call=None, **params):
        super().__init__(call, **params)
        p = self.params
        if (p["dissipation"] is None) == (p["restitution"] is None):
            raise ParameterError(f"{self.call}: give exactly one of dissipation (A [s], >= 0) "
                                 "or restitution (in (0, 1], at reference_speed)")
        if p["reference_speed"] is not None and p["restitution"] is None:
            raise ParameterError(f"{self.call}: reference_speed goes with restitution; "
                                 "allowed: dissipation alone")

    def dissipation(self, a, b, meff: float, reff: float, speed: float) -> float:
        """A [s]: given, or solved from the restitution for m* = meff, R* = reff."""
        return _dissipation(self, a, b, meff, reff, speed)
