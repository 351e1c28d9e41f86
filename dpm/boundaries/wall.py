"""Finite wall: a rectangular plate of given thickness."""

from __future__ import annotations

import itertools

import numpy as np

from ..kernels.boundary_geometry import SLAB
from ..parameters import Parameter, shown
from .base import Boundary, Primitives
from .frames import box_of_points, in_plane_axes, unit


class Wall(Boundary):
    """A rectangle centred at ``center`` with unit ``normal``, in-plane axis ``u`` and
    half extents ``half_extents`` = (a, b) along u and v = normal x u, as a plate of
    ``thickness`` (0: a sheet).

    Contact (kernel kind SLAB): the closest point of the box ``|s| <= a``, ``|t| <= b``,
    ``|w| <= thickness / 2``, so faces push along the normal from either side and edges and
    corners act as rounded edges (the force points from the closest edge point to the
    sphere centre). Volume 4 a b thickness; it carries no mass (boundaries move by
    prescribed motions).
    """

    name = "wall"
    parameters = {
        "center": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "normal": Parameter(default=(0.0, 0.0, 1.0), kind="vector"),
        "u": Parameter(default=None, kind="any", doc="in-plane axis of half extent a"),
        "half_extents": Parameter(kind="any", unit="m", doc="(a, b) > 0"),
        "thickness": Parameter(default=0.0, low=0.0, unit="m"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "Wall()"
        p = self.params
        self.center = np.asarray(p["center"], float)
        self.normal = unit(call, "normal", p["normal"])
        self.u, self.v = in_plane_axes(call, self.normal, p["u"])
        he = np.asarray(p["half_extents"], float).reshape(-1)
        if he.shape != (2,) or not np.all(he > 0):
            from ..errors import ParameterError

            raise ParameterError(f"{call}: half_extents={shown(p['half_extents'])} must be two "
                                 "positive lengths (a, b)")
        self.a, self.b = float(he[0]), float(he[1])
        self.h = 0.5 * float(p["thickness"])

    def corners(self) -> np.ndarray:
        return np.array([self.center + sa * self.a * self.u + sb * self.b * self.v
                         + sh * self.h * self.normal
                         for sa, sb, sh in itertools.product((-1, 1), repeat=3)])

    def volume(self) -> float:
        """Volume of the plate [m3]: 4 a b thickness."""
        return 4.0 * self.a * self.b * 2.0 * self.h

    def primitives(self) -> Primitives:
        row = [*self.center, *self.u, *self.v, self.a, self.b, self.h]
        return Primitives.build([(SLAB, row, box_of_points(self.corners(), 0.0))])
