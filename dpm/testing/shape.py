"""Contract checks of a shape: its mass properties against a Monte-Carlo sampled volume.

The reference is the solid itself, given as an inside test in the shape's documented
frame, whose origin is the body's position (the centre of mass): the contract's
``inside(points)`` and ``bounds()``, else the shape's own (a
:class:`dpm.shapes.cluster.ClusterShape` has both), else the union of the shape's sphere
elements (exact for a sphere or a shape that is its union of spheres).

``N`` points uniform in the bounding box (volume V_box, fixed seed) estimate, with w = 1
inside and 0 outside, the volume V = V_box <w>, the first moment S = V_box <w x> (zero
about the centre of mass) and the inertia tensor per unit density J = V_box <w (|x|^2 1 -
x x^T)>. Each estimate's standard error is V_box std(.)/sqrt(N); a check allows 5 of them
(a false failure has odds below 1e-6 per component; the seed is fixed, so a result does
not change between runs). The shape's built body (``build(1, density)``) must match:
mass = density V, S = 0, inertia R diag(I) R^T = density J with R the principal
rotation. Every element must lie inside the solid: 64 points on each element's sphere
(radius shrunk by 1e-6) are tested.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from .errors import ContractError

#: standard errors a Monte-Carlo estimate may differ by
Z = 5.0
#: points per element sphere of the inside test
ELEMENT_POINTS = 64


def _shape(shape: Any, params: dict[str, Any]):
    from ..plugins import registry
    from ..shapes.base import Shape

    if isinstance(shape, Shape):
        return shape
    cls = registry().lookup("shape", shape, "dpm.testing")
    return cls(call=f"dpm.testing({getattr(cls, 'name', '') or cls.__name__})", **params)


def _sphere_points(n: int) -> np.ndarray:
    """``n`` points on the unit sphere (Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * k
    s = np.sqrt(1.0 - z * z)
    return np.column_stack([s * np.cos(phi), s * np.sin(phi), z])


def built_body(shape: Any, params: dict[str, Any], density: float) -> dict[str, np.ndarray]:
    """One body of the shape: mass, inertia tensor and element centres in the shape frame,
    element radii."""
    from ..shapes.geometry import matrix_from_quaternion

    inst = _shape(shape, params)
    b = inst.build(1, density)
    rot = matrix_from_quaternion(np.asarray(b.principal_rotation)[0])
    n = int(b.element_count[0])
    off = np.asarray(b.element_offset, float)[:n]
    return {"mass": float(b.mass[0]),
            "tensor": rot @ np.diag(np.asarray(b.inertia, float)[0]) @ rot.T,
            "centres": off @ rot.T, "radii": np.asarray(b.element_radius, float)[:n],
            "instance": inst}


def union_solid(centres: np.ndarray, radii: np.ndarray):
    """(inside, bounds) of the union of spheres."""
    def inside(p: np.ndarray) -> np.ndarray:
        out = np.zeros(len(p), bool)
        for c, r in zip(centres, radii, strict=True):
            out |= np.einsum("ij,ij->i", p - c, p - c) <= r * r
        return out

    lo = np.min(centres - radii[:, None], axis=0)
    hi = np.max(centres + radii[:, None], axis=0)
    return inside, (lo, hi)


def sampled_mass_properties(inside: Callable[[np.ndarray], np.ndarray],
                            bounds: tuple[Any, Any], samples: int = 400_000,
                            seed: int = 0) -> dict[str, np.ndarray]:
    """Monte-Carlo estimates (and standard errors) of the volume, first moment and inertia
    tensor per unit density of the solid ``inside`` within ``bounds``."""
    lo, hi = (np.asarray(x, float) for x in bounds)
    if not np.all(np.isfinite(lo) & np.isfinite(hi) & (hi > lo)):
        raise ContractError(f"bounds {lo}, {hi} must be finite with upper > lower")
    vbox = float(np.prod(hi - lo))
    rng = np.random.default_rng(seed)
    s0 = np.zeros(1 + 3 + 9)
    s1 = np.zeros(1 + 3 + 9)
    done = 0
    while done < samples:
        n = min(100_000, samples - done)
        x = lo + (hi - lo) * rng.random((n, 3))
        w = np.asarray(inside(x), bool).astype(float)
        r2 = np.einsum("ij,ij->i", x, x)
        j = (r2[:, None, None] * np.eye(3)[None] - x[:, :, None] * x[:, None, :]).reshape(n, 9)
        f = w[:, None] * np.column_stack([np.ones(n), x, j])
        s0 += f.sum(axis=0)
        s1 += (f * f).sum(axis=0)
        done += n
    mean = s0 / samples
    err = np.sqrt(np.maximum(s1 / samples - mean**2, 0.0) / samples)
    return {"volume": vbox * mean[0], "volume_error": vbox * err[0],
            "moment": vbox * mean[1:4], "moment_error": vbox * err[1:4],
            "tensor": vbox * mean[4:].reshape(3, 3), "tensor_error": vbox * err[4:].reshape(3, 3),
            "samples": samples}


def check_shape(shape: Any, params: dict[str, Any] | None = None, *,
                inside: Callable[[np.ndarray], np.ndarray] | None = None,
                bounds: tuple[Any, Any] | None = None, density: float = 1000.0,
                samples: int = 400_000, seed: int = 0,
                checks: tuple[str, ...] = ("mass", "centre", "inertia", "elements")
                ) -> dict[str, Any]:
    """Check the built body of ``shape`` (name, class or instance) against the sampled
    solid (see the module docstring); raise :class:`ContractError` on the first failed
    check of ``checks``; return the estimates."""
    body = built_body(shape, params or {}, density)
    inst = body.pop("instance")
    name = getattr(inst, "name", "") or type(inst).__name__
    if inside is None:
        own_inside, own_bounds = getattr(inst, "inside", None), getattr(inst, "bounds", None)
        try:
            if own_inside is not None and own_bounds is not None:
                inside, bounds = own_inside, own_bounds()
        except NotImplementedError:
            inside = None
        if inside is None:
            inside, bounds = union_solid(body["centres"], body["radii"])
    if bounds is None:
        raise ContractError(f"{name}: give bounds() with inside()")
    est = sampled_mass_properties(inside, bounds, samples, seed)
    floor = 1e-12
    if "mass" in checks:
        want, err = density * est["volume"], Z * density * est["volume_error"]
        if not abs(body["mass"] - want) <= err + floor * want:
            raise ContractError(f"{name}: mass {body['mass']:.6g} kg; the sampled solid's "
                                f"{want:.6g} kg (density {density:g} x volume "
                                f"{est['volume']:.6g} m3), allowed +-{err:.3g} ({Z:g} standard "
                                f"errors of {samples} samples)")
    size = float(np.max(np.abs(np.asarray(bounds[1], float) - np.asarray(bounds[0], float))))
    if "centre" in checks:
        s, err = est["moment"], Z * est["moment_error"]
        bad = np.abs(s) > err + floor * est["volume"] * size
        if bad.any():
            centre = s / est["volume"]
            raise ContractError(f"{name}: the sampled solid's centre of mass is {centre} m in "
                                "the shape frame, whose origin must be the centre of mass "
                                f"(allowed +-{err / est['volume']} m, {Z:g} standard errors)")
    if "inertia" in checks:
        want, err = density * est["tensor"], Z * density * est["tensor_error"]
        scale = float(np.trace(np.abs(want)))
        bad = np.abs(body["tensor"] - want) > err + floor * scale
        if bad.any():
            raise ContractError(f"{name}: inertia tensor in the shape frame\n{body['tensor']}\n"
                                f"the sampled solid's\n{want}\nallowed +-\n{err}\n({Z:g} "
                                f"standard errors of {samples} samples)")
    if "elements" in checks:
        pts = _sphere_points(ELEMENT_POINTS)
        for k, (c, r) in enumerate(zip(body["centres"], body["radii"], strict=True)):
            p = c + (1.0 - 1e-6) * r * pts
            out = ~np.asarray(inside(p), bool)
            if out.any():
                raise ContractError(f"{name}: element {k} (centre {c} m, radius {r:.6g} m) "
                                    f"reaches outside the solid at {int(out.sum())} of "
                                    f"{ELEMENT_POINTS} points of its surface, e.g. {p[out][0]}")
    return {**est, "mass": body["mass"], "body_tensor": body["tensor"]}


class ShapeContract:
    """Subclass as ``class TestMine(ShapeContract)``, set ``shape`` and ``params`` and, for
    a shape whose solid is not the union of its elements (and not a ClusterShape), define
    ``inside(self, points) -> bool array`` and ``bounds(self) -> (lower, upper)`` of the
    ideal solid in the shape frame (origin at the centre of mass)."""

    shape: ClassVar[Any] = ""
    params: ClassVar[dict[str, Any]] = {}
    density: ClassVar[float] = 1000.0
    samples: ClassVar[int] = 400_000
    seed: ClassVar[int] = 0

    def _check(self, what: str) -> dict[str, Any]:
        inside = getattr(self, "inside", None)
        bounds = self.bounds() if inside is not None else None
        return check_shape(self.shape, dict(self.params), inside=inside, bounds=bounds,
                           density=self.density, samples=self.samples, seed=self.seed,
                           checks=(what,))

    def test_mass_against_sampled_volume(self) -> None:
        self._check("mass")

    def test_centre_of_mass_at_origin(self) -> None:
        self._check("centre")

    def test_inertia_against_sampled_volume(self) -> None:
        self._check("inertia")

    def test_elements_inside_solid(self) -> None:
        self._check("elements")
