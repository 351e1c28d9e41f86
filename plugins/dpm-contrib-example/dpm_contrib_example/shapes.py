"""The ``spherocylinder`` shape: a capsule as a row of equal sphere elements.

A cylinder of radius r and length l along the shape frame's x axis, closed by two
hemispheres (total length l + 2 r), centre of mass at the origin. Elements: n spheres of
radius r with centres evenly spaced on the axis segment [-l/2, l/2], n = ceil(l /
(spacing r)) + 1 (``spacing`` default 0.5: the union's surface lies within r (1 -
sqrt(1 - spacing^2 / 4)) = 0.032 r of the capsule's). Every element is inside the
capsule; the mass properties are those of the true solid, in closed form (cylinder m_c,
both hemispheres together a sphere's mass m_s):

    V   = pi r^2 l + 4/3 pi r^3
    I_x = rho (m_c r^2 / 2 + 2/5 m_s r^2)                         (axis)
    I_y = I_z = rho (m_c (r^2/4 + l^2/12) + m_s (2/5 r^2 + l^2/4 + 3/8 l r))

with m_c = pi r^2 l and m_s = 4/3 pi r^3 per unit density (a hemisphere's centre of
mass lies 3/8 r from its flat face).
"""

from __future__ import annotations

import math

import numpy as np

import dpm
from dpm.parameters import Parameter
from dpm.shapes import BodyBatch


def capsule_mass_properties(r: float, length: float) -> tuple[float, float, float]:
    """(volume, I_axis, I_transverse) per unit density of a capsule."""
    mc = math.pi * r * r * length
    ms = 4.0 / 3.0 * math.pi * r**3
    ix = mc * r * r / 2.0 + 0.4 * ms * r * r
    iy = mc * (r * r / 4.0 + length**2 / 12.0) + ms * (0.4 * r * r + length**2 / 4.0
                                                        + 0.375 * length * r)
    return mc + ms, ix, iy


class Spherocylinder(dpm.Shape):
    """Capsule of radius ``radius`` [m] and cylinder length ``length`` [m] along x, made of
    sphere elements spaced at most ``spacing`` x radius; mass properties of the capsule."""

    name = "spherocylinder"
    parameters = {
        "radius": Parameter(low=0.0, low_open=True, unit="m"),
        "length": Parameter(low=0.0, unit="m", doc="length of the cylindrical part"),
        "spacing": Parameter(default=0.5, low=0.0, high=1.0, low_open=True,
                             doc="largest element spacing as a fraction of the radius"),
    }

    def centres(self) -> np.ndarray:
        r, length = float(self.params["radius"]), float(self.params["length"])
        n = int(math.ceil(length / (float(self.params["spacing"]) * r))) + 1 if length else 1
        x = np.linspace(-length / 2, length / 2, n)
        return np.column_stack([x, np.zeros(n), np.zeros(n)])

    def inside(self, points: np.ndarray) -> np.ndarray:
        """Points inside the capsule (shape frame)."""
        r, h = float(self.params["radius"]), float(self.params["length"]) / 2
        p = np.asarray(points, float)
        x = np.clip(p[:, 0], -h, h)
        return (p[:, 0] - x) ** 2 + p[:, 1] ** 2 + p[:, 2] ** 2 <= r * r

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        r, h = float(self.params["radius"]), float(self.params["length"]) / 2
        return -np.array([h + r, r, r]), np.array([h + r, r, r])

    def build(self, count: int, density: float) -> BodyBatch:
        r, length = float(self.params["radius"]), float(self.params["length"])
        vol, ix, iy = capsule_mass_properties(r, length)
        c = self.centres()
        n = len(c)
        # principal moments as the shape's axes (x the axis; I_x < I_y unless very short)
        return BodyBatch(mass=np.full(count, density * vol),
                         inertia=np.tile(density * np.array([ix, iy, iy]), (count, 1)),
                         element_count=np.full(count, n, np.int64),
                         element_offset=np.tile(c, (count, 1)),
                         element_radius=np.full(n * count, r),
                         bounding_radius=np.full(count, length / 2 + r))
