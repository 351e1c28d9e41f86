"""Base class of boundaries."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ..material import Material
from ..parameters import Parameter, validate


class Boundary:
    """A boundary: subclass, declare ``parameters``, and give its contact geometry.

    The kernels of this version handle one-sided infinite planes; a boundary made of
    planes returns them from :meth:`planes`. ``force`` and ``torque`` hold the total
    contact force [N] and torque about the origin [N m] that particles exert on it in the
    last step.
    """

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = {}

    def __init__(self, material: Material, call: str | None = None, **params: Any) -> None:
        call = call or f"{type(self).__name__}()"
        if not isinstance(material, Material):
            from ..errors import ParameterError

            raise ParameterError(f"{call}: material={material!r} must be a dpm.Material")
        self.material = material
        self.params = validate(call, self.parameters, params)
        self.force = np.zeros(3)
        self.torque = np.zeros(3)

    def planes(self) -> tuple[np.ndarray, np.ndarray]:
        """(points (k, 3), unit normals (k, 3)) of the planes, normals into the domain."""
        return np.zeros((0, 3)), np.zeros((0, 3))

    def outside(self, position: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """Mask of particles whose centre lies on the wrong side of this boundary."""
        pts, nrm = self.planes()
        if len(pts) == 0:
            return np.zeros(len(position), bool)
        d = np.einsum("nkj,kj->nk", position[:, None, :] - pts[None], nrm)
        return np.any(d < 0.0, axis=1)
