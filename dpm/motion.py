"""Prescribed motions of boundaries.

A motion is a rigid transform of time: a boundary point at ``x0`` (its place at t = 0)
is at ``x(t) = R(t) x0 + o(t)`` and moves with ``v = do/dt + omega x (x - o)``. A
:class:`Motion` subclass gives :meth:`Motion.pose` (R and o for an array of times,
vectorised with numpy) and, where it knows them in closed form, :meth:`Motion.rates`
(do/dt and omega); the default rates are central differences of the pose (error
O(h^2) with h = 1e-6 of the motion's time scale). Motions compose: ``a.then(b)`` (or
``Compose(a, b)``) applies ``a`` first and moves the result by ``b``.

The step kernels see only the frame rows (o, R, do/dt, omega) that :func:`frames`
computes for the times of the coming steps, so a plugin motion is plain numpy code.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from .errors import ParameterError
from .parameters import Parameter, declared_repr, shown, validate


def _rodrigues(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) by ``angle`` (n,) about the unit ``axis``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    s = np.sin(angle)[:, None, None]
    c = np.cos(angle)[:, None, None]
    return np.eye(3)[None] + s * k[None] + (1 - c) * (k @ k)[None]


def _unit(call: str, name: str, v: Sequence[float]) -> np.ndarray:
    a = np.asarray(v, float)
    n = float(np.linalg.norm(a))
    if n == 0.0:
        raise ParameterError(f"{call}: {name}={shown(v)} must not be zero")
    return a / n


class Motion:
    """A prescribed rigid motion; subclass and give :meth:`pose` (and :meth:`rates`)."""

    name: ClassVar[str] = ""
    parameters: ClassVar[dict[str, Parameter]] = {}
    #: point about which boundary torques are reported (None: the origin)
    pivot: np.ndarray | None = None
    #: time scale of the motion [s] (sets the finite-difference step of the default rates)
    time_scale: float = 1.0

    def __init_subclass__(cls, **kwargs: Any) -> None:
        # help(), inspect.signature and the docs list the declared parameters (with units
        # and ranges in the docstring) though __init__ takes them as **params
        super().__init_subclass__(**kwargs)
        from .boundaries.signature import document

        document(cls)

    def __init__(self, **params: Any) -> None:
        self.params = validate(f"{type(self).__name__}()", self.parameters, params)

    def __repr__(self) -> str:
        """``Rotation(axis=(0, 1, 0), rpm=30)``: the declared parameters given (required
        ones and those that differ from their default)."""
        return declared_repr(type(self).__name__, self.parameters,
                             getattr(self, "params", {}))

    def pose(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(R (n, 3, 3), o (n, 3)) at the times ``t`` (n,)."""
        raise NotImplementedError

    def rates(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(do/dt (n, 3), omega (n, 3)) at the times ``t``: central differences."""
        h = 1e-6 * self.time_scale
        rp, op = self.pose(t + h)
        rm, om = self.pose(t - h)
        r0, _ = self.pose(t)
        rdot = (rp - rm) / (2 * h)
        w = rdot @ np.transpose(r0, (0, 2, 1))  # skew(omega) = dR/dt R^T
        omega = 0.5 * np.stack([w[:, 2, 1] - w[:, 1, 2], w[:, 0, 2] - w[:, 2, 0],
                                w[:, 1, 0] - w[:, 0, 1]], axis=1)
        return (op - om) / (2 * h), omega

    def then(self, outer: Motion) -> Compose:
        """This motion, then moved by ``outer``."""
        return Compose(self, outer)


class Compose(Motion):
    """Motions applied one after the other: ``Compose(a, b)`` is a, then b on top.

    x = R_b (R_a x0 + o_a) + o_b;  omega = omega_b + R_b omega_a;
    do/dt = R_b do_a/dt + omega_b x (R_b o_a) + do_b/dt.
    """

    name = "compose"

    def __init__(self, *motions: Motion) -> None:
        if not motions or not all(isinstance(m, Motion) for m in motions):
            raise ParameterError(f"Compose(): motions={motions!r} must be dpm.Motion objects")
        self.motions = motions
        self.params = {}
        pivots = [m.pivot for m in motions if m.pivot is not None]
        self.pivot = pivots[0] if pivots else None
        self.time_scale = min(m.time_scale for m in motions)

    def __repr__(self) -> str:
        return f"Compose({', '.join(repr(m) for m in self.motions)})"

    def pose(self, t):
        r, o = self.motions[0].pose(t)
        for m in self.motions[1:]:
            rb, ob = m.pose(t)
            r = rb @ r
            o = np.einsum("nij,nj->ni", rb, o) + ob
        return r, o

    def rates(self, t):
        r, o = self.motions[0].pose(t)
        v, w = self.motions[0].rates(t)
        for m in self.motions[1:]:
            rb, ob = m.pose(t)
            vb, wb = m.rates(t)
            rbo = np.einsum("nij,nj->ni", rb, o)
            v = np.einsum("nij,nj->ni", rb, v) + np.cross(wb, rbo) + vb
            w = wb + np.einsum("nij,nj->ni", rb, w)
            r = rb @ r
            o = rbo + ob
        return v, w


class Translation(Motion):
    """Constant velocity: o = v t."""

    name = "translation"
    parameters = {"velocity": Parameter(kind="vector", unit="m/s")}

    def pose(self, t):
        v = np.asarray(self.params["velocity"], float)
        return np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy(), t[:, None] * v[None]

    def rates(self, t):
        v = np.asarray(self.params["velocity"], float)
        return np.tile(v, (len(t), 1)), np.zeros((len(t), 3))


class Rotation(Motion):
    """Rotation about ``axis`` through ``center`` at ``rpm`` (or ``omega`` [rad/s]),
    reached linearly over ``ramp`` seconds: omega(t) = omega min(t / ramp, 1).

    R = exp(phi(t) [axis]x), o = c - R c, phi = omega t^2 / (2 ramp) while t < ramp,
    omega (t - ramp / 2) after. Torques are reported about ``center``.
    """

    name = "rotation"
    parameters = {
        "axis": Parameter(default=(0.0, 0.0, 1.0), kind="vector"),
        "rpm": Parameter(default=None, unit="1/min"),
        "omega": Parameter(default=None, unit="rad/s"),
        "center": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "ramp": Parameter(default=0.0, low=0.0, unit="s"),
    }

    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        p = self.params
        if (p["rpm"] is None) == (p["omega"] is None):
            raise ParameterError(f"Rotation(): give exactly one of rpm or omega (got rpm="
                                 f"{p['rpm']}, omega={p['omega']})")
        self.omega = float(p["omega"]) if p["omega"] is not None else p["rpm"] * math.pi / 30
        self.axis = _unit("Rotation()", "axis", p["axis"])
        self.pivot = np.asarray(p["center"], float)
        self.ramp = float(p["ramp"])
        self.time_scale = 1.0 / max(abs(self.omega), 1e-12)

    def angle(self, t):
        t = np.maximum(t, 0.0)
        if self.ramp == 0.0:
            return self.omega * t
        return np.where(t < self.ramp, 0.5 * self.omega * t**2 / self.ramp,
                        self.omega * (t - 0.5 * self.ramp))

    def speed(self, t):
        if self.ramp == 0.0:
            return np.full(len(t), self.omega)
        return self.omega * np.clip(t / self.ramp, 0.0, 1.0)

    def pose(self, t):
        r = _rodrigues(self.axis, self.angle(t))
        return r, self.pivot[None] - np.einsum("nij,j->ni", r, self.pivot)

    def rates(self, t):
        w = self.speed(t)[:, None] * self.axis[None]
        r, o = self.pose(t)
        # the pivot stays put: do/dt + omega x (c - o) = 0
        return -np.cross(w, self.pivot[None] - o), w


class Oscillation(Motion):
    """Sinusoidal translation: o = A sin(2 pi f t + phase)."""

    name = "oscillation"
    parameters = {
        "amplitude": Parameter(kind="vector", unit="m"),
        "frequency": Parameter(low=0.0, low_open=True, unit="Hz"),
        "phase": Parameter(default=0.0, unit="rad"),
    }

    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        self.time_scale = 1.0 / self.params["frequency"]

    def pose(self, t):
        a = np.asarray(self.params["amplitude"], float)
        w = 2 * math.pi * self.params["frequency"]
        o = np.sin(w * t + self.params["phase"])[:, None] * a[None]
        return np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy(), o

    def rates(self, t):
        a = np.asarray(self.params["amplitude"], float)
        w = 2 * math.pi * self.params["frequency"]
        return (w * np.cos(w * t + self.params["phase"]))[:, None] * a[None], np.zeros(
            (len(t), 3))


def triangle_wave(t: np.ndarray, period: float) -> tuple[np.ndarray, np.ndarray]:
    """(value, slope) of the triangle wave rising from 0 to 1 in half a period and back."""
    x = np.mod(t / period, 1.0)
    up = x < 0.5
    return np.where(up, 2 * x, 2 - 2 * x), np.where(up, 2.0, -2.0) / period


class TriangularOscillation(Motion):
    """Back-and-forth translation at constant speed: o = A tri(t / T), tri rising from 0
    to 1 in T/2 and back (the triangular oscillation of Alkhaldi 2007, eq. 4.7, applied
    to a translation)."""

    name = "triangular_oscillation"
    parameters = {
        "amplitude": Parameter(kind="vector", unit="m"),
        "period": Parameter(low=0.0, low_open=True, unit="s"),
    }

    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        self.time_scale = self.params["period"]

    def pose(self, t):
        a = np.asarray(self.params["amplitude"], float)
        v, _ = triangle_wave(t, self.params["period"])
        return np.broadcast_to(np.eye(3), (len(t), 3, 3)).copy(), v[:, None] * a[None]

    def rates(self, t):
        a = np.asarray(self.params["amplitude"], float)
        _, s = triangle_wave(t, self.params["period"])
        return s[:, None] * a[None], np.zeros((len(t), 3))


class Tumbling(Motion):
    """Gyratory motion of a tumbling screening machine (Alkhaldi 2007, sec. 4.3.2).

    The main shaft turns at ``omega`` (or ``rpm``) about the vertical z axis; the barrel
    sits on a plate inclined by ``alpha`` and ``beta`` [rad], offset by the plate
    dimensions ``u``, ``e`` and the shaft ``eccentricity``. Its own rotation psi(t) is
    ``barrel="free"`` (psi = omega t, case 1, eq. 4.4), ``"fixed"`` (psi = 0, case 2, eq.
    4.5) or ``"oscillating"`` (case 3, eqs. 4.6-4.7: a triangular back-and-forth at
    omega_b = K omega, ``oscillation_factor`` K, over ``oscillation_period`` t_p).

    World from local: x_g = r_oc + A_lg^T x_l with r_oc of eq. 4.1 and
    A_lg = Rz(psi - omega t) M(omega t) (eq. 4.3 written as a product; M is eq. 4.4).
    Rates are central differences of that pose.
    """

    name = "tumbling"
    parameters = {
        "rpm": Parameter(default=None, unit="1/min"),
        "omega": Parameter(default=None, unit="rad/s"),
        "alpha": Parameter(default=0.0, unit="rad"),
        "beta": Parameter(default=0.0, unit="rad"),
        "u": Parameter(default=0.0, unit="m"),
        "e": Parameter(default=0.0, unit="m"),
        "eccentricity": Parameter(default=0.0, unit="m"),
        "barrel": Parameter(default="free", kind="str"),
        "oscillation_factor": Parameter(default=1.0, low=0.0),
        "oscillation_period": Parameter(default=1.0, low=0.0, low_open=True, unit="s"),
    }

    def __init__(self, **params: Any) -> None:
        super().__init__(**params)
        p = self.params
        if (p["rpm"] is None) == (p["omega"] is None):
            raise ParameterError("Tumbling(): give exactly one of rpm or omega")
        if p["barrel"] not in ("free", "fixed", "oscillating"):
            raise ParameterError(f"Tumbling(): barrel={p['barrel']!r}; allowed: free, fixed, "
                                 "oscillating")
        self.omega = float(p["omega"]) if p["omega"] is not None else p["rpm"] * math.pi / 30
        self.pivot = np.zeros(3)
        self.time_scale = 1.0 / max(abs(self.omega), 1e-12)

    def psi(self, t):
        p = self.params
        if p["barrel"] == "free":
            return self.omega * t
        if p["barrel"] == "fixed":
            return np.zeros_like(t)
        tp = p["oscillation_period"]
        wb = p["oscillation_factor"] * self.omega
        tri, _ = triangle_wave(t, tp)
        return 0.5 * wb * tp * tri  # psi_max = omega_b t_p / 2 (eq. 4.6) at t_p / 2

    def pose(self, t):
        p = self.params
        a, b, u, e, ecc = p["alpha"], p["beta"], p["u"], p["e"], p["eccentricity"]
        wt = self.omega * t
        c, s = np.cos(wt), np.sin(wt)
        ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
        m = np.empty((len(t), 3, 3))
        m[:, 0, 0] = c * cb - s * sa * sb
        m[:, 0, 1] = s * cb + c * sa * sb
        m[:, 0, 2] = -ca * sb
        m[:, 1, 0] = -s * ca
        m[:, 1, 1] = c * ca
        m[:, 1, 2] = np.full(len(t), sa)
        m[:, 2, 0] = c * sb + s * sa * cb
        m[:, 2, 1] = s * sb - c * sa * cb
        m[:, 2, 2] = np.full(len(t), ca * cb)
        g = self.psi(t) - wt
        cg, sg = np.cos(g), np.sin(g)
        rz = np.zeros((len(t), 3, 3))
        rz[:, 0, 0] = cg
        rz[:, 0, 1] = sg
        rz[:, 1, 0] = -sg
        rz[:, 1, 1] = cg
        rz[:, 2, 2] = 1.0
        a_lg = rz @ m
        o = np.stack([u * c - u * c * cb + e * s - ecc * s + u * s * sa * sb - e * s * ca,
                      u * s - u * s * cb - e * c + ecc * c - u * c * sa * sb + e * c * ca,
                      np.full(len(t), u * sb * ca + e * sa)], axis=1)
        return np.transpose(a_lg, (0, 2, 1)), o


def frames(motion: Motion | None, t: np.ndarray) -> np.ndarray:
    """Frame rows (len(t), 18): o, R (row-major), do/dt, omega (identity if no motion)."""
    t = np.asarray(t, float)
    out = np.zeros((len(t), 18))
    if motion is None:
        out[:, 3:12] = np.eye(3).ravel()
        return out
    r, o = motion.pose(t)
    v, w = motion.rates(t)
    out[:, 0:3] = o
    out[:, 3:12] = r.reshape(len(t), 9)
    out[:, 12:15] = v
    out[:, 15:18] = w
    return out
