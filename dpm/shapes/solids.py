"""The analytic clustered shapes of the thesis' shape catalogue (section 2.9.1).

Every shape is given in its *shape frame*: origin at the centre of mass, axes as written
in each class (pictures in ``docs/shapes.md``). Following the thesis, the solids of
revolution (cylinder, cone, double cone, hyperboloid, barrel, disc) have their axis along
x; the torus lies in the x-y plane with its axis along z. Volumes and inertias are closed
forms (checked against trimesh's mass properties of fine meshes in
``tests/objects/test_shapes.py``; the thesis' slips listed in ``shared/seeds/ERRATA.md`` are
corrected). All lengths in metres.
"""

from __future__ import annotations

import math

import numpy as np

from .._lazy import lazy_module
from ..parameters import Parameter
from .cluster import RESOLUTION, ClusterShape, length
from .geometry import (
    ellipsoid_depth,
    inertia_from_second_moment,
    segment_distance_2d,
)

trimesh = lazy_module("trimesh")

#: rotation taking trimesh's revolution axis z onto x: (x, y, z) -> (z, x, y)
_Z_TO_X = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def _transform(rot: np.ndarray, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rot
    t[:3, 3] = shift
    return t


# ====================================================================== ellipsoid
class Ellipsoid(ClusterShape):
    """Ellipsoid with semi-axes ``a`` (x), ``b`` (y), ``c`` (z; default ``c = b``).

    The thesis' DPM allowed only two equal smaller radii (a spheroid, the default);
    here any three positive semi-axes work. V = 4/3 pi a b c,
    I_xx = V (b^2 + c^2) / 5 (cyclic).
    """

    name = "ellipsoid"
    parameters = {
        "a": length("semi-axis along x", 2e-3),
        "b": length("semi-axis along y", 1e-3),
        "c": Parameter(default=None, low=0.0, low_open=True, unit="m",
                       doc="semi-axis along z (default: b)"),
        "resolution": RESOLUTION,
    }

    @property
    def semi_axes(self) -> np.ndarray:
        p = self.params
        return np.array([p["a"], p["b"], p["b"] if p["c"] is None else p["c"]], float)

    def volume(self) -> float:
        a, b, c = self.semi_axes
        return 4.0 / 3.0 * math.pi * a * b * c

    def inertia_tensor(self) -> np.ndarray:
        a, b, c = self.semi_axes
        return self.volume() / 5.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])

    def bounds(self):
        e = self.semi_axes
        return -e, e

    def inside(self, points):
        return np.sum((points / self.semi_axes) ** 2, axis=1) <= 1.0

    def depth(self, points):
        return ellipsoid_depth(points, self.semi_axes)


    def mesh(self, fine: bool = False):
        n = 128 if fine else 40
        m = trimesh.creation.uv_sphere(radius=1.0, count=[n, n])
        m.apply_scale(self.semi_axes)
        return m


# ====================================================================== polyhedra
class _ConvexPolyhedron(ClusterShape):
    """A convex polyhedron given by its vertices (shape frame, centroid at the origin)."""

    def vertices(self) -> np.ndarray:
        raise NotImplementedError

    def _hull(self):
        if "hull" not in self._cache:
            v = self.vertices()
            scale = float(np.max(np.abs(v)))  # build at unit size: trimesh merges tiny edges
            hull = trimesh.convex.convex_hull(v / scale)
            hull.apply_scale(scale)
            self._cache["hull"] = hull
        return self._cache["hull"]

    def _planes(self):
        if "planes" not in self._cache:
            hull = self._hull()
            n = hull.face_normals
            d = np.einsum("ij,ij->i", n, hull.triangles[:, 0])
            # one plane per facet: drop duplicates of coplanar triangles
            key = np.round(np.column_stack([n, d / max(abs(d).max(), 1e-300)]), 9)
            _, first = np.unique(key, axis=0, return_index=True)
            first = np.sort(first)
            self._cache["planes"] = (n[first], d[first])
        return self._cache["planes"]

    def bounds(self):
        v = self.vertices()
        return v.min(axis=0), v.max(axis=0)

    def inside(self, points):
        n, d = self._planes()
        return np.all(points @ n.T <= d, axis=1)

    def depth(self, points):
        n, d = self._planes()
        return np.min(d - points @ n.T, axis=1)

    def mesh(self, fine: bool = False):
        return self._hull().copy()


