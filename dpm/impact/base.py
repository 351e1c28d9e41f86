"""Base class of impact models."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..errors import ParameterError
from ..kernels.config import N_HISTORY, N_PAIR_PARAMS
from ..material import Material
from ..parameters import Parameter, validate

#: rolling resistance models -> id in pair_params slot 6 (see dpm.kernels.rolling)
ROLLING_MODELS = {"constant_torque": 1, "epsd": 2}
#: rolling models that read a normal stiffness from slot 5 and eta_r from slot 6
_ROLLING_WITH_SPRING = {"epsd"}

COMMON = {
    "restitution": Parameter(default=0.5, low=0.0, high=1.0, low_open=True,
                             doc="normal coefficient of restitution"),
    "friction": Parameter(default=0.5, low=0.0, doc="Coulomb friction coefficient"),
    "rolling_friction": Parameter(default=0.0, low=0.0,
                                  doc="rolling friction coefficient mu_r (torque mu_r F_n R*)"),
    "rolling_model": Parameter(default="constant_torque", kind="str",
                               doc="rolling resistance model: " + ", ".join(ROLLING_MODELS)),
    "rolling_damping": Parameter(default=0.3, low=0.0, high=1.0, high_open=True,
                                 doc="rolling_model='epsd': viscous damping ratio eta_r of the "
                                     "rolling spring (Ai et al. 2011 advise 0.3)"),
}


@dataclass(frozen=True)
class PairContext:
    """What the scene tells a model about a material pair when the tables are packed.

    impact_speed: characteristic impact speed [m/s] (largest initial speed or free-fall
    speed over the scene's height); meff, reff: effective mass [kg] and radius [m] of the
    smallest bodies of the pair (a wall counts as infinite).
    """

    impact_speed: float = 1.0
    meff: float = 1.0
    reff: float = 1.0


class ImpactModel:
    """A contact force law for one material pair.

    Subclass it, declare ``parameters``, name the numba kernel in ``kernel`` as
    ``("package.module", "function")`` with the signature of
    :func:`dpm.kernels.law_linear.linear_spring_dashpot`, and fill the pair constants in
    :meth:`pair_row` with :meth:`_row` (slots 6 and 7 carry the rolling resistance model
    and coefficient, read by the step; slots 0..5 are the law's own, except that the
    ``epsd`` rolling model takes slot 5 for the normal stiffness its spring scales with:
    a law that offers it fills at most slots 0..4 and passes ``stiffness=`` to ``_row``).
    """

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = dict(COMMON)
    kernel: ClassVar[tuple[str, str]] = ("", "")
    needs_elastic_constants: ClassVar[bool] = False
    #: history floats per contact the kernel reads and writes, ``hist[k, 0:history_slots]``
    #: (0-2: the tangential spring by convention; 6-7 free for the normal law). Slots 3-5
    #: belong to the rolling spring and are added when a pair has rolling resistance. Each
    #: scene allocates the widest its laws declare: a narrow history row is less memory
    #: and less traffic per contact. The default, N_HISTORY, suits any law.
    history_slots: ClassVar[int] = N_HISTORY

    def __init__(self, call: str | None = None, **params: Any) -> None:
        self.call = call or f"{type(self).__name__}()"
        self.params = validate(self.call, self.parameters, params)
        rm = self.params.get("rolling_model", "constant_torque")
        if rm not in ROLLING_MODELS:
            raise ParameterError(f"{self.call}: rolling_model={rm!r}; allowed: "
                                 f"{', '.join(ROLLING_MODELS)}")

    def pair_row(self, a: Material, b: Material, context: PairContext) -> np.ndarray:
        """Constants of the kernel for materials ``a`` and ``b`` (length N_PAIR_PARAMS)."""
        raise NotImplementedError

    def contact_time(self, a: Material, b: Material, meff: float, reff: float,
                     speed: float) -> float:
        """Duration [s] of a head-on collision at ``speed`` (for the time-step check)."""
        raise NotImplementedError

    def _row(self, *values: float, stiffness: float | None = None) -> np.ndarray:
        """Pack the law's constants; add the rolling model's (slots 6, 7 and for ``epsd`` 5).

        ``stiffness``: a representative normal stiffness k_n [N/m] of the pair, which the
        ``epsd`` rolling spring scales with (k_r = 2.25 mu_r^2 R*^2 k_n).
        """
        row = np.zeros(N_PAIR_PARAMS)
        row[: len(values)] = values
        mu_r = float(self.params.get("rolling_friction", 0.0))
        if mu_r > 0.0:
            rm = self.params.get("rolling_model", "constant_torque")
            row[6] = ROLLING_MODELS[rm]
            row[7] = mu_r
            if rm in _ROLLING_WITH_SPRING:
                if len(values) > 5 or stiffness is None:
                    raise ParameterError(f"{self.call}: rolling_model={rm!r} is not offered by "
                                         f"{type(self).__name__}; allowed: constant_torque")
                row[5] = stiffness if math.isfinite(stiffness) else 0.0
                row[6] += float(self.params.get("rolling_damping", 0.3))
        return row


def hertz_contact_time(meff: float, reff: float, estar: float, speed: float) -> float:
    """Elastic Hertz contact duration t = 2.868 (m*^2 / (R* E*^2 v))^(1/5) (Johnson 1985)."""
    speed = max(speed, 1e-12)
    return 2.868265699194 * (meff**2 / (reff * estar**2 * speed)) ** 0.2


def hertz_equivalent_stiffness(meff: float, reff: float, estar: float, speed: float) -> float:
    """Maw's linear stiffness that stores the strain energy of a Hertz contact at ``speed``:
    k = 16/15 sqrt(R*) E* (15 m* v^2 / (16 sqrt(R*) E*))^(1/5) (DPM thesis eq. 2.29)."""
    speed = max(speed, 1e-12)
    h = 16.0 / 15.0 * math.sqrt(reff) * estar
    return h * (meff * speed * speed / h) ** 0.2


def hertz_beta(restitution: float) -> float:
    """beta = -ln e / sqrt(ln^2 e + pi^2) (0 for e = 1)."""
    le = math.log(restitution)
    return -le / math.sqrt(le * le + math.pi**2)
