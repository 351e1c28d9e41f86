"""Regions of space for inlets and outlets, and planar faces for stream insertion."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .errors import ParameterError
from .parameters import Parameter, numeric_array, validate


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


class Face(Region):
    """A planar face for stream insertion (LIGGGHTS' ``insert/stream``): an inlet given a
    face places its bodies in the slab behind the face that the next interval carries
    through it (:class:`dpm.flow.Inlet`). Subclasses give :meth:`sample` (points on the
    face), :meth:`on_face` (projection inside the outline), ``point``, ``normal``
    (unit, either side: the inlet orients it along its velocity), ``area`` and the bounding
    box ``lower``, ``upper``. A face has no volume (an outlet refuses it)."""

    point: np.ndarray
    normal: np.ndarray
    area: float
    lower: np.ndarray
    upper: np.ndarray

    def on_face(self, points: np.ndarray) -> np.ndarray:
        """Mask of the points whose projection on the plane lies on the face."""
        raise NotImplementedError

    def contains(self, points):
        """Points on the face (within 1e-9 of its size of the plane)."""
        p = np.asarray(points, float).reshape(-1, 3)
        tol = 1e-9 * float(np.max(self.upper - self.lower))
        return self.on_face(p) & (np.abs((p - self.point) @ self.normal) <= tol)

    @property
    def volume(self):
        raise NotImplementedError("a face has an area, no volume")

    def _box(self, pts: np.ndarray) -> None:
        self.lower = pts.min(axis=0)
        self.upper = pts.max(axis=0)


class RectangleFace(Face):
    """The parallelogram ``corner + a edge1 + b edge2`` (0 <= a, b <= 1); normal
    edge1 x edge2 (a rectangle when the edges are perpendicular)."""

    parameters = {"corner": Parameter(kind="vector", unit="m"),
                  "edge1": Parameter(kind="vector", unit="m"),
                  "edge2": Parameter(kind="vector", unit="m")}

    def __init__(self, corner: Sequence[float], edge1: Sequence[float],
                 edge2: Sequence[float]) -> None:
        validate("RectangleFace()", self.parameters,
                 {"corner": corner, "edge1": edge1, "edge2": edge2})
        self.point = np.asarray(corner, float).reshape(3)
        self.edge1 = np.asarray(edge1, float).reshape(3)
        self.edge2 = np.asarray(edge2, float).reshape(3)
        cross = np.cross(self.edge1, self.edge2)
        scale = float(np.linalg.norm(self.edge1) * np.linalg.norm(self.edge2))
        if not scale > 0 or np.linalg.norm(cross) <= 1e-9 * scale:
            raise ParameterError(f"RectangleFace(): edge1={tuple(self.edge1)}, "
                                 f"edge2={tuple(self.edge2)} must be non-zero and not "
                                 "parallel")
        self.area = float(np.linalg.norm(cross))
        self.normal = cross / self.area
        # (a, b) of a point: the dual basis of the two edges
        self._dual = np.linalg.pinv(np.column_stack([self.edge1, self.edge2]))
        c = self.point
        self._box(np.array([c, c + self.edge1, c + self.edge2, c + self.edge1 + self.edge2]))

    def sample(self, rng, n, margin):
        a, b = rng.random((2, n))
        return self.point + a[:, None] * self.edge1 + b[:, None] * self.edge2

    def on_face(self, points):
        ab = (np.asarray(points, float).reshape(-1, 3) - self.point) @ self._dual.T
        return np.all((ab >= -1e-12) & (ab <= 1 + 1e-12), axis=1)

    def __repr__(self) -> str:
        return (f"RectangleFace(corner={tuple(float(x) for x in self.point)}, "
                f"edge1={tuple(float(x) for x in self.edge1)}, "
                f"edge2={tuple(float(x) for x in self.edge2)})")


class DiscFace(Face):
    """The disc of ``radius`` about ``center`` normal to ``normal``."""

    parameters = {"center": Parameter(kind="vector", unit="m"),
                  "normal": Parameter(kind="vector"),
                  "radius": Parameter(low=0.0, low_open=True, unit="m")}

    def __init__(self, center: Sequence[float], normal: Sequence[float],
                 radius: float) -> None:
        validate("DiscFace()", self.parameters,
                 {"center": center, "normal": normal, "radius": radius})
        nrm = np.asarray(normal, float).reshape(3)
        if np.linalg.norm(nrm) == 0:
            raise ParameterError(f"DiscFace(): normal={tuple(nrm)} must be non-zero")
        self.point = np.asarray(center, float).reshape(3)
        self.normal = nrm / np.linalg.norm(nrm)
        self.radius = float(radius)
        self.area = math.pi * self.radius**2
        helper = np.array([1.0, 0, 0]) if abs(self.normal[0]) < 0.9 else np.array([0, 1.0, 0])
        self.e1 = np.cross(self.normal, helper)
        self.e1 /= np.linalg.norm(self.e1)
        self.e2 = np.cross(self.normal, self.e1)
        ext = self.radius * np.sqrt(np.maximum(1.0 - self.normal**2, 0.0))
        self.lower, self.upper = self.point - ext, self.point + ext

    def sample(self, rng, n, margin):
        r = self.radius * np.sqrt(rng.random(n))
        phi = 2 * np.pi * rng.random(n)
        return (self.point + (r * np.cos(phi))[:, None] * self.e1
                + (r * np.sin(phi))[:, None] * self.e2)

    def on_face(self, points):
        d = np.asarray(points, float).reshape(-1, 3) - self.point
        rho = d - (d @ self.normal)[:, None] * self.normal
        return np.linalg.norm(rho, axis=1) <= self.radius * (1 + 1e-12)

    def __repr__(self) -> str:
        return (f"DiscFace(center={tuple(float(x) for x in self.point)}, "
                f"normal={tuple(float(x) for x in self.normal)}, radius={self.radius:g})")


class MeshFace(Face):
    """A planar triangle mesh: a ``file`` (STL, OBJ, ... read by trimesh; ``scale`` then
    ``translate`` applied, as for the ``mesh`` boundary) or ``vertices`` (n, 3) [m] and
    ``triangles`` (m, 3) indices. LIGGGHTS' insertion face ``fix mesh/surface file
    insertion_face.stl``. Every triangle must lie in one plane (to 1e-6 of the mesh's
    size)."""

    parameters = {"file": Parameter(default=None, kind="str"),
                  "vertices": Parameter(default=None, kind="any"),
                  "triangles": Parameter(default=None, kind="any"),
                  "scale": Parameter(default=1.0, low=0.0, low_open=True),
                  "translate": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m")}

    def __init__(self, file: str | None = None, vertices=None, triangles=None,
                 scale: float = 1.0, translate: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
        call = "MeshFace()"
        validate(call, self.parameters, {"file": file, "vertices": vertices,
                                         "triangles": triangles, "scale": scale,
                                         "translate": translate})
        if (file is None) == (vertices is None) or (vertices is None) != (triangles is None):
            raise ParameterError(f"{call}: give file=, or vertices= and triangles=")
        if file is not None:
            import trimesh

            from .boundaries.mesh import check_stl

            check_stl(call, "file", file)
            try:
                m = trimesh.load(str(file), force="mesh")
            except (OSError, ValueError) as exc:
                raise ParameterError(f"{call}: file={str(file)!r} cannot be read: {exc}") \
                    from None
            v, f = np.asarray(m.vertices, float), np.asarray(m.faces, np.int64)
        else:
            v = numeric_array(vertices)
            f = numeric_array(triangles)
            if (v is None or v.ndim != 2 or v.shape[1] != 3 or f is None or f.ndim != 2
                    or f.shape[1] != 3 or np.any(f != np.round(f))):
                raise ParameterError(f"{call}: vertices must be (n, 3) numbers and "
                                     "triangles (m, 3) integer indices")
            f = f.astype(np.int64)
            if np.any(f < 0) or np.any(f >= len(v)):
                raise ParameterError(f"{call}: triangles index beyond the {len(v)} vertices")
        if len(f) == 0:
            raise ParameterError(f"{call}: the mesh has no triangles")
        self.file = None if file is None else str(file)
        self.vertices = v * float(scale) + np.asarray(translate, float)
        self.triangles = f
        tri = self.vertices[f]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        areas = 0.5 * np.linalg.norm(cross, axis=1)
        self.area = float(areas.sum())
        if not self.area > 0:
            raise ParameterError(f"{call}: the triangles have no area")
        k = int(np.argmax(areas))
        self.normal = cross[k] / np.linalg.norm(cross[k])
        self.point = tri[k, 0].copy()
        self._box(self.vertices[np.unique(f)])
        size = float(np.max(self.upper - self.lower))
        off = np.abs((self.vertices[np.unique(f)] - self.point) @ self.normal)
        if np.max(off) > 1e-6 * size:
            raise ParameterError(f"{call}: the mesh is not planar (a vertex lies "
                                 f"{np.max(off):.3g} m off the plane of its largest "
                                 "triangle); an insertion face must be planar")
        self._tri = tri
        self._cum = np.cumsum(areas) / self.area

    def sample(self, rng, n, margin):
        k = np.minimum(np.searchsorted(self._cum, rng.random(n)), len(self._tri) - 1)
        u, v = rng.random((2, n))
        flip = u + v > 1
        u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
        t = self._tri[k]
        return t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])

    def on_face(self, points):
        p = np.asarray(points, float).reshape(-1, 3)
        p = p - ((p - self.point) @ self.normal)[:, None] * self.normal
        out = np.zeros(len(p), bool)
        for a, b, c in self._tri:  # barycentric test, triangle by triangle
            v0, v1 = b - a, c - a
            d00, d01, d11 = v0 @ v0, v0 @ v1, v1 @ v1
            den = d00 * d11 - d01 * d01
            if den <= 0:
                continue
            w = p - a
            d20, d21 = w @ v0, w @ v1
            s = (d11 * d20 - d01 * d21) / den
            t = (d00 * d21 - d01 * d20) / den
            out |= (s >= -1e-12) & (t >= -1e-12) & (s + t <= 1 + 1e-12)
        return out

    def __repr__(self) -> str:
        what = f"file={self.file!r}" if self.file else f"{len(self.triangles)} triangles"
        return f"MeshFace({what}, area={self.area:g})"