class _Box(_ConvexPolyhedron):
    def extents(self) -> np.ndarray:
        raise NotImplementedError

    def vertices(self):
        e = 0.5 * self.extents()
        corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
        return corners * e

    def volume(self):
        return float(np.prod(self.extents()))

    def inertia_tensor(self):
        a, b, c = self.extents()
        return self.volume() / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])

    def inside(self, points):
        return np.all(np.abs(points) <= 0.5 * self.extents(), axis=1)

    def depth(self, points):
        return np.min(0.5 * self.extents() - np.abs(points), axis=1)


    def mesh(self, fine: bool = False):
        e = self.extents()
        m = trimesh.creation.box(extents=e / e.max())
        m.apply_scale(e.max())
        return m


class Cube(_Box):
    """Cube of edge ``a``, faces normal to x, y, z. V = a^3, I = a^5 / 6 (per density)."""

    name = "cube"
    parameters = {"a": length("edge length", 2e-3), "resolution": RESOLUTION}

    def extents(self):
        return np.full(3, float(self.params["a"]))


class Block(_Box):
    """Rectangular block with edges ``a`` (x), ``b`` (y), ``c`` (z).

    V = a b c, I_xx = V (b^2 + c^2) / 12 (cyclic).
    """

    name = "block"
    parameters = {
        "a": length("edge along x", 3e-3),
        "b": length("edge along y", 2e-3),
        "c": length("edge along z", 1e-3),
        "resolution": RESOLUTION,
    }

    def extents(self):
        p = self.params
        return np.array([p["a"], p["b"], p["c"]], float)


class Parallelepiped(_ConvexPolyhedron):
    """Parallelepiped with edges ``a``, ``b``, ``c`` (default ``c = b``) and the angles
    ``alpha`` (between the b and c edges), ``beta`` (a, c) and ``gamma`` (a, b) in degrees.

    Edge vectors (crystallographic convention): e1 = a x; e2 = b (cos gamma, sin gamma, 0);
    e3 = c (cos beta, (cos alpha - cos beta cos gamma) / sin gamma, ...), centred on its
    centroid. ``V = |det E|``; second moment S = V/12 E E^T; I = tr(S) 1 - S. With all angles
    90 degrees and c = b this is the thesis' special case (a square prism).
    The default (gamma = 70 degrees) is an oblique prism whose principal axes are not the
    frame's axes.
    """

    name = "parallelepiped"
    parameters = {
        "a": length("length of the first edge (along x)", 3e-3),
        "b": length("length of the second edge (in the x-y plane)", 2e-3),
        "c": Parameter(default=None, low=0.0, low_open=True, unit="m",
                       doc="length of the third edge (default: b)"),
        "alpha": Parameter(default=90.0, low=0.0, high=180.0, low_open=True,
                           high_open=True, unit="deg", doc="angle between b and c edges"),
        "beta": Parameter(default=90.0, low=0.0, high=180.0, low_open=True, high_open=True,
                          unit="deg", doc="angle between a and c edges"),
        "gamma": Parameter(default=70.0, low=0.0, high=180.0, low_open=True,
                           high_open=True, unit="deg", doc="angle between a and b edges"),
        "resolution": RESOLUTION,
    }

    def check(self):
        ca, cb, cg = (math.cos(math.radians(self.params[k])) for k in ("alpha", "beta", "gamma"))
        g = 1 - ca * ca - cb * cb - cg * cg + 2 * ca * cb * cg
        if g <= 1e-6:
            return [f"alpha={self.params['alpha']:g}, beta={self.params['beta']:g}, "
                    f"gamma={self.params['gamma']:g} give no solid (1 - cos^2 alpha - "
                    f"cos^2 beta - cos^2 gamma + 2 cos alpha cos beta cos gamma = {g:.3g} "
                    "must be > 0)"]
        return []

    def edges(self) -> np.ndarray:
        """Edge vectors as the columns of E."""
        p = self.params
        a, b = float(p["a"]), float(p["b"])
        c = b if p["c"] is None else float(p["c"])
        al, be, ga = (math.radians(p[k]) for k in ("alpha", "beta", "gamma"))
        e1 = np.array([a, 0.0, 0.0])
        e2 = b * np.array([math.cos(ga), math.sin(ga), 0.0])
        cy = (math.cos(al) - math.cos(be) * math.cos(ga)) / math.sin(ga)
        cz = math.sqrt(max(1.0 - math.cos(be) ** 2 - cy * cy, 0.0))
        e3 = c * np.array([math.cos(be), cy, cz])
        return np.column_stack([e1, e2, e3])

    def vertices(self):
        corners = np.array([[i, j, k] for i in (-.5, .5) for j in (-.5, .5) for k in (-.5, .5)])
        return corners @ self.edges().T

    def volume(self):
        return float(abs(np.linalg.det(self.edges())))

    def inertia_tensor(self):
        e = self.edges()
        return inertia_from_second_moment(self.volume() / 12.0 * e @ e.T)



