"""The ``kelvin_voigt`` impact model: a linear spring-dashpot whose force is not cut off.

    F_n = k_n d + c_n d',   c_n = 2 zeta sqrt(m* k_n)          (Kelvin-Voigt)
    F_t = -min(c_t |v_t|, mu max(F_n, 0)) v_t/|v_t|,  c_t = 2 zeta_t sqrt(m* k_n)

The contact lasts while the overlap is positive (dpm evaluates a law only then), half a
period of the damped oscillator, t_c = pi / omega_d with omega_0 = sqrt(k_n / m*),
omega_d = omega_0 sqrt(1 - zeta^2); near its end the dashpot pulls (F_n < 0): the
classical spring-dashpot of Cundall & Strack (1979). The restitution is then
e = exp(-pi zeta / sqrt(1 - zeta^2)), so zeta = -ln e / sqrt(pi^2 + ln^2 e) (Schafer,
Dippel & Wolf 1996, J. Phys. I France 6, 5, eq. 14; compare dpm's
``linear_spring_dashpot``, which cuts the attraction off and solves zeta for that).
"""

from __future__ import annotations

import math

import dpm
from dpm.impact.parts import NormalPart, TangentialPart
from dpm.parameters import Parameter


def damping_ratio(restitution: float) -> float:
    """zeta of the uncut linear spring-dashpot for restitution e in (0, 1]."""
    if restitution >= 1.0:
        return 0.0
    ln = math.log(restitution)
    return -ln / math.sqrt(math.pi**2 + ln * ln)


class KelvinVoigtNormal(NormalPart):
    """F_n = k_n d + 2 zeta sqrt(m* k_n) d' (not cut off); slots (k_n, zeta)."""

    name = "kelvin_voigt"
    slots = ("k_n", "zeta")
    function = ("dpm_contrib_example.kernels", "kelvin_voigt_normal")
    parameters = {
        "stiffness": Parameter(low=0.0, low_open=True, unit="N/m", doc="normal stiffness k_n"),
        "restitution": Parameter(default=0.5, low=0.0, high=1.0, low_open=True,
                                 doc="normal coefficient of restitution"),
    }

    def values(self, model, a, b, context):
        return (float(model.params["stiffness"]),
                damping_ratio(float(model.params["restitution"])))

    def stiffness(self, model, a, b, context):
        return float(model.params["stiffness"])

    def contact_time(self, model, a, b, meff, reff, speed):
        zeta = damping_ratio(float(model.params["restitution"]))
        w0 = math.sqrt(float(model.params["stiffness"]) / meff)
        return math.pi / (w0 * math.sqrt(1.0 - zeta * zeta))


class ViscousCoulombTangential(TangentialPart):
    """F_t = -min(2 zeta_t sqrt(m* k_n) |v_t|, mu max(F_n, 0)) v_t/|v_t|; slots
    (zeta_t, mu); no history."""

    name = "viscous_coulomb"
    slots = ("zeta_t", "mu")
    function = ("dpm_contrib_example.kernels", "viscous_coulomb_tangential")
    parameters = {
        "friction": Parameter(default=0.5, low=0.0, doc="Coulomb friction coefficient"),
        "tangential_damping_ratio": Parameter(default=1.0, low=0.0,
                                              doc="zeta_t of the viscous tangential force"),
    }

    def values(self, model, a, b, context):
        return (float(model.params["tangential_damping_ratio"]),
                float(model.params["friction"]))


class KelvinVoigt(dpm.ImpactModel):
    """Linear spring-dashpot, not cut off (Cundall & Strack 1979), with a viscous Coulomb
    tangential force.

    Parameters: stiffness k_n [N/m] (required), restitution e (zeta = -ln e / sqrt(pi^2 +
    ln^2 e), Schafer et al. 1996), friction mu, tangential_damping_ratio zeta_t (default
    1), rolling_friction, rolling_model. Parts: :class:`KelvinVoigtNormal` x
    :class:`ViscousCoulombTangential`.
    """

    name = "kelvin_voigt"
    normal = KelvinVoigtNormal()
    tangential = ViscousCoulombTangential()
