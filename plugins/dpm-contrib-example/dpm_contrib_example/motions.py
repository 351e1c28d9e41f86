"""The ``orbit`` motion: circular translation (a gyratory shaker's table).

The boundary keeps its orientation and its points move on circles of radius a at angular
frequency omega = 2 pi f in the plane spanned by the unit vectors u and v = n x u (n the
plane's normal ``axis``, u the ``start`` direction projected into the plane):

    R(t) = 1,   o(t) = a ((cos(omega t) - 1) u + sin(omega t) v)      (o(0) = 0)
    do/dt = a omega (-sin(omega t) u + cos(omega t) v),   omega_vec = 0
"""

from __future__ import annotations

import math

import numpy as np

import dpm
from dpm.errors import ParameterError
from dpm.parameters import Parameter


class Orbit(dpm.Motion):
    """Circular translation of radius ``radius`` [m] at ``frequency`` [Hz] in the plane
    normal to ``axis``, starting towards ``start`` (projected into that plane)."""

    name = "orbit"
    parameters = {
        "radius": Parameter(low=0.0, low_open=True, unit="m", doc="orbit radius a"),
        "frequency": Parameter(low=0.0, low_open=True, unit="Hz"),
        "axis": Parameter(default=(0.0, 0.0, 1.0), kind="vector", doc="normal of the orbit"),
        "start": Parameter(default=(1.0, 0.0, 0.0), kind="vector",
                           doc="direction u of the first displacement"),
    }

    def __init__(self, **params) -> None:
        super().__init__(**params)
        n = np.asarray(self.params["axis"], float)
        if np.linalg.norm(n) == 0.0:
            raise ParameterError(f"Orbit(): axis={tuple(n)} must not be zero")
        n = n / np.linalg.norm(n)
        u = np.asarray(self.params["start"], float)
        u = u - (u @ n) * n
        if np.linalg.norm(u) < 1e-12:
            raise ParameterError(f"Orbit(): start={tuple(self.params['start'])} must not be "
                                 f"parallel to axis={tuple(self.params['axis'])}")
        self.u = u / np.linalg.norm(u)
        self.v = np.cross(n, self.u)
        self.omega = 2.0 * math.pi * float(self.params["frequency"])
        self.time_scale = 1.0 / float(self.params["frequency"])

    def origin(self, t: np.ndarray) -> np.ndarray:
        """o(t) (n, 3) in closed form."""
        a, w = float(self.params["radius"]), self.omega
        t = np.asarray(t, float)
        return a * ((np.cos(w * t) - 1.0)[:, None] * self.u + np.sin(w * t)[:, None] * self.v)

    def pose(self, t):
        t = np.asarray(t, float)
        return np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy(), self.origin(t)

    def rates(self, t):
        a, w = float(self.params["radius"]), self.omega
        t = np.asarray(t, float)
        v = a * w * (-np.sin(w * t)[:, None] * self.u + np.cos(w * t)[:, None] * self.v)
        return v, np.zeros((len(t), 3))
