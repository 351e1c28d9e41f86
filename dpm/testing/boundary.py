"""Contract checks of a boundary: the engine's contact distance and normal against brute
force.

The reference is a dense set of points on the boundary's surface (the contract's
``surface()``: points, and ``spacing``, the largest distance from any point of the surface
to its nearest sample). For probe points near the surface on the particles' side, the
brute-force distance is the distance to the nearest sample, d_ref, and the reference
normal points from that sample to the probe. The engine's answer is the nearest of the
boundary's primitives as the step evaluates them (each primitive kind's registered
geometry function, :mod:`dpm.boundaries.primitives`, in the boundary's frame at t = 0),
d and n. Since the samples lie on the surface and one lies within ``spacing`` of the
probe's foot point, 0 <= d_ref - d <= spacing (plus round-off), and the angle between the
normals is at most asin(spacing / (d_ref - spacing)).
"""

from __future__ import annotations

import importlib
import math
from typing import Any, ClassVar

import numpy as np

from .errors import ContractError

#: round-off allowance of the distance comparison, relative to the probe radius
ROUND_OFF = 1e-9


def _boundary(boundary: Any, params: dict[str, Any]):
    from ..boundaries.base import Boundary
    from ..material import Material
    from ..plugins import registry

    if isinstance(boundary, Boundary):
        return boundary
    cls = registry().lookup("boundary", boundary, "dpm.testing")
    return cls(Material("contract", density=1000.0),
               call=f"dpm.testing({getattr(cls, 'name', '') or cls.__name__})", **params)


def engine_contact(boundary: Any, points: np.ndarray, radius: float,
                   params: dict[str, Any] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(distance (n,), unit normal (n, 3)) of the boundary's nearest primitive to each point
    (a sphere centre of radius ``radius``), by the registered geometry functions."""
    from ..boundaries.primitives import primitive_kind

    prims = _boundary(boundary, params or {}).primitives()
    pts = np.asarray(points, float)
    dist = np.full(len(pts), np.inf)
    normal = np.zeros((len(pts), 3))
    for k in range(len(prims.kind)):
        kind = primitive_kind(int(prims.kind[k]))
        mod, fn = kind.function
        f = getattr(importlib.import_module(mod), fn)
        row = tuple(float(x) for x in prims.par[k])
        for i, (x, y, z) in enumerate(pts):
            out = (f(row, x, y, z, float(radius)) if kind.takes_radius else f(row, x, y, z))
            if out[0] < dist[i]:
                dist[i] = out[0]
                normal[i] = out[1:4]
    return dist, normal


def brute_force(surface: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance to the nearest surface sample, unit vector from it to the point)."""
    from scipy.spatial import cKDTree

    d, k = cKDTree(surface).query(points)
    v = points - surface[k]
    return d, v / np.maximum(d, 1e-300)[:, None]


def probe_points(surface: np.ndarray, radius: float, count: int, seed: int = 0,
                 outside: Any = None) -> np.ndarray:
    """Points at 0.2-1 ``radius`` from random surface samples in random directions, kept
    where ``outside`` (the particles' side) holds and the nearest sample is >= 0.2 radius
    away."""
    rng = np.random.default_rng(seed)
    base = surface[rng.integers(0, len(surface), 4 * count)]
    u = rng.normal(size=(len(base), 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    p = base + u * radius * rng.uniform(0.2, 1.0, len(base))[:, None]
    if outside is not None:
        p = p[np.asarray(outside(p), bool)]
    d, _ = brute_force(surface, p)
    return p[d >= 0.2 * radius][:count]


def check_boundary(boundary: Any, params: dict[str, Any] | None, surface: np.ndarray,
                   spacing: float, *, radius: float, probes: np.ndarray | None = None,
                   outside: Any = None, count: int = 300, seed: int = 0,
                   checks: tuple[str, ...] = ("distance", "normal")) -> dict[str, Any]:
    """Compare the engine's contact distance and normal with brute force at probe points
    (see the module docstring); raise :class:`ContractError` on a failure; return the
    largest differences found."""
    name = boundary if isinstance(boundary, str) else type(boundary).__name__
    surface = np.asarray(surface, float)
    if probes is None:
        probes = probe_points(surface, radius, count, seed, outside)
    probes = np.asarray(probes, float)
    if len(probes) < 10:
        raise ContractError(f"{name}: only {len(probes)} probe points near the surface on the "
                            "particles' side; give more surface points or probes")
    dref, nref = brute_force(surface, probes)
    if np.any(dref <= 2.0 * spacing):
        raise ContractError(f"{name}: probes closer to the surface samples than 2 x spacing "
                            f"({spacing:g} m): use a finer surface or probes farther away")
    d, n = engine_contact(boundary, probes, radius, params)
    tol = ROUND_OFF * radius
    gap = dref - d
    if "distance" in checks:
        bad = ~((gap >= -tol) & (gap <= spacing + tol))
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ContractError(
                f"{name}: at {probes[i]} m the engine's contact distance is {d[i]:.9g} m, the "
                f"nearest surface sample is {dref[i]:.9g} m away; allowed d_ref - d in [0, "
                f"{spacing:g}] (the samples' spacing); {int(bad.sum())} of {len(probes)} "
                "probes differ")
    cosang = np.einsum("ij,ij->i", n, nref)
    allowed = np.arcsin(np.minimum(1.0, spacing / np.maximum(dref - spacing, 1e-300))) + 1e-9
    angle = np.arccos(np.clip(cosang, -1.0, 1.0))
    if "normal" in checks:
        bad = ~(angle <= allowed)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ContractError(
                f"{name}: at {probes[i]} m the engine's contact normal is {n[i]}, brute force "
                f"{nref[i]} ({math.degrees(angle[i]):.3g} deg apart; allowed "
                f"{math.degrees(allowed[i]):.3g} deg); {int(bad.sum())} of {len(probes)} "
                "probes differ")
    return {"probes": len(probes), "distance_gap": float(np.max(np.abs(gap))),
            "angle": float(np.max(angle))}


class BoundaryContract:
    """Subclass as ``class TestMine(BoundaryContract)``; set ``boundary``, ``params`` and
    ``radius`` (the particle radius the check is about) and define ``surface(self) ->
    (points (n, 3), spacing)``: dense points on the boundary's surface in its frame at t = 0
    and the largest distance from a surface point to its nearest sample. Optionally
    ``outside(self, points) -> bool array``: the particles' side (default: everywhere)."""

    boundary: ClassVar[Any] = ""
    params: ClassVar[dict[str, Any]] = {}
    radius: ClassVar[float] = 1e-3
    count: ClassVar[int] = 300
    seed: ClassVar[int] = 0

    def surface(self) -> tuple[np.ndarray, float]:
        raise NotImplementedError("define surface(self) -> (points, spacing)")

    def _check(self, what: str) -> dict[str, Any]:
        pts, spacing = self.surface()
        return check_boundary(self.boundary, dict(self.params), pts, float(spacing),
                              radius=self.radius, outside=getattr(self, "outside", None),
                              count=self.count, seed=self.seed, checks=(what,))

    def test_contact_distance_against_brute_force(self) -> None:
        self._check("distance")

    def test_contact_normal_against_brute_force(self) -> None:
        self._check("normal")
