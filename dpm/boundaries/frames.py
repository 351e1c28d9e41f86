"""Small geometry helpers of the boundary classes."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import ParameterError
from ..parameters import shown


def unit(call: str, name: str, v: Sequence[float]) -> np.ndarray:
    """``v`` normalised; a zero vector is refused naming the parameter."""
    a = np.asarray(v, float)
    n = float(np.linalg.norm(a))
    if n == 0.0 or not np.isfinite(n):
        raise ParameterError(f"{call}: {name}={shown(v)} must be a non-zero finite vector")
    return a / n


def in_plane_axes(call: str, normal: np.ndarray, u: Sequence[float] | None,
                  uname: str = "u") -> tuple[np.ndarray, np.ndarray]:
    """Unit axes (u, v) spanning the plane of ``normal`` with u x v = normal; ``u`` is
    projected onto the plane (a default is picked if None)."""
    if u is None:
        helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0, 1.0, 0])
        u = np.cross(normal, np.cross(helper, normal))
    given = u
    u = np.asarray(u, float)
    u = u - (u @ normal) * normal
    if np.linalg.norm(u) < 1e-12:
        raise ParameterError(f"{call}: {uname}={shown(given)} must not be parallel to the "
                             "normal")
    u = u / np.linalg.norm(u)
    return u, np.cross(normal, u)


def box_of_points(points: np.ndarray, pad: float) -> tuple[np.ndarray, np.ndarray]:
    return points.min(axis=0) - pad, points.max(axis=0) + pad
