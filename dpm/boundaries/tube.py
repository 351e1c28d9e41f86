"""Tube: a conical frustum wall (a cylinder when both radii agree), with optional caps."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..kernels.boundary_geometry import AXI
from ..parameters import Parameter
from .base import Boundary, Primitives
from .frames import unit

CAPS = ("none", "start", "end", "both")


class Tube(Boundary):
    """A frustum wall from ``start`` along ``axis`` over ``length``, radius ``radius`` (or
    ``radius_start`` at the start and ``radius_end`` at the end) to the middle of a wall of
    ``thickness``; ``caps`` closes the start, the end or both with discs.

    Contact (kernel kind AXI, a surface of revolution of a meridian segment): in the plane
    (rho, z) through the axis and the sphere centre, the distance to the segment from
    (r_start, 0) to (r_end, length) minus thickness / 2. Spheres touch it from inside and
    from outside; the rims are rounded. A cap is the segment from (0, z) to (r, z). An open
    end that meets another tube's or bend's open end (same centre, opposite direction, same
    radius, same motion) is joined: no rim there, so a ball crosses the joint as inside one
    pipe.
    """

    name = "tube"
    joinable_ends = True
    parameters = {
        "start": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "axis": Parameter(default=(0.0, 0.0, 1.0), kind="vector"),
        "length": Parameter(low=0.0, low_open=True, unit="m"),
        "radius": Parameter(default=None, low=0.0, low_open=True, unit="m"),
        "radius_start": Parameter(default=None, low=0.0, unit="m"),
        "radius_end": Parameter(default=None, low=0.0, unit="m"),
        "thickness": Parameter(default=0.0, low=0.0, unit="m"),
        "caps": Parameter(default="none", kind="str", doc="none, start, end or both"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "Tube()"
        p = self.params
        self.start = np.asarray(p["start"], float)
        self.axis = unit(call, "axis", p["axis"])
        self.length = float(p["length"])
        r, r0, r1 = p["radius"], p["radius_start"], p["radius_end"]
        if r is not None and (r0 is not None or r1 is not None):
            raise ParameterError(f"{call}: give radius, or radius_start and radius_end, not "
                                 "both")
        if r is None and (r0 is None or r1 is None):
            raise ParameterError(f"{call}: give radius, or both radius_start and radius_end")
        self.r0 = float(r if r is not None else r0)
        self.r1 = float(r if r is not None else r1)
        if self.r0 == 0.0 and self.r1 == 0.0:
            raise ParameterError(f"{call}: radius_start and radius_end are both 0")
        if p["caps"] not in CAPS:
            raise ParameterError(f"{call}: caps={p['caps']!r}; allowed: {', '.join(CAPS)}")
        self.caps = p["caps"]
        self.h = 0.5 * float(p["thickness"])
        #: ends ("start", "end") joined to another pipe piece (set by the simulation when
        #: an end meets another piece's end of the same radius; see pipe_ends)
        self.joined: set[str] = set()

    def pipe_ends(self) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
        """(name, centre, outward axis, radius) of the open ends."""
        ends = []
        if self.caps not in ("start", "both"):
            ends.append(("start", self.start, -self.axis, self.r0))
        if self.caps not in ("end", "both"):
            ends.append(("end", self.end, self.axis, self.r1))
        return ends

    @property
    def end(self) -> np.ndarray:
        """Centre of the end face (start + length axis)."""
        return self.start + self.length * self.axis

    def inside(self, position: np.ndarray) -> np.ndarray:
        """Mask of points strictly inside the frustum (between the ends)."""
        d = np.asarray(position, float) - self.start
        z = d @ self.axis
        rho = np.linalg.norm(d - z[:, None] * self.axis, axis=1)
        r = self.r0 + (self.r1 - self.r0) * z / self.length
        return (z > 0) & (z < self.length) & (rho < r)

    def volume(self) -> float:
        """Volume of the wall [m3]: the frustum's lateral area pi (r0 + r1) s (s the slant
        length) times the thickness, plus pi r^2 thickness per cap (thin-wall formula)."""
        s = math.hypot(self.length, self.r1 - self.r0)
        v = math.pi * (self.r0 + self.r1) * s * 2.0 * self.h
        if self.caps in ("start", "both"):
            v += math.pi * self.r0**2 * 2.0 * self.h
        if self.caps in ("end", "both"):
            v += math.pi * self.r1**2 * 2.0 * self.h
        return v

    def primitives(self) -> Primitives:
        o, a, h, L = self.start, self.axis, self.h, self.length
        rmax = max(self.r0, self.r1) + h
        lo = np.minimum(o, self.end) - rmax
        hi = np.maximum(o, self.end) + rmax
        flags = (1 if "start" in self.joined else 0) | (2 if "end" in self.joined else 0)
        rows = [(AXI, [*o, *a, self.r0, 0.0, self.r1, L, h, flags], (lo, hi))]
        if self.caps in ("start", "both"):
            rows.append((AXI, [*o, *a, 0.0, 0.0, self.r0, 0.0, h], (lo, hi)))
        if self.caps in ("end", "both"):
            rows.append((AXI, [*o, *a, 0.0, L, self.r1, L, h], (lo, hi)))
        prims = Primitives.build(rows)
        prims.extent = float(np.linalg.norm(o)) + math.hypot(L, rmax)
        return prims
