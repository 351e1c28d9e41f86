"""Walton-Braun hysteretic impact model."""

from __future__ import annotations

import math

from ..parameters import Parameter
from .base import COMMON, ImpactModel
from .linear import LinearTangential
from .parts import NormalPart


def _unloading(model) -> float:
    return float(model.params["stiffness"]) / float(model.params["restitution"]) ** 2


class WaltonBraunNormal(NormalPart):
    """Hysteretic spring (Walton & Braun 1986, J. Rheol. 30, 949; DPM thesis §2.6.6):

        loading (d >= d_max so far):  F_n = k_l d
        otherwise:                    F_n = max(0, k_ul (d - d_0)),  d_0 = d_max (1 - k_l/k_ul)

    k_ul = k_l / e^2, so e = sqrt(k_l/k_ul) at every speed. Slots (k_l, k_ul); history
    (d_max, d_0); k_n passed on: k_l. Duration pi/2 (sqrt(m*/k_l) + sqrt(m*/k_ul)).
    """

    name = "walton_braun"
    slots = ("k_l", "k_ul")
    history = 2
    function = ("dpm.kernels.law_walton_braun", "walton_braun_normal")
    parameters = {
        "restitution": COMMON["restitution"],
        "stiffness": Parameter(low=0.0, low_open=True, unit="N/m", doc="loading stiffness k_l"),
    }

    def values(self, model, a, b, context):
        return float(model.params["stiffness"]), _unloading(model)

    def stiffness(self, model, a, b, context):
        return float(model.params["stiffness"])

    def contact_time(self, model, a, b, meff, reff, speed):
        kl = float(model.params["stiffness"])
        return 0.5 * math.pi * (math.sqrt(meff / kl) + math.sqrt(meff / _unloading(model)))


class WaltonBraun(ImpactModel):
    """Hysteretic spring: plastic loading k_l, elastic unloading k_ul, e = sqrt(k_l/k_ul).

    Walton & Braun 1986, J. Rheol. 30, 949; DPM thesis §2.6.6.

        loading (d >= largest overlap so far):  F_n = k_l d
        unloading / reloading:                  F_n = max(0, k_ul (d - d_0))
        d_0 = d_max (1 - k_l/k_ul)   plastic overlap,   k_ul = k_l / e^2

    No dashpot: the hysteresis dissipates, e = sqrt(k_l/k_ul) at every speed. Head-on:
    d_max = v0 sqrt(m*/k_l), duration pi/2 (sqrt(m*/k_l) + sqrt(m*/k_ul)).
    Tangential as the linear spring-dashpot: k_t = kappa k_l with history, dashpot
    c_t = 2 zeta_t sqrt(m* k_l), Coulomb limit mu F_n.
    Parameters: stiffness k_l [N/m] (required), restitution (sets k_ul), friction,
    rolling_*, tangential_stiffness_ratio kappa (default 2/7), tangential_damping_ratio
    zeta_t (default: the damping ratio a linear dashpot would need for this restitution).
    Parts: :class:`WaltonBraunNormal` (history d_max, d_0) x
    :class:`~dpm.impact.linear.LinearTangential`.
    """

    name = "walton_braun"
    kernel = ("dpm.kernels.law_walton_braun", "walton_braun")
    normal = WaltonBraunNormal()
    tangential = LinearTangential()
    parameters = {
        **COMMON,
        "stiffness": Parameter(low=0.0, low_open=True, unit="N/m",
                               doc="loading stiffness k_l"),
        "tangential_stiffness_ratio": Parameter(default=2.0 / 7.0, low=0.0,
                                                doc="k_t / k_l"),
        "tangential_damping_ratio": Parameter(default=None, low=0.0,
                                              doc="zeta_t (default: from restitution)"),
    }
