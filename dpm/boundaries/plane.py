"""Infinite plane."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter, shown
from .base import Boundary


class Plane(Boundary):
    """Infinite one-sided plane through ``point`` with unit ``normal`` pointing into the domain.

    Contact: overlap delta = r - (x - p).n for a sphere of radius r at x, if 0 < delta.
    """

    name = "plane"
    parameters = {
        "point": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "normal": Parameter(default=(0.0, 0.0, 1.0), kind="vector"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        n = np.asarray(self.params["normal"], float)
        norm = np.linalg.norm(n)
        if norm == 0.0:
            raise ParameterError(f"{call or 'Plane()'}: normal={shown(self.params['normal'])} "
                                 "must not be zero")
        self.point = np.asarray(self.params["point"], float)
        self.normal = n / norm

    def planes(self):
        return self.point[None].copy(), self.normal[None].copy()
