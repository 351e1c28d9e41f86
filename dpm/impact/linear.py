"""Linear spring-dashpot impact model."""

from __future__ import annotations

import math
from functools import lru_cache

from .._lazy import lazy_module
from ..errors import ParameterError
from ..parameters import Parameter
from .base import COMMON, ImpactModel
from .parts import NormalPart, TangentialPart

optimize = lazy_module("scipy.optimize")


def cutoff_contact_time(zeta: float, omega0: float) -> float:
    """Duration of a linear spring-dashpot contact whose attractive force is cut off.

    The force k d + c d' reaches zero (and the particles separate) at::

      t_c = (pi - 2 atan(beta/omega)) / omega          zeta < 1, omega = omega0 sqrt(1-zeta^2)
      t_c = 2 / beta                                   zeta = 1
      t_c = 2 atanh(omega'/beta) / omega'              zeta > 1, omega' = omega0 sqrt(zeta^2-1)

    with beta = zeta omega0 (Schwager & Poschel 2007, PRE 75, 051304).
    """
    beta = zeta * omega0
    if zeta < 1.0:
        w = omega0 * math.sqrt(1.0 - zeta * zeta)
        return (math.pi - 2.0 * math.atan2(beta, w)) / w
    if zeta == 1.0:
        return 2.0 / beta
    w = omega0 * math.sqrt(zeta * zeta - 1.0)
    return 2.0 * math.atanh(w / beta) / w


def cutoff_restitution(zeta: float) -> float:
    """Restitution e = exp(-beta t_c) of the cut-off linear spring-dashpot (mass-independent)."""
    if zeta == 0.0:
        return 1.0
    return math.exp(-zeta * cutoff_contact_time(zeta, 1.0))


@lru_cache(maxsize=256)
def damping_ratio_for_restitution(restitution: float) -> float:
    """zeta such that :func:`cutoff_restitution` (zeta) = restitution (solved by brentq)."""
    if restitution >= 1.0:
        return 0.0
    target = math.log(restitution)
    hi = 1.0
    while math.log(cutoff_restitution(hi)) > target:
        hi *= 2.0
        if hi > 1e8:
            raise ParameterError(f"restitution={restitution:g} is too small to reach")
    return optimize.brentq(lambda z: math.log(cutoff_restitution(z)) - target, 0.0, hi, xtol=1e-15,
                  rtol=1e-14)


#: the tangential parameters of the linear-spring family
TANGENTIAL = {
    "tangential_stiffness_ratio": Parameter(default=2.0 / 7.0, low=0.0, doc="k_t / k_n"),
    "tangential_damping_ratio": Parameter(default=None, low=0.0,
                                          doc="zeta_t (default: normal zeta)"),
}


def _restitution_zeta(model) -> float:
    return damping_ratio_for_restitution(float(model.params["restitution"]))


class LinearNormal(NormalPart):
    """Linear spring-dashpot normal force (Cundall & Strack 1979; DPM thesis §2.6.1):

        F_n = max(0, k_n d + c_n d'),  c_n = 2 zeta sqrt(m* k_n)

    zeta solved so that the restitution with the attractive force cut off is the one set
    (Schwager & Poschel 2007, :func:`damping_ratio_for_restitution`). Slots (k_n, zeta);
    parameters ``stiffness`` [N/m], ``restitution``. Duration :func:`cutoff_contact_time`.
    """

    name = "linear"
    slots = ("k_n", "zeta")
    function = ("dpm.kernels.law_linear", "linear_normal")
    parameters = {
        "restitution": COMMON["restitution"],
        "stiffness": Parameter(low=0.0, low_open=True, unit="N/m", doc="normal stiffness k_n"),
    }

    def values(self, model, a, b, context):
        return float(model.params["stiffness"]), _restitution_zeta(model)

    def stiffness(self, model, a, b, context):
        return float(model.params["stiffness"])

    def contact_time(self, model, a, b, meff, reff, speed):
        return cutoff_contact_time(_restitution_zeta(model),
                                   math.sqrt(model.params["stiffness"] / meff))


class LinearTangential(TangentialPart):
    """Tangential spring-dashpot of the linear family (Cundall & Strack 1979)::

        F_t = -(k_t s + c_t v_t), |F_t| <= mu F_n,  k_t = kappa k_n,  c_t = 2 zeta_t sqrt(m* k_n)

    k_n is the normal part's stiffness; the spring s has history (projected on the tangent
    plane) and sliding shortens it, never lengthens it, so that it alone carries at most
    mu F_n (:func:`dpm.kernels.tangential.spring_coulomb_at`). Slots (mu, kappa, zeta_t);
    zeta_t defaults to the linear damping ratio of the restitution.
    ``tangential_stiffness_ratio=0`` gives the thesis' viscous ``F_t = min(c_t |v_t|, mu F_n)``
    (eq. 2.28).
    """

    name = "linear_spring_coulomb"
    slots = ("mu", "kappa", "zeta_t")
    history = 3
    function = ("dpm.kernels.tangential", "linear_tangential")
    parameters = {"friction": COMMON["friction"], **TANGENTIAL}

    def values(self, model, a, b, context):
        zt = model.params.get("tangential_damping_ratio")
        return (float(model.params["friction"]), float(model.params["tangential_stiffness_ratio"]),
                _restitution_zeta(model) if zt is None else float(zt))


class LinearSpringDashpot(ImpactModel):
    """Linear spring-dashpot (Cundall & Strack 1979; DPM thesis Samiei 2012, §2.6.1)::

        Normal:      F_n = max(0, k_n d + c_n d'),  c_n = 2 zeta sqrt(m* k_n)
        Tangential:  spring k_t = kappa k_n with history, dashpot c_t = 2 zeta_t sqrt(m* k_n),
                     Coulomb limit mu F_n.

    ``tangential_stiffness_ratio=0`` gives the thesis' purely viscous
    ``F_t = min(c_t |v_t|, mu F_n)`` (eq. 2.28).

    The damping ratio zeta is solved so that the restitution *with the attractive force cut
    off* is the one set (the thesis' eq. 2.21 ignores the cut-off and gives e = 0.55 for a
    set 0.5; see shared/seeds/ERRATA.md). Contact duration: :func:`cutoff_contact_time`.

    Parameters: stiffness k_n [N/m] (required), restitution, friction, rolling_friction,
    tangential_stiffness_ratio kappa (default 2/7), tangential_damping_ratio zeta_t
    (default: the normal zeta).
    Parts: :class:`LinearNormal` x :class:`LinearTangential`.
    """

    name = "linear_spring_dashpot"
    kernel = ("dpm.kernels.law_linear", "linear_spring_dashpot")
    normal = LinearNormal()
    tangential = LinearTangential()
    parameters = {
        **COMMON,
        "stiffness": Parameter(low=0.0, low_open=True, unit="N/m", doc="normal stiffness k_n"),
        **TANGENTIAL,
    }

    @property
    def damping_ratio(self) -> float:
        return damping_ratio_for_restitution(float(self.params["restitution"]))
