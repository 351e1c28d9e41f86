"""Base class of particle shapes."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..parameters import Parameter, validate


@dataclass
class BodyBatch:
    """Mass properties and sphere elements of ``n`` new bodies.

    mass (n,), inertia (n, 3) principal moments, quaternion of the principal frame is the
    body frame; element_count (n,) elements per body, element_offset (m, 3) body-frame
    offsets, element_radius (m,), bounding_radius (n,).
    """

    mass: np.ndarray
    inertia: np.ndarray
    element_count: np.ndarray
    element_offset: np.ndarray
    element_radius: np.ndarray
    bounding_radius: np.ndarray


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
        """Return the bodies' mass properties and elements for ``count`` bodies."""
        raise NotImplementedError