class Tetrahedron(_ConvexPolyhedron):
    """Regular tetrahedron of edge ``a``: base triangle parallel to the x-y plane with one
    vertex on the +x side, apex on +z, centroid at the origin.

    V = sqrt(2)/12 a^3; inertia isotropic, I = sqrt(2)/240 a^5 (per density) about every
    axis (the thesis' Ixx and Iyy are misprints, see ERRATA.md).
    """

    name = "tetrahedron"
    parameters = {"a": length("edge length", 2e-3), "resolution": RESOLUTION}

    def vertices(self):
        a = float(self.params["a"])
        h = a * math.sqrt(2.0 / 3.0)
        rc = a / math.sqrt(3.0)
        ang = np.radians([0.0, 120.0, 240.0])
        base = np.column_stack([rc * np.cos(ang), rc * np.sin(ang), np.full(3, -h / 4)])
        return np.vstack([base, [0.0, 0.0, 0.75 * h]])

    def volume(self):
        return math.sqrt(2.0) / 12.0 * float(self.params["a"]) ** 3

    def inertia_tensor(self):
        return math.sqrt(2.0) / 240.0 * float(self.params["a"]) ** 5 * np.eye(3)



# ====================================================================== revolution
class _Revolution(ClusterShape):
    """A solid of revolution about ``axis`` given by its meridian profile.

    ``profile()`` returns (s, rho) points (s along the axis, rho >= 0 the distance from
    it), counter-clockwise in the (rho, s) plane, starting and ending on the axis unless
    the solid has a hole. The depth of a point is its 2-D distance, in its meridian
    half-plane, to the profile's edges off the axis (exact for straight edges, within the
    polyline's chord error for curved ones).
    """

    axis = 0

    def profile(self) -> np.ndarray:
        raise NotImplementedError

    def closed_profile(self) -> bool:
        return False

    def _sr(self, points):
        p = np.asarray(points, float)
        s = p[:, self.axis]
        rho = np.linalg.norm(np.delete(p, self.axis, axis=1), axis=1)
        return s, rho

    def _segments(self):
        if "segments" not in self._cache:
            pr = self.profile()
            if self.closed_profile():
                pr = np.vstack([pr, pr[:1]])
            a, b = pr[:-1], pr[1:]
            on_axis = (np.abs(a[:, 1]) < 1e-15) & (np.abs(b[:, 1]) < 1e-15)
            self._cache["segments"] = (a[~on_axis], b[~on_axis])
        return self._cache["segments"]

    def depth(self, points):
        s, rho = self._sr(points)
        a, b = self._segments()
        return segment_distance_2d(np.column_stack([s, rho]), a, b)

    def bounds(self):
        pr = self.profile()
        rmax = float(pr[:, 1].max())
        lo, hi = np.full(3, -rmax), np.full(3, rmax)
        lo[self.axis], hi[self.axis] = pr[:, 0].min(), pr[:, 0].max()
        return lo, hi

    def mesh(self, fine: bool = False):
        pr = self.fine_profile() if fine else self.profile()
        line = pr[:, ::-1]  # (rho, s) for trimesh.creation.revolve (axis z)
        if self.closed_profile():
            line = np.vstack([line, line[:1]])
        scale = float(np.max(np.abs(line)))  # unit size: trimesh drops tiny faces
        m = trimesh.creation.revolve(line / scale, sections=128 if fine else 48)
        m.apply_scale(scale)
        if self.axis == 0:
            m.apply_transform(_transform(_Z_TO_X))
        return m

    def fine_profile(self) -> np.ndarray:
        return self.profile()


