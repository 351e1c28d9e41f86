"""Bend: a torus segment, the curved piece of a pipe run."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..kernels.boundary_geometry import TORUS
from ..parameters import Parameter, shown
from .base import Boundary, Primitives
from .frames import unit


class Bend(Boundary):
    """A pipe of radius ``pipe_radius`` bent on a circle of radius ``bend_radius`` about
    ``center`` over ``angle`` [rad], in the plane normal to ``axis``, starting in the
    direction ``start_direction`` (e1) from the centre; the pipe runs from
    center + R e1 towards e2 = axis x e1. The wall has ``thickness``.

    Contact (kernel kind TORUS): the pipe-centre circle point at the sphere's angle
    (clamped to the segment), and in that cross-section plane the distance to the pipe
    circle minus thickness / 2; inside and outside both touch, the end rings are rounded.
    A :class:`~dpm.boundaries.tube.Tube` ending at center + R e1 with axis e2 joins it
    smoothly (see :meth:`start_point`, :meth:`end_point`, :meth:`end_direction`): ends that
    meet are joined (no rounded rim there, see :class:`~dpm.boundaries.tube.Tube`).
    """

    name = "bend"
    joinable_ends = True
    parameters = {
        "center": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "axis": Parameter(default=(0.0, 0.0, 1.0), kind="vector"),
        "start_direction": Parameter(default=(1.0, 0.0, 0.0), kind="vector"),
        "bend_radius": Parameter(low=0.0, low_open=True, unit="m"),
        "pipe_radius": Parameter(low=0.0, low_open=True, unit="m"),
        "angle": Parameter(low=0.0, high=2 * math.pi, low_open=True, unit="rad"),
        "thickness": Parameter(default=0.0, low=0.0, unit="m"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "Bend()"
        p = self.params
        self.center = np.asarray(p["center"], float)
        self.axis = unit(call, "axis", p["axis"])
        e1 = np.asarray(p["start_direction"], float)
        e1 = e1 - (e1 @ self.axis) * self.axis
        if np.linalg.norm(e1) < 1e-12:
            raise ParameterError(f"{call}: start_direction={shown(p['start_direction'])} "
                                 "must not be parallel to axis")
        self.e1 = e1 / np.linalg.norm(e1)
        self.e2 = np.cross(self.axis, self.e1)
        self.R = float(p["bend_radius"])
        self.rp = float(p["pipe_radius"])
        if self.rp >= self.R:
            raise ParameterError(f"{call}: pipe_radius={self.rp:g} must be smaller than "
                                 f"bend_radius={self.R:g}")
        self.angle = float(p["angle"])
        self.h = 0.5 * float(p["thickness"])
        #: ends ("start", "end") joined to another pipe piece (see Tube.pipe_ends)
        self.joined: set[str] = set()

    def pipe_ends(self) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
        """(name, centre, outward pipe direction, pipe radius) of both ends."""
        return [("start", self.start_point(), -self.direction(0.0), self.rp),
                ("end", self.end_point(), self.end_direction(), self.rp)]

    def point(self, phi: float) -> np.ndarray:
        return self.center + self.R * (math.cos(phi) * self.e1 + math.sin(phi) * self.e2)

    def direction(self, phi: float) -> np.ndarray:
        return -math.sin(phi) * self.e1 + math.cos(phi) * self.e2

    def start_point(self) -> np.ndarray:
        return self.point(0.0)

    def end_point(self) -> np.ndarray:
        return self.point(self.angle)

    def end_direction(self) -> np.ndarray:
        return self.direction(self.angle)

    def volume(self) -> float:
        """Volume of the pipe wall [m3] (Pappus): 2 pi rp thickness x R angle, thin wall."""
        return 2.0 * math.pi * self.rp * 2.0 * self.h * self.R * self.angle

    def primitives(self) -> Primitives:
        pad = self.R + self.rp + self.h
        lo, hi = self.center - pad, self.center + pad
        flags = (1 if "start" in self.joined else 0) | (2 if "end" in self.joined else 0)
        row = [*self.center, *self.axis, *self.e1, self.R, self.rp, self.angle, self.h, flags]
        prims = Primitives.build([(TORUS, row, (lo, hi))])
        prims.extent = float(np.linalg.norm(self.center)) + pad
        return prims
