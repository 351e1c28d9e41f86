"""Rigid bodies made of overlapping sphere elements ("sub-shapes", thesis section 2.4.2).

A :class:`ClusterShape` describes an ideal solid in its own documented *shape frame*
(origin at the centre of mass) by an inside test, the depth of interior points below the
surface, its bounds, a triangle mesh and its mass properties (closed forms, or trimesh for
meshes). The sphere cluster is generated once per shape instance and cached; ``build``
tiles it for any number of bodies.

Mass, centre of mass and inertia tensor are those of the ideal solid, never of the
overlapping spheres. The principal frame is found by diagonalising the inertia tensor
(:func:`dpm.shapes.geometry.principal_frame`); element offsets are given in it.

Cluster generation (:func:`generate_cluster`), deterministic, all spheres inscribed
(every element lies inside the ideal solid: its radius is the exact depth of its centre):

1. the largest inscribed sphere (deepest voxel of a coarse grid, exact depth) is placed;
2. the surface is sampled (area-uniform, fixed seed, about four points per tol^2);
3. greedy, farthest point first: take the surface sample farthest from the union of the
   spheres placed so far; place the *maximal inscribed ball touching the surface there*
   (walk inwards along the normal while the depth keeps growing as fast as the walked
   distance); if that ball is smaller than ``r_min`` (near an edge or a tip), walk its
   centre up the depth gradient to the nearest point with depth ``r_min`` instead; a
   sample no allowed ball brings within ``tol`` is given up (it is reported by the
   metrics, not hidden);
4. stop when every remaining sample is within ``tol`` of the union;
5. a coarse voxel pass fills any interior hole deeper than ``tol`` left between balls.

The resolution knob ("sub-shape packing density") ``resolution`` in (0, 1] sets the
surface tolerance ``tol = R_in * 0.5 * 0.04**resolution`` (``R_in`` the largest inscribed
radius: from 0.5 R_in at resolution -> 0 to R_in / 50 at resolution 1) and the smallest
element radius ``r_min = tol`` (which bounds the critical time step from below). Higher
resolution: smaller tolerance, more spheres, closer shape; the union's volume converges to
the solid's (about 98 % at resolution 1). Points of sharp edges and tips stay farther
from the cluster than ``tol`` (up to about 2 tol at a tetrahedron's tip): an element can't
be smaller than ``r_min``.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .._lazy import lazy_module
from ..errors import ParameterError
from ..parameters import Parameter
from .base import BodyBatch, Shape
from .geometry import principal_frame, quaternion_from_matrix

trimesh = lazy_module("trimesh")
ndimage = lazy_module("scipy.ndimage")
spatial = lazy_module("scipy.spatial")

#: surface tolerance at resolution -> 0 and at resolution 1, as fractions of the largest
#: inscribed radius R_in (geometric interpolation in between)
TOLERANCE_COARSE = 0.5
TOLERANCE_FINE = 0.02
#: smallest element radius as a multiple of the surface tolerance
MIN_RADIUS_FACTOR = 1.0
#: surface samples used by the generator
MIN_SAMPLES = 3000
MAX_SAMPLES = 60_000
#: most elements a cluster may have (the generator refuses beyond)
MAX_ELEMENTS = 20_000
#: steps of the inward walk that finds a maximal ball
WALK_STEPS = 48
#: voxel budget of the coarse grid that finds the deepest point
COARSE_VOXELS = 40_000
#: most cells a voxel grid may have (a solid much thinner than long needs a fine grid over
#: its whole box), and the bytes a cell costs (the grid, its distance transform's arrays)
MAX_GRID_CELLS = 8_000_000
BYTES_PER_GRID_CELL = 50
#: clustered shapes remembered by :func:`built_shape` (the most recently built)
BUILT_MAX = 256
_BUILT: OrderedDict[str, ClusterShape] = OrderedDict()

RESOLUTION = Parameter(
    default=0.3, low=0.0, high=1.0, low_open=True,
    doc="sub-shape packing density: surface tolerance tol = R_in * 0.5 * 0.04**resolution "
        "(R_in: largest inscribed sphere radius), elements >= tol; higher = more spheres, "
        "closer shape")


def length(doc: str, default: Any) -> Parameter:
    """A positive length parameter [m]."""
    return Parameter(default=default, low=0.0, low_open=True, unit="m", doc=doc)


@dataclass
class MassProperties:
    """Mass properties of the ideal solid per unit density.

    ``volume`` [m3]; ``centre`` the centre of mass in the coordinates the solid was given
    in (zero for the built-in shapes, whose frame is centred on it; a mesh's own
    coordinates for a MeshShape); ``tensor`` the inertia tensor per unit density [m5]
    about the centre of mass in the shape frame; ``moments`` the principal moments
    (ascending) and ``rotation`` the proper rotation whose columns are the principal axes
    in the shape frame; ``quaternion`` (w, x, y, z) of ``rotation``.
    """

    volume: float
    centre: np.ndarray
    tensor: np.ndarray
    moments: np.ndarray
    rotation: np.ndarray
    quaternion: np.ndarray

    @classmethod
    def from_tensor(cls, volume: float, tensor: np.ndarray,
                    centre: np.ndarray | None = None) -> MassProperties:
        t = np.asarray(tensor, dtype=float)
        moments, rot = principal_frame(t)
        return cls(float(volume), np.zeros(3) if centre is None else np.asarray(centre, float),
                   t, moments, rot, quaternion_from_matrix(rot))


@dataclass
class Cluster:
    """Sphere elements of one body in the shape frame (centre of mass at the origin).

    ``inscribed_radius`` R_in, ``tolerance`` the surface tolerance and ``min_radius`` the
    smallest element radius allowed at the cluster's resolution, ``samples`` the number
    of surface samples the generator checked, ``seconds`` its run time.
    """

    centres: np.ndarray
    radii: np.ndarray
    inscribed_radius: float
    tolerance: float
    min_radius: float
    samples: int
    seconds: float

    def __len__(self) -> int:
        return len(self.radii)


class ClusterShape(Shape):
    """An ideal solid approximated by a cluster of sphere elements.

    Subclasses declare ``parameters`` (including ``resolution``) and implement
    :meth:`volume`, :meth:`inertia_tensor`, :meth:`bounds`, :meth:`inside`, :meth:`depth`
    and :meth:`mesh`, all in the shape frame whose origin is the centre of mass, and may
    refine :meth:`check` for constraints between parameters.
    """

    #: offset the voxel grid by an irrational fraction of its spacing (mesh ray tests)
    grid_jitter: ClassVar[bool] = False

    def __init__(self, call: str | None = None, **params: Any) -> None:
        self.call = call or f"{type(self).__name__}()"
        super().__init__(call=self.call, **params)
        problems = self.check()
        if problems:
            raise ParameterError("\n".join(f"{self.call}: {m}" for m in problems))
        self._cache: dict[str, Any] = {}

    # ------------------------------------------------------------------ to implement
    def check(self) -> list[str]:
        """Problems between parameters (each message names parameter, value and range)."""
        return []

    def volume(self) -> float:
        raise NotImplementedError

    def inertia_tensor(self) -> np.ndarray:
        """Inertia tensor per unit density [m5] about the centre of mass, shape frame."""
        raise NotImplementedError

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def inside(self, points: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def depth(self, points: np.ndarray) -> np.ndarray:
        """Distance of interior points to the surface (>= 0; undefined outside)."""
        raise NotImplementedError

    def mesh(self, fine: bool = False):
        """A closed trimesh of the solid in the shape frame (fine: for mass checks)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ provided
    def inside_grid(self, xs: np.ndarray, ys: np.ndarray, zs: np.ndarray) -> np.ndarray:
        """Inside test on the grid xs x ys x zs, shape (len(xs), len(ys), len(zs))."""
        out = np.empty((len(xs), len(ys), len(zs)), dtype=bool)
        gy, gz = np.meshgrid(ys, zs, indexing="ij")
        yz = np.column_stack([gy.ravel(), gz.ravel()])
        for i, x in enumerate(xs):
            pts = np.column_stack([np.full(len(yz), x), yz])
            out[i] = self.inside(pts).reshape(len(ys), len(zs))
        return out

    def deepest_point(self) -> tuple[float, np.ndarray]:
        """Radius and centre of the largest inscribed sphere (best voxel of a coarse grid)."""
        if "deepest" not in self._cache:
            lo, hi = self.bounds()
            lo, hi = np.asarray(lo, float), np.asarray(hi, float)
            h = (float(np.prod(hi - lo)) / COARSE_VOXELS) ** (1.0 / 3.0)
            h = min(h, float(np.min(hi - lo)) / 8.0)
            axes = _grid_axes(self, lo, hi, h, "largest inscribed sphere")
            inside = self.inside_grid(*axes)
            if not inside.any():
                raise ParameterError(f"{self.call}: the solid is too thin for the voxel grid")
            edt = ndimage.distance_transform_edt(inside, sampling=h).ravel()
            top = np.argsort(-edt, kind="stable")[:16]
            idx = np.unravel_index(top, inside.shape)
            pts = np.column_stack([axes[0][idx[0]], axes[1][idx[1]], axes[2][idx[2]]])
            d = self.depth(pts)
            k = int(np.argmax(d))
            self._cache["deepest"] = (float(d[k]), pts[k])
        return self._cache["deepest"]

    def surface_samples(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """``count`` points on the surface (area-uniform, seed 0) and inward normals."""
        key = ("samples", count)
        if key not in self._cache:
            m = self.mesh(fine=True)
            pts, faces = trimesh.sample.sample_surface(m, count, seed=0)
            self._cache[key] = (np.asarray(pts), -m.face_normals[faces])
        return self._cache[key]

    @property
    def resolution(self) -> float:
        return float(self.params["resolution"])

    def mass_properties(self) -> MassProperties:
        """Volume, centre and inertia of the ideal solid per unit density (cached)."""
        if "mass" not in self._cache:
            self._cache["mass"] = MassProperties.from_tensor(self.volume(),
                                                             self.inertia_tensor())
        return self._cache["mass"]

    def cluster(self) -> Cluster:
        """The sphere elements in the shape frame (generated once, cached)."""
        if "cluster" not in self._cache:
            self._cache["cluster"] = generate_cluster(self, self.resolution)
        return self._cache["cluster"]

    def principal_offsets(self) -> np.ndarray:
        """Element centres in the principal frame (rows: R^T c)."""
        return self.cluster().centres @ self.mass_properties().rotation

    def build(self, count: int, density: float) -> BodyBatch:
        mp = self.mass_properties()
        cl = self.cluster()
        off = self.principal_offsets()
        m = len(cl.radii)
        bound = float(np.max(np.linalg.norm(off, axis=1) + cl.radii))
        batch = BodyBatch(
            mass=np.full(count, density * mp.volume),
            inertia=np.tile(density * mp.moments, (count, 1)),
            element_count=np.full(count, m, dtype=np.int64),
            element_offset=np.tile(off, (count, 1)),
            element_radius=np.tile(cl.radii, count),
            bounding_radius=np.full(count, bound),
            principal_rotation=np.tile(mp.quaternion, (count, 1)))
        remember(self, off, cl.radii)
        return batch

    def describe(self, resolution: bool = True) -> str:
        """``name(p=v, ...)`` with the shape's parameters."""
        skip = ("mesh",) if resolution else ("mesh", "resolution")
        args = ", ".join(f"{k}={_fmt_param(v)}" for k, v in self.params.items()
                         if v is not None and k not in skip)
        return f"{self.name}({args})"


def element_key(offsets: np.ndarray, radii: np.ndarray) -> str:
    """A digest of one body's elements (offsets in the principal frame, radii): equal for
    the bodies of one shape, as the state holds them (the arrays :meth:`ClusterShape.build`
    gives, copied bit for bit)."""
    h = hashlib.sha256(np.ascontiguousarray(offsets, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(radii, dtype=np.float64).tobytes())
    return h.hexdigest()[:32]


def remember(shape: ClusterShape, offsets: np.ndarray, radii: np.ndarray) -> None:
    """Remember ``shape`` under the digest of its elements (:func:`element_key`), so that
    the output finds the ideal solid of a body from its elements (``sim.output(...,
    solids=True)``, :mod:`dpm.io.solids`); the :data:`BUILT_MAX` most recent are kept."""
    key = element_key(offsets, radii)
    _BUILT[key] = shape
    _BUILT.move_to_end(key)
    while len(_BUILT) > BUILT_MAX:
        _BUILT.popitem(last=False)


def built_shape(key: str) -> ClusterShape | None:
    """The clustered shape built in this process whose elements have the digest ``key``
    (None when none is remembered)."""
    return _BUILT.get(key)


def _fmt_param(v: Any) -> str:
    if isinstance(v, float | int | np.floating | np.integer) and not isinstance(v, bool):
        return f"{float(v):g}"
    return repr(v) if isinstance(v, str) else str(v)


def _grid_axes(shape: ClusterShape, lo: np.ndarray, hi: np.ndarray, h: float,
               purpose: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The axes of a voxel grid of spacing ``h`` over the box [lo, hi] of ``shape``;
    ParameterError, before anything is allocated, beyond :data:`MAX_GRID_CELLS` cells."""
    mid = 0.5 * (np.asarray(lo) + np.asarray(hi))
    ext = np.asarray(hi) - np.asarray(lo)
    shift = (np.array([math.sqrt(2), math.sqrt(3), math.sqrt(5)]) - 1.0) * 1e-3 * h \
        if shape.grid_jitter else np.zeros(3)
    counts = [2 * int(math.ceil(ext[k] / (2 * h))) + 3 for k in range(3)]
    cells = math.prod(counts)
    if cells > MAX_GRID_CELLS:
        raise ParameterError(
            f"{shape.call}: {shape.describe()} needs a voxel grid of {cells:,} cells "
            f"({' x '.join(map(str, counts))}, about {cells * BYTES_PER_GRID_CELL / 1e9:.3g} "
            f"GB) for its {purpose}; allowed: at most {MAX_GRID_CELLS:,} cells "
            f"({MAX_GRID_CELLS * BYTES_PER_GRID_CELL / 1e6:.0f} MB): a less slender solid "
            "(its thinnest part sets the grid spacing)")
    xs, ys, zs = (mid[k] + shift[k] + (np.arange(n) - (n - 1) / 2) * h
                  for k, n in enumerate(counts))
    return xs, ys, zs


def generate_cluster(shape: ClusterShape, resolution: float) -> Cluster:
    """Sphere cluster of ``shape`` at ``resolution`` (see the module docstring)."""
    t0 = time.perf_counter()
    r_in, deepest = shape.deepest_point()
    tol, r_floor = tolerances(r_in, resolution)
    pts, normals = shape.surface_samples(surface_sample_count(shape, tol))
    tree = spatial.cKDTree(pts)
    centres: list[np.ndarray] = []
    radii: list[float] = []
    dist = np.full(len(pts), np.inf)
    excluded = np.zeros(len(pts), dtype=bool)

    def place(c: np.ndarray, r: float, reach: float) -> None:
        centres.append(c)
        radii.append(r)
        if np.isfinite(reach):
            near = np.asarray(tree.query_ball_point(c, r + reach), dtype=np.int64)
        else:
            near = np.arange(len(pts))
        if len(near):
            d = np.linalg.norm(pts[near] - c, axis=1) - r
            dist[near] = np.minimum(dist[near], d)

    place(deepest, float(shape.depth(deepest[None, :])[0]), np.inf)
    while True:
        gap = np.where(excluded, -np.inf, dist)
        i = int(np.argmax(gap))
        if gap[i] <= tol:
            break
        c, r = maximal_ball(shape, pts[i], normals[i], r_in)
        if r < r_floor:
            c, r = floor_ball(shape, c, r_floor)
        cs, rs = np.array(centres), np.array(radii)
        redundant = np.any(np.linalg.norm(cs - c, axis=1) + r <= rs + 1e-9 * r_in)
        helps = np.linalg.norm(pts[i] - c) - r < gap[i] - 0.25 * tol
        if r < r_floor or redundant or not helps:
            excluded[i] = True
            continue
        place(c, r, gap[i])
        if len(radii) > MAX_ELEMENTS:
            raise ParameterError(
                f"{shape.call}: resolution={resolution:g} needs more than {MAX_ELEMENTS} "
                f"spheres (surface tolerance {tol:.3g} m against an inscribed radius "
                f"{r_in:.3g} m); lower the resolution")
        if dist[i] > tol:  # the ball missed its own point (faceted normal): give it up
            excluded[i] = True
    # interior: cover any hole deeper than the tolerance left between the balls
    _fill_interior(shape, r_in, max(tol, r_floor), centres, radii)
    return Cluster(centres=np.array(centres), radii=np.array(radii), inscribed_radius=r_in,
                   tolerance=tol, min_radius=r_floor, samples=len(pts),
                   seconds=time.perf_counter() - t0)


def tolerances(r_in: float, resolution: float) -> tuple[float, float]:
    """Surface tolerance and smallest element radius at ``resolution``."""
    tol = r_in * TOLERANCE_COARSE * (TOLERANCE_FINE / TOLERANCE_COARSE) ** float(resolution)
    return tol, MIN_RADIUS_FACTOR * tol


def surface_sample_count(shape: ClusterShape, tol: float) -> int:
    """Surface samples: about four per tol^2 of area, within [MIN_SAMPLES, MAX_SAMPLES]."""
    area = float(shape.mesh(fine=True).area)
    return int(np.clip(4.0 * area / tol**2, MIN_SAMPLES, MAX_SAMPLES))


def maximal_ball(shape: ClusterShape, p: np.ndarray, n: np.ndarray,
                 r_in: float) -> tuple[np.ndarray, float]:
    """The largest inscribed ball touching the surface at ``p`` (inward normal ``n``).

    Walks from ``p`` along ``n`` while the depth of the walked point stays equal to the
    walked distance (the ball of that radius still touches the surface at ``p``; depth is
    1-Lipschitz, so once it falls behind it never catches up), refines the end with a
    second, finer walk, and returns the centre and its exact depth as the radius.
    """
    slack = 1e-4 * r_in
    lo, hi = 0.0, 1.02 * r_in
    for _ in range(2):
        steps = np.linspace(lo, hi, WALK_STEPS + 1)[1:]
        d = shape.depth(p + steps[:, None] * n)
        ok = d >= steps - slack
        k = int(np.argmin(ok)) if not ok.all() else len(ok)
        if k == len(ok):
            lo = steps[-1]
            break
        lo, hi = (steps[k - 1] if k > 0 else lo), steps[k]
    if lo <= 0:
        return p, 0.0
    c = p + lo * n
    if not shape.inside(c[None, :])[0]:  # a normal pointing out (bad mesh): no ball
        return p, 0.0
    return c, float(shape.depth(c[None, :])[0])


def floor_ball(shape: ClusterShape, c: np.ndarray, r_floor: float) -> tuple[np.ndarray, float]:
    """From a ball smaller than ``r_floor`` (near an edge or a tip), walk its centre up the
    depth gradient to the first point as deep as ``r_floor``: the nearest ball allowed."""
    eta = 0.25 * r_floor
    probe = c + eta * np.vstack([np.eye(3), -np.eye(3)])
    d = shape.depth(probe)
    g = (d[:3] - d[3:]) / (2 * eta)
    norm = float(np.linalg.norm(g))
    if norm < 1e-6:
        return c, 0.0
    steps = np.linspace(0.0, 4.0 * r_floor, 33)[1:]
    walk = c + steps[:, None] * (g / norm)
    d = shape.depth(walk)
    ok = (d >= r_floor) & shape.inside(walk)
    if not ok.any():
        return c, 0.0
    k = int(np.argmax(ok))
    return walk[k], float(d[k])


def _fill_interior(shape: ClusterShape, r_in: float, threshold: float,
                   centres: list, radii: list) -> None:
    lo, hi = shape.bounds()
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    h = max(r_in / 10.0, (float(np.prod(hi - lo)) / 200_000) ** (1.0 / 3.0))
    xs, ys, zs = _grid_axes(shape, lo, hi, h, "interior fill")
    inside = shape.inside_grid(xs, ys, zs)
    d_est = ndimage.distance_transform_edt(inside, sampling=h) - 0.5 * h
    covered = np.zeros(inside.shape, dtype=bool)
    for c, r in zip(centres, radii, strict=True):
        _mark_ball(covered, xs, ys, zs, h, c, r)
    todo = np.flatnonzero(inside & ~covered & (d_est >= threshold))
    if len(todo) == 0:
        return
    todo = todo[np.argsort(-d_est.ravel()[todo], kind="stable")]
    cov_flat = covered.reshape(-1)
    for v in todo:
        if cov_flat[v]:
            continue
        i3 = np.unravel_index(v, inside.shape)
        c = np.array([xs[i3[0]], ys[i3[1]], zs[i3[2]]])
        r = float(shape.depth(c[None, :])[0])
        if r >= threshold:
            centres.append(c)
            radii.append(r)
            _mark_ball(covered, xs, ys, zs, h, c, r)


def _mark_ball(covered: np.ndarray, xs, ys, zs, h: float, c: np.ndarray, r: float) -> None:
    sl = []
    for ax, v in zip((xs, ys, zs), c, strict=True):
        a = max(0, int(math.floor((v - r - ax[0]) / h)))
        b = min(len(ax), int(math.ceil((v + r - ax[0]) / h)) + 1)
        sl.append(slice(a, b))
    dx = (xs[sl[0]] - c[0]) ** 2
    dy = (ys[sl[1]] - c[1]) ** 2
    dz = (zs[sl[2]] - c[2]) ** 2
    ball = dx[:, None, None] + dy[None, :, None] + dz[None, None, :] <= r * r
    covered[sl[0], sl[1], sl[2]] |= ball
