"""The sphere: one element at the body's centre."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter
from .base import BodyBatch, Shape


class Sphere(Shape):
    """Solid sphere of radius ``radius`` [m] (scalar, or one per particle).

    m = 4/3 pi r^3 rho,  I = 2/5 m r^2 about every axis.
    """

    name = "sphere"
    parameters = {
        "radius": Parameter(low=0.0, low_open=True, unit="m", doc="sphere radius", array=True),
    }

    def build(self, count: int, density: float) -> BodyBatch:
        r = np.asarray(self.params["radius"], dtype=float)
        if r.ndim == 1 and r.size != count:
            raise ParameterError(f"sphere: radius has {r.size} values for {count} particles")
        r = np.broadcast_to(r, (count,)).astype(float)
        mass = 4.0 / 3.0 * np.pi * r**3 * density
        inertia = np.repeat((0.4 * mass * r**2)[:, None], 3, axis=1)
        return BodyBatch(mass=mass, inertia=inertia, element_count=np.ones(count, np.int64),
                         element_offset=np.zeros((count, 3)), element_radius=r.copy(),
                         bounding_radius=r.copy())
