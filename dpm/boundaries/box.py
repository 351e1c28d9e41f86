"""Axis-aligned box of planar walls."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter
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
            raise ParameterError(f"{call}: upper={tuple(self.upper)} must exceed "
                                 f"lower={tuple(self.lower)} in every coordinate")
        open_faces = self.params["open"]
        if isinstance(open_faces, str):
            open_faces = (open_faces,)
        bad = [f for f in open_faces if f not in FACES]
        if bad:
            raise ParameterError(f"{call}: open={tuple(open_faces)} has unknown faces {bad}; "
                                 f"allowed: {', '.join(FACES)}")
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