class Cylinder(_Revolution):
    """Cylinder of radius ``r`` and length ``l``, axis along x.

    V = pi r^2 l, I_xx = V r^2 / 2, I_yy = I_zz = V (r^2 / 4 + l^2 / 12).
    """

    name = "cylinder"
    parameters = {"r": length("radius", 1e-3), "l": length("length (along x)", 3e-3),
                  "resolution": RESOLUTION}

    def profile(self):
        r, h = float(self.params["r"]), 0.5 * float(self.params["l"])
        return np.array([[-h, 0.0], [-h, r], [h, r], [h, 0.0]])

    def inside(self, points):
        s, rho = self._sr(points)
        return (np.abs(s) <= 0.5 * self.params["l"]) & (rho <= self.params["r"])

    def volume(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        return math.pi * r * r * l

    def inertia_tensor(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        v = self.volume()
        return np.diag([v * r * r / 2, v * (r * r / 4 + l * l / 12), v * (r * r / 4 + l * l / 12)])



class Cone(_Revolution):
    """Right circular cone of base radius ``r`` and length ``l``, axis along x: base at
    x = -l/4, apex at x = +3l/4 (the centroid is the origin).

    V = pi r^2 l / 3, I_xx = 3/10 V r^2, I_yy = I_zz = 3/80 V (4 r^2 + l^2).
    """

    name = "cone"
    parameters = {"r": length("base radius", 1e-3),
                  "l": length("length, base to apex (along x)", 3e-3),
                  "resolution": RESOLUTION}

    def profile(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        return np.array([[-l / 4, 0.0], [-l / 4, r], [0.75 * l, 0.0]])

    def inside(self, points):
        s, rho = self._sr(points)
        r, l = float(self.params["r"]), float(self.params["l"])
        return (s >= -l / 4) & (rho <= r * (0.75 * l - s) / l)

    def volume(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        return math.pi * r * r * l / 3

    def inertia_tensor(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        v = self.volume()
        t = 3 / 80 * v * (4 * r * r + l * l)
        return np.diag([0.3 * v * r * r, t, t])



class DoubleCone(_Revolution):
    """Two cones of radius ``r`` and length ``l`` joined base to base, axis along x, tips
    at x = -l and x = +l (so the body is 2 l long; ``l`` is the thesis' length).

    V = 2/3 pi r^2 l, I_xx = pi/5 r^4 l, I_yy = I_zz = pi/10 r^2 l (r^2 + 2 l^2 / 3)
    (the thesis' I_yy is twice too large, ERRATA.md).
    """

    name = "double_cone"
    parameters = {"r": length("radius at the middle", 1e-3),
                  "l": length("length of each cone (tip to the middle, along x)", 1.5e-3),
                  "resolution": RESOLUTION}

    def profile(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        return np.array([[-l, 0.0], [0.0, r], [l, 0.0]])

    def inside(self, points):
        s, rho = self._sr(points)
        r, l = float(self.params["r"]), float(self.params["l"])
        return rho <= r * (l - np.abs(s)) / l

    def volume(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        return 2 / 3 * math.pi * r * r * l

    def inertia_tensor(self):
        r, l = float(self.params["r"]), float(self.params["l"])
        t = math.pi / 10 * r * r * l * (r * r + 2 * l * l / 3)
        return np.diag([math.pi / 5 * r**4 * l, t, t])



class _CurvedRevolution(_Revolution):
    """Solid of revolution with a curved side rho(s), |s| <= l/2, and flat ends."""

    n_profile: int = 200

    def radius_at(self, s: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _profile(self, n: int) -> np.ndarray:
        h = 0.5 * float(self.params["l"])
        s = np.linspace(-h, h, n + 1)
        side = np.column_stack([s, self.radius_at(s)])
        return np.vstack([[-h, 0.0], side, [h, 0.0]])

    def profile(self):
        return self._profile(self.n_profile)

    def fine_profile(self):
        return self._profile(200)

    def mesh(self, fine: bool = False):
        if fine:
            return super().mesh(fine=True)
        pr = self._profile(24)[:, ::-1]
        scale = float(np.max(np.abs(pr)))
        m = trimesh.creation.revolve(pr / scale, sections=48)
        m.apply_scale(scale)
        m.apply_transform(_transform(_Z_TO_X))
        return m

    def inside(self, points):
        s, rho = self._sr(points)
        h = 0.5 * float(self.params["l"])
        return (np.abs(s) <= h) & (rho <= self.radius_at(np.clip(s, -h, h)))


class Hyperboloid(_CurvedRevolution):
    """Hyperboloid of one sheet, axis along x, flat ends: end radius ``r1``, waist radius
    ``r2`` <= r1 at x = 0, length ``l``; rho(x)^2 = r2^2 + (r1^2 - r2^2) (2x / l)^2.

    With A = r2^2, B = r1^2 - r2^2: V = pi l (A + B/3) = pi l (r1^2 + 2 r2^2) / 3,
    I_xx = pi l / 2 (A^2 + 2AB/3 + B^2/5),
    I_yy = I_zz = pi l / 4 (A^2 + 2AB/3 + B^2/5) + pi l^3 / 4 (A/3 + B/5).
    """

    name = "hyperboloid"
    parameters = {"r1": length("end radius (the big one)", 1e-3),
                  "r2": length("waist radius (the small one, <= r1)", 0.6e-3),
                  "l": length("length (along x)", 3e-3),
                  "resolution": RESOLUTION}

    def check(self):
        r1, r2 = self.params["r1"], self.params["r2"]
        return [] if r2 <= r1 else [f"r2={r2:g} is outside (0, r1={r1:g}]"]

    def radius_at(self, s):
        r1, r2, l = (float(self.params[k]) for k in ("r1", "r2", "l"))
        return np.sqrt(r2 * r2 + (r1 * r1 - r2 * r2) * (2 * s / l) ** 2)

    def _ab(self):
        r1, r2, l = (float(self.params[k]) for k in ("r1", "r2", "l"))
        return r2 * r2, r1 * r1 - r2 * r2, l

    def volume(self):
        a, b, l = self._ab()
        return math.pi * l * (a + b / 3)

    def inertia_tensor(self):
        a, b, l = self._ab()
        q4 = a * a + 2 * a * b / 3 + b * b / 5
        t = math.pi * l / 4 * q4 + math.pi * l**3 / 4 * (a / 3 + b / 5)
        return np.diag([math.pi * l / 2 * q4, t, t])


class Barrel(_CurvedRevolution):
    """Barrel with a parabolic side, axis along x, flat ends: end radius ``r1``, middle
    radius ``r2`` >= r1, length ``l``; rho(x) = r2 - (r2 - r1) (2x / l)^2.

    With d = r2 - r1: V = pi l (r2^2 - 2 r2 d / 3 + d^2 / 5) (= the thesis' form),
    I_xx = pi l / 2 Q4, I_yy = I_zz = pi l / 4 Q4 + pi l^3 / 4 Q2 where
    Q4 = r2^4 - 4/3 r2^3 d + 6/5 r2^2 d^2 - 4/7 r2 d^3 + d^4 / 9 and
    Q2 = r2^2 / 3 - 2/5 r2 d + d^2 / 7.
    """

    name = "barrel"
    parameters = {"r1": length("end radius (the small one, <= r2)", 0.7e-3),
                  "r2": length("middle radius (the big one)", 1e-3),
                  "l": length("length (along x)", 3e-3),
                  "resolution": RESOLUTION}

    def check(self):
        r1, r2 = self.params["r1"], self.params["r2"]
        return [] if r1 <= r2 else [f"r1={r1:g} is outside (0, r2={r2:g}]"]

    def radius_at(self, s):
        r1, r2, l = (float(self.params[k]) for k in ("r1", "r2", "l"))
        return r2 - (r2 - r1) * (2 * s / l) ** 2

    def volume(self):
        r1, r2, l = (float(self.params[k]) for k in ("r1", "r2", "l"))
        d = r2 - r1
        return math.pi * l * (r2 * r2 - 2 * r2 * d / 3 + d * d / 5)

    def inertia_tensor(self):
        r1, r2, l = (float(self.params[k]) for k in ("r1", "r2", "l"))
        d = r2 - r1
        q4 = r2**4 - 4 / 3 * r2**3 * d + 6 / 5 * r2**2 * d**2 - 4 / 7 * r2 * d**3 + d**4 / 9
        q2 = r2**2 / 3 - 2 / 5 * r2 * d + d**2 / 7
        t = math.pi * l / 4 * q4 + math.pi * l**3 / 4 * q2
        return np.diag([math.pi * l / 2 * q4, t, t])


class Disc(_Revolution):
    """Flat disc (annulus) of outer radius ``r1``, inner radius ``r2`` (0: no hole) and
    thickness ``c``, axis along x.

    V = pi (r1^2 - r2^2) c, I_xx = V (r1^2 + r2^2) / 2,
    I_yy = I_zz = V ((r1^2 + r2^2) / 4 + c^2 / 12) (the thesis omits c^2/12, ERRATA.md).
    """

    name = "disc"
    parameters = {"r1": length("outer radius", 2e-3),
                  "r2": Parameter(default=0.5e-3, low=0.0, unit="m",
                                  doc="inner radius (hole), 0 <= r2 < r1"),
                  "c": length("thickness (along x)", 1e-3),
                  "resolution": RESOLUTION}

    def check(self):
        r1, r2 = self.params["r1"], self.params["r2"]
        return [] if r2 < r1 else [f"r2={r2:g} is outside [0, r1={r1:g})"]

    def closed_profile(self):
        return float(self.params["r2"]) > 0

    def profile(self):
        r1, r2, h = float(self.params["r1"]), float(self.params["r2"]), 0.5 * self.params["c"]
        return np.array([[-h, r2], [-h, r1], [h, r1], [h, r2]])

    def inside(self, points):
        s, rho = self._sr(points)
        p = self.params
        return (np.abs(s) <= 0.5 * p["c"]) & (rho <= p["r1"]) & (rho >= p["r2"])

    def volume(self):
        r1, r2, c = (float(self.params[k]) for k in ("r1", "r2", "c"))
        return math.pi * (r1 * r1 - r2 * r2) * c

    def inertia_tensor(self):
        r1, r2, c = (float(self.params[k]) for k in ("r1", "r2", "c"))
        v = self.volume()
        t = v * ((r1 * r1 + r2 * r2) / 4 + c * c / 12)
        return np.diag([v * (r1 * r1 + r2 * r2) / 2, t, t])



class Torus(_Revolution):
    """Torus of tube radius ``r1`` and ring radius ``r2`` > r1, lying in the x-y plane
    with its axis along z.

    V = 2 pi^2 r1^2 r2, I_zz = V (r2^2 + 3/4 r1^2) (the thesis' I_zz is twice too large,
    ERRATA.md), I_xx = I_yy = V (r2^2 / 2 + 5/8 r1^2).
    """

    name = "torus"
    axis = 2
    parameters = {"r1": length("tube radius", 0.5e-3),
                  "r2": length("ring radius (axis to tube centre), > r1", 1.5e-3),
                  "resolution": RESOLUTION}

    def check(self):
        r1, r2 = self.params["r1"], self.params["r2"]
        return [] if r1 < r2 else [f"r1={r1:g} is outside (0, r2={r2:g})"]

    def closed_profile(self):
        return True

    def profile(self):
        r1, r2 = float(self.params["r1"]), float(self.params["r2"])
        t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
        return np.column_stack([r1 * np.sin(t), r2 + r1 * np.cos(t)])

    def bounds(self):
        r1, r2 = float(self.params["r1"]), float(self.params["r2"])
        e = np.array([r1 + r2, r1 + r2, r1])
        return -e, e

    def _tube(self, points):
        s, rho = self._sr(points)
        return np.hypot(rho - self.params["r2"], s)

    def inside(self, points):
        return self._tube(points) <= self.params["r1"]

    def depth(self, points):
        return self.params["r1"] - self._tube(points)


    def volume(self):
        r1, r2 = float(self.params["r1"]), float(self.params["r2"])
        return 2 * math.pi**2 * r1 * r1 * r2

    def inertia_tensor(self):
        r1, r2 = float(self.params["r1"]), float(self.params["r2"])
        v = self.volume()
        t = v * (r2 * r2 / 2 + 5 / 8 * r1 * r1)
        return np.diag([t, t, v * (r2 * r2 + 0.75 * r1 * r1)])

    def mesh(self, fine: bool = False):
        r1, r2 = float(self.params["r1"]), float(self.params["r2"])
        n = (512, 128) if fine else (64, 24)
        m = trimesh.creation.torus(1.0, r1 / r2, major_sections=n[0], minor_sections=n[1])
        m.apply_scale(r2)  # built at unit size: trimesh drops tiny faces
        return m
