"""Regions of space for inlets and outlets."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .errors import ParameterError
from .parameters import Parameter, validate


class Region:
    """A region: subclass and give :meth:`contains` and :meth:`sample`."""

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Mask of the points inside."""
        raise NotImplementedError

    def sample(self, rng: np.random.Generator, n: int, margin: np.ndarray) -> np.ndarray:
        """``n`` uniform random points whose ball of radius ``margin`` lies inside."""
        raise NotImplementedError

    @property
    def volume(self) -> float:
        raise NotImplementedError

    def holds(self, radius: float) -> bool:
        """Whether a ball of ``radius`` fits inside (True where a subclass cannot tell)."""
        return True


class BoxRegion(Region):
    """Axis-aligned box ``lower`` <= x <= ``upper``."""

    parameters = {"lower": Parameter(kind="vector", unit="m"),
                  "upper": Parameter(kind="vector", unit="m")}

    def __init__(self, lower: Sequence[float], upper: Sequence[float]) -> None:
        validate("BoxRegion()", self.parameters, {"lower": lower, "upper": upper})
        self.lower = np.asarray(lower, float).reshape(3)
        self.upper = np.asarray(upper, float).reshape(3)
        if np.any(self.upper <= self.lower):
            raise ParameterError(f"BoxRegion(): upper={tuple(self.upper)} must exceed "
                                 f"lower={tuple(self.lower)} in every coordinate")

    def contains(self, points):
        p = np.asarray(points, float)
        return np.all((p >= self.lower) & (p <= self.upper), axis=1)

    def sample(self, rng, n, margin):
        m = np.asarray(margin, float).reshape(-1, 1)
        lo = self.lower + m
        hi = self.upper - m
        return lo + rng.random((n, 3)) * np.maximum(hi - lo, 0.0)

    @property
    def volume(self):
        return float(np.prod(self.upper - self.lower))

    def holds(self, radius):
        return bool(np.all(self.upper - self.lower >= 2.0 * radius))

    def __repr__(self) -> str:
        return (f"BoxRegion(lower={tuple(float(x) for x in self.lower)}, "
                f"upper={tuple(float(x) for x in self.upper)})")


class CylinderRegion(Region):
    """Cylinder from ``start`` along ``axis`` over ``length`` with ``radius``."""

    parameters = {"start": Parameter(kind="vector", unit="m"),
                  "axis": Parameter(kind="vector"),
                  "length": Parameter(low=0.0, low_open=True, unit="m"),
                  "radius": Parameter(low=0.0, low_open=True, unit="m")}

    def __init__(self, start: Sequence[float], axis: Sequence[float], length: float,
                 radius: float) -> None:
        validate("CylinderRegion()", self.parameters,
                 {"start": start, "axis": axis, "length": length, "radius": radius})
        self.start = np.asarray(start, float).reshape(3)
        a = np.asarray(axis, float).reshape(3)
        if np.linalg.norm(a) == 0 or length <= 0 or radius <= 0:
            raise ParameterError(f"CylinderRegion(): axis={tuple(a)}, length={length}, "
                                 f"radius={radius}: need a non-zero axis and positive sizes")
        self.axis = a / np.linalg.norm(a)
        self.length = float(length)
        self.radius = float(radius)
        helper = np.array([1.0, 0, 0]) if abs(self.axis[0]) < 0.9 else np.array([0, 1.0, 0])
        self.e1 = np.cross(self.axis, helper)
        self.e1 /= np.linalg.norm(self.e1)
        self.e2 = np.cross(self.axis, self.e1)

    def contains(self, points):
        d = np.asarray(points, float) - self.start
        z = d @ self.axis
        rho = np.linalg.norm(d - z[:, None] * self.axis, axis=1)
        return (z >= 0) & (z <= self.length) & (rho <= self.radius)

    def sample(self, rng, n, margin):
        m = np.asarray(margin, float).reshape(-1)
        m = np.broadcast_to(m, (n,))
        r = np.maximum(self.radius - m, 0.0) * np.sqrt(rng.random(n))
        phi = 2 * np.pi * rng.random(n)
        z = m + rng.random(n) * np.maximum(self.length - 2 * m, 0.0)
        return (self.start + z[:, None] * self.axis + (r * np.cos(phi))[:, None] * self.e1
                + (r * np.sin(phi))[:, None] * self.e2)

    @property
    def volume(self):
        return float(np.pi * self.radius**2 * self.length)

    def holds(self, radius):
        return bool(self.radius >= radius and self.length >= 2.0 * radius)

    def __repr__(self) -> str:
        return (f"CylinderRegion(start={tuple(float(x) for x in self.start)}, "
                f"axis={tuple(float(x) for x in self.axis)}, length={self.length:g}, "
                f"radius={self.radius:g})")
