"""Base class of impact models."""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from ..kernels.config import N_PAIR_PARAMS
from ..material import Material
from ..parameters import Parameter, validate

COMMON = {
    "restitution": Parameter(default=0.5, low=0.0, high=1.0, low_open=True,
                             doc="normal coefficient of restitution"),
    "friction": Parameter(default=0.5, low=0.0, doc="Coulomb friction coefficient"),
    "rolling_friction": Parameter(default=0.0, low=0.0,
                                  doc="rolling friction coefficient mu_r (torque mu_r F_n R*)"),
}


class ImpactModel:
    """A contact force law for one material pair.

    Subclass it, declare ``parameters``, name the numba kernel in ``kernel`` as
    ``("package.module", "function")`` with the signature of
    :func:`dpm.kernels.law_linear.linear_spring_dashpot`, and fill the pair constants in
    :meth:`pair_row` (slot 7 is the rolling friction coefficient, read by the step).
    """

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = dict(COMMON)
    kernel: ClassVar[tuple[str, str]] = ("", "")
    needs_elastic_constants: ClassVar[bool] = False

    def __init__(self, call: str | None = None, **params: Any) -> None:
        self.call = call or f"{type(self).__name__}()"
        self.params = validate(self.call, self.parameters, params)

    def pair_row(self, a: Material, b: Material) -> np.ndarray:
        """Constants of the kernel for materials ``a`` and ``b`` (length N_PAIR_PARAMS)."""
        raise NotImplementedError

    def contact_time(self, a: Material, b: Material, meff: float, reff: float,
                     speed: float) -> float:
        """Duration [s] of a head-on collision at ``speed`` (for the time-step check)."""
        raise NotImplementedError

    def _row(self, *values: float) -> np.ndarray:
        row = np.zeros(N_PAIR_PARAMS)
        row[: len(values)] = values
        row[7] = self.params["rolling_friction"]
        return row


def hertz_contact_time(meff: float, reff: float, estar: float, speed: float) -> float:
    """Elastic Hertz contact duration t = 2.868 (m*^2 / (R* E*^2 v))^(1/5) (Johnson 1985)."""
    speed = max(speed, 1e-12)
    return 2.868265699194 * (meff**2 / (reff * estar**2 * speed)) ** 0.2


def hertz_beta(restitution: float) -> float:
    """beta = -ln e / sqrt(ln^2 e + pi^2) (0 for e = 1)."""
    le = math.log(restitution)
    return -le / math.sqrt(le * le + math.pi**2)
