"""Reciprocating translation with a pause at each end: the stroke of a moving grate bar.

The moving bars of forward and backward acting grates go back and forth at a constant
speed and stop for a short time at the end of each stroke before they turn (Samiei 2012,
DPM thesis, sec. 4.2 and sec. 4.7.3: "the moving bars do normally have a small pause at
the end of a single stroke and before changing direction"). :class:`Reciprocating` is that
motion in closed form; :class:`dpm.TriangularOscillation` is the same without the pauses.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import ParameterError
from .motion import Motion
from .parameters import Parameter


class Reciprocating(Motion):
    """Back-and-forth translation along ``stroke`` (a vector: direction and length A) at
    constant ``speed`` v, with a ``pause`` t_p at each end.

    With T_s = A / v the time of one stroke, the period is T = 2 T_s + 2 t_p. Over one
    period, tau = (t + ``phase``) mod T, the displacement along the unit stroke direction
    e = stroke / A is, with its rate::

        tau in [0, T_s):               s = v tau,                    ds/dt = v
        tau in [T_s, T_s + t_p):       s = A,                        ds/dt = 0
        tau in [T_s + t_p, 2 T_s + t_p): s = A - v (tau - T_s - t_p),  ds/dt = -v
        tau in [2 T_s + t_p, T):       s = 0,                        ds/dt = 0

    and the frame moves by o(t) = s e, do/dt = (ds/dt) e, R = I, omega = 0. ``phase`` [s]
    shifts the cycle (a bar started mid-stroke); at t + phase = 0 the bar is at its rest
    end, about to move along +stroke. ``pause`` = 0 gives a triangular oscillation of
    period 2 A / v. At the turning instants the velocity is that of the following
    interval (the function is right-continuous).
    """

    name = "reciprocating"
    parameters = {
        "stroke": Parameter(kind="vector", unit="m", doc="direction and length A of a stroke"),
        "speed": Parameter(low=0.0, low_open=True, unit="m/s", doc="constant bar speed v"),
        "pause": Parameter(default=0.0, low=0.0, unit="s", doc="rest at each end t_p"),
        "phase": Parameter(default=0.0, unit="s", doc="time shift of the cycle"),
    }

    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        p = self.params
        a = np.asarray(p["stroke"], float).reshape(3)
        length = float(np.linalg.norm(a))
        if not length > 0.0:
            raise ParameterError(f"Reciprocating(): stroke={tuple(a)} must not be zero "
                                 "(its length is the stroke A)")
        self.direction = a / length
        self.length = length
        self.speed = float(p["speed"])
        self.pause = float(p["pause"])
        self.phase = float(p["phase"])
        self.stroke_time = length / self.speed
        self.period = 2.0 * self.stroke_time + 2.0 * self.pause
        self.time_scale = min(self.stroke_time, self.pause) if self.pause > 0 else \
            self.stroke_time

    def displacement(self, t: Any) -> tuple[np.ndarray, np.ndarray]:
        """(s, ds/dt) along the stroke direction at the times ``t`` (the table above)."""
        ts, tp, v, a = self.stroke_time, self.pause, self.speed, self.length
        tau = np.mod(np.asarray(t, float) + self.phase, self.period)
        s = np.where(tau < ts, v * tau,
                     np.where(tau < ts + tp, a,
                              np.where(tau < 2 * ts + tp, a - v * (tau - ts - tp), 0.0)))
        rate = np.where(tau < ts, v,
                        np.where(tau < ts + tp, 0.0, np.where(tau < 2 * ts + tp, -v, 0.0)))
        return np.clip(s, 0.0, a), rate

    def pose(self, t):
        s, _ = self.displacement(t)
        return (np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy(),
                s[:, None] * self.direction[None])

    def rates(self, t):
        _, rate = self.displacement(t)
        return rate[:, None] * self.direction[None], np.zeros((len(t), 3))
