"""Base class of particle shapes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..parameters import Parameter, validate


@dataclass
class BodyBatch:
    """Mass properties and sphere elements of ``n`` new bodies.

    mass (n,); inertia (n, 3) principal moments; element_count (n,) elements per body;
    element_offset (m, 3) element centres in the principal (body) frame, centre of mass at
    the origin; element_radius (m,); bounding_radius (n,); principal_rotation (n, 4) unit
    quaternions (w, x, y, z) rotating the principal frame into the shape's documented
    frame (offset_shape = R(q) offset_principal; identity when they coincide). A body's
    orientation is that of its principal frame: q_body = q_user (x) principal_rotation.
    """

    mass: np.ndarray
    inertia: np.ndarray
    element_count: np.ndarray
    element_offset: np.ndarray
    element_radius: np.ndarray
    bounding_radius: np.ndarray
    principal_rotation: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.principal_rotation is None:
            n = len(self.mass)
            self.principal_rotation = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))


class Shape:
    """A particle shape: subclass, declare ``parameters`` and implement :meth:`build`.

    Parameters are keyword arguments validated at construction; ``sim.add_particles(name,
    **params)`` builds the shape registered under ``name``.
    """

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = {}

    def __init__(self, call: str | None = None, **params: Any) -> None:
        self.params = validate(call or f"{type(self).__name__}()", self.parameters, params)

    def build(self, count: int, density: float) -> BodyBatch:
        """Return the bodies' mass properties and elements for ``count`` bodies, in fresh
        arrays: the simulation may keep them without a copy."""
        raise NotImplementedError
