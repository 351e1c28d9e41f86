"""Axis-aligned box of planar walls."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter, shown
from .base import Boundary

FACES = ("-x", "+x", "-y", "+y", "-z", "+z")


class Box(Boundary):
    """Six (or fewer) inward-facing planes bounding ``lower`` <= x <= ``upper``.

    ``open`` lists faces left out, e.g. ``open=("+z",)`` for a box without a lid.
    The planes are infinite: corners and edges act as the intersection of half-spaces.
    """

    name = "box"
    parameters = {
        "lower": Parameter(kind="vector", unit="m", doc="lower corner"),
        "upper": Parameter(kind="vector", unit="m", doc="upper corner"),
        "open": Parameter(default=(), kind="any", doc="faces left out, among " + " ".join(FACES)),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "Box()"
        self.lower = np.asarray(self.params["lower"], float)
        self.upper = np.asarray(self.params["upper"], float)
        if np.any(self.upper <= self.lower):
            raise ParameterError(f"{call}: upper={shown(self.upper)} must exceed "
                                 f"lower={shown(self.lower)} in every coordinate")
        open_faces = self.params["open"]
        if isinstance(open_faces, str):
            open_faces = (open_faces,)
        bad = [f for f in open_faces if f not in FACES]
        if bad:
            raise ParameterError(f"{call}: open={shown(tuple(open_faces))} has unknown faces "
                                 f"{shown(bad)}; allowed: {', '.join(FACES)}")
        self.faces = tuple(f for f in FACES if f not in open_faces)

    def planes(self):
        pts, nrm = [], []
        for f in self.faces:
            axis = "xyz".index(f[1])
            n = np.zeros(3)
            if f[0] == "-":
                n[axis] = 1.0
                p = self.lower.copy()
            else:
                n[axis] = -1.0
                p = self.upper.copy()
            pts.append(p)
            nrm.append(n)
        return np.array(pts), np.array(nrm)

    def surface(self, extent: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, faces) of the box's closed faces (for viewing: the planes are
        infinite, the box's faces are its rectangles)."""
        verts, faces = [], []
        lo, hi = self.lower, self.upper
        for f in self.faces:
            axis = "xyz".index(f[1])
            a, b = [d for d in range(3) if d != axis]
            value = lo[axis] if f[0] == "-" else hi[axis]
            k = len(verts)
            for sa, sb in ((lo[a], lo[b]), (hi[a], lo[b]), (hi[a], hi[b]), (lo[a], hi[b])):
                p = np.zeros(3)
                p[axis], p[a], p[b] = value, sa, sb
                verts.append(p)
            faces += [(k, k + 1, k + 2), (k, k + 2, k + 3)]
        return np.asarray(verts).reshape(-1, 3), np.asarray(faces, np.int64).reshape(-1, 3)
