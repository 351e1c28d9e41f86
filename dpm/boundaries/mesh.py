"""Triangle-mesh boundary: any STL/OBJ/PLY that trimesh reads, or vertex/face arrays."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..kernels.boundary_geometry import TRIANGLE
from ..parameters import Parameter, numeric_array, shown
from .base import Boundary, Primitives

#: dihedral angle [rad] below which an edge counts as flat (inactive)
FLAT_ANGLE = 1e-6
#: a face whose area is at most this times its longest edge squared is degenerate (its
#: vertices on a line up to rounding, float32 rounding included: STL stores float32; a
#: height under 2e-6 of its longest edge) and dropped
DEGENERATE = 1e-6


def rotation_matrix(call: str, spec: Any) -> np.ndarray:
    """The 3x3 matrix of a mesh's ``rotate``: None (identity), ``(ax, ay, az, degrees)``,
    a list of those (the first applied first), or a proper rotation matrix."""
    allowed = "allowed: (ax, ay, az, degrees), a list of them, or a 3x3 rotation matrix"
    if spec is None:
        return np.eye(3)
    if isinstance(spec, np.ndarray):
        spec = spec.tolist()  # (named on one line)
    try:
        a = np.asarray(spec, float)
    except (TypeError, ValueError):
        raise ParameterError(f"{call}: rotate={shown(spec)}; {allowed}") from None
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"{call}: rotate={shown(spec)} is not finite; {allowed}")
    if a.shape == (3, 3):
        if not (np.allclose(a @ a.T, np.eye(3), atol=1e-9) and np.linalg.det(a) > 0):
            raise ParameterError(f"{call}: rotate={shown(spec)} is not a rotation matrix "
                                 "(orthonormal, determinant +1)")
        return a
    if a.shape == (4,):
        a = a[None]
    if a.ndim != 2 or a.shape[1] != 4:
        raise ParameterError(f"{call}: rotate={shown(spec)}; {allowed}")
    r = np.eye(3)
    for ax, ay, az, deg in a:
        n = np.array([ax, ay, az])
        norm = float(np.linalg.norm(n))
        if norm == 0.0:
            raise ParameterError(f"{call}: rotate={shown(spec)} has a zero axis; {allowed}")
        n /= norm
        t = np.radians(deg)
        k = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
        r = (np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k) @ r  # (Rodrigues)
    return r


class Mesh(Boundary):
    """A triangle mesh from ``file`` (read by trimesh) or from ``vertices`` (n, 3) and
    ``faces`` (m, 3), in the file's units scaled by ``scale`` (1e-3: a CAD file in mm),
    then turned by ``rotate`` about the file's origin, then shifted by ``translate`` [m]:
    x = R (scale x_file) + translate. ``rotate`` is ``(ax, ay, az, degrees)`` (right-handed
    about the axis), a list of those applied in order (LIGGGHTS' ``rotate axis ... angle``
    repeated), or a 3x3 rotation matrix. ``thickness`` makes each triangle a plate
    (default 0, a surface).

    Contact (kernel kind TRIANGLE): closest point of each triangle within reach of the
    sphere (Ericson 2005), both sides. Shared edges and vertices are counted once
    (:mod:`dpm.kernels.mesh_contact`): an edge between coplanar or concave neighbours
    (seen from the side the face normals point to) and a vertex with only such edges are
    inactive, so a sphere rolling over a flat meshed floor feels exactly the plane force.
    Edges of one face only (open borders) and convex edges are active. Triangles are
    found through a uniform grid in the mesh's frame, so the search cost per sphere does not
    grow with the triangle count. Degenerate faces (zero area, up to ``DEGENERATE``) are
    dropped; a mesh with
    no face of non-zero area left, a missing or unreadable file, or non-finite vertices is
    refused.

    ``side`` says where the particles belong, checked before the first step (particles
    on the wrong side are refused, as for the other boundaries): ``"auto"`` (default) for
    a closed (watertight) mesh the side its face normals point to, which is the side the
    contact treatment of its edges assumes (outward normals, positive volume: an obstacle,
    particles outside; inward normals: a container, particles inside), and anywhere for an
    open mesh; ``"inside"`` or ``"outside"`` of a closed mesh; ``"both"`` no check.
    Inside is decided by the generalised winding number of the triangles at each centre.
    """

    name = "mesh"
    parameters = {
        "file": Parameter(default=None, kind="any", doc="path of an STL/OBJ/PLY file"),
        "vertices": Parameter(default=None, kind="any", unit="m"),
        "faces": Parameter(default=None, kind="any"),
        "scale": Parameter(default=1.0, low=0.0, low_open=True),
        "translate": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "rotate": Parameter(default=None, kind="any",
                            doc="(ax, ay, az, degrees), a list of them, or a 3x3 matrix"),
        "thickness": Parameter(default=0.0, low=0.0, unit="m"),
        "side": Parameter(default="auto", kind="str",
                          doc="where the particles belong: auto, inside, outside, both"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "Mesh()"
        p = self.params
        import trimesh

        if (p["file"] is None) == (p["vertices"] is None):
            raise ParameterError(f"{call}: give either file or vertices and faces")
        if p["side"] not in SIDES:
            raise ParameterError(f"{call}: side={p['side']!r}; allowed: {', '.join(SIDES)}")
        if p["file"] is not None:
            tm = load_mesh(call, p["file"])
            what = f"file={str(p['file'])!r}"
        else:
            v = numeric_array(p["vertices"])
            f = numeric_array(p["faces"]) if p["faces"] is not None else None
            if v is None or v.ndim != 2 or v.shape[1] != 3 or f is None or f.ndim != 2 \
                    or f.shape[1] != 3:
                raise ParameterError(f"{call}: vertices must be (n, 3) and faces (m, 3) "
                                     f"numbers (got {_shape(p['vertices'])} and "
                                     f"{_shape(p['faces'])})")
            if not np.all(np.isfinite(v)):
                raise ParameterError(f"{call}: vertices contain NaN or inf")
            if np.any(f != np.round(f)):
                raise ParameterError(f"{call}: faces must be integer vertex indices")
            f = f.astype(np.int64)
            if f.size and (f.min() < 0 or f.max() >= len(v)):
                raise ParameterError(f"{call}: faces index vertices 0..{len(v) - 1}; got "
                                     f"{f.min()}..{f.max()}")
            tm = trimesh.Trimesh(v, f, process=False)
            what = "vertices/faces"
        if not np.all(np.isfinite(tm.vertices)):
            raise ParameterError(f"{call}: {what}: the mesh has NaN or inf vertices")
        tm.merge_vertices()
        tri = tm.triangles
        longest = np.max(np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2), axis=1)
        keep = tm.area_faces > DEGENERATE * longest**2
        tm.update_faces(keep)
        if len(tm.faces) == 0:
            raise ParameterError(f"{call}: {what}: the mesh has no triangle of non-zero area "
                                 "(degenerate: zero faces or zero area)")
        if p["side"] in ("inside", "outside") and not tm.is_watertight:
            raise ParameterError(f"{call}: side={p['side']!r} needs a closed (watertight) "
                                 "mesh; this one has open edges (use side='both')")
        self._trimesh = tm
        # (the cleaned mesh in its own frame: what a checkpoint keeps of it, plain arrays)
        self._mesh = (np.array(tm.vertices, float), np.array(tm.faces, np.int64))
        self.rotation = rotation_matrix(call, p["rotate"])
        self.vertices = (np.asarray(tm.vertices, float) * float(p["scale"])) @ self.rotation.T \
            + np.asarray(p["translate"], float)
        self.faces = np.asarray(tm.faces, np.int64)
        self.h = 0.5 * float(p["thickness"])
        #: where the particles belong ("inside", "outside" or None: anywhere)
        self.side = p["side"]
        if self.side == "auto":
            self.side = (None if not tm.is_watertight
                         else "outside" if tm.volume > 0 else "inside")
        elif self.side == "both":
            self.side = None

    @property
    def trimesh(self) -> Any:
        """The cleaned mesh (merged vertices, degenerate faces dropped) as a trimesh, in
        its own frame (before scale, rotate, translate)."""
        tm = self.__dict__.get("_trimesh")
        if tm is None:  # (restored from a checkpoint: built again from its arrays)
            import trimesh

            tm = self._trimesh = trimesh.Trimesh(*self._mesh, process=False)
        return tm

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state.pop("_trimesh", None)
        return state

    def outside(self, position: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """Particles whose centre lies on the wrong side of a closed mesh (see ``side``);
        none for an open mesh or ``side="both"``."""
        position = np.asarray(position, float)
        if self.side is None or len(position) == 0:
            return np.zeros(len(position), bool)
        inside = contains(self.vertices, self.faces, position)
        return ~inside if self.side == "inside" else inside

    def surface(self, extent: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, faces) for viewing: the mesh itself (its mid surface)."""
        return self.vertices, self.faces

    def volume(self) -> float:
        """Enclosed volume [m3] of a watertight mesh; else the surface area times the
        thickness."""
        if self.trimesh.is_watertight:
            return float(abs(self.trimesh.volume)) * float(self.params["scale"]) ** 3
        area = float(self.trimesh.area) * float(self.params["scale"]) ** 2
        return area * 2.0 * self.h

    def feature_flags(self) -> np.ndarray:
        """Per face: bits 0-2 edge k active (v_k v_k+1), bits 3-5 vertex k active."""
        return feature_flags(self.trimesh, self.faces, len(self.vertices))

    def primitives(self) -> Primitives:
        return triangle_primitives(self.vertices, self.faces, self.h, self.feature_flags())


SIDES = ("auto", "inside", "outside", "both")


def _shape(value) -> str:
    try:
        return str(np.shape(value))
    except (TypeError, ValueError):
        return type(value).__name__


def check_stl(call: str, name: str, file) -> None:
    """Refuse, without reading it, a binary STL file whose size is not the 84 + 50 n bytes
    its header's triangle count n says (ParameterError naming ``name=file``, the count and
    both sizes); other files, ASCII STL (``solid`` and text at the start) included, pass."""
    path = Path(str(file))
    if path.suffix.lower() != ".stl" or not path.is_file():
        return
    size = path.stat().st_size
    with path.open("rb") as f:
        head = f.read(512)
    ascii_stl = head.lstrip(b"\xef\xbb\xbf \t\r\n")[:5].lower() == b"solid"
    if size < 84 or (ascii_stl and b"\0" not in head):
        return
    count = int.from_bytes(head[80:84], "little")
    if size != 84 + 50 * count:
        raise ParameterError(
            f"{call}: {name}={str(file)!r} is a binary STL whose header claims {count:,} "
            f"triangles, {84 + 50 * count:,} bytes, but the file has {size:,} bytes; "
            "allowed: a binary STL of 84 + 50 x (its triangle count) bytes, or an ASCII "
            "STL (starting with 'solid')")


def load_mesh(call: str, file):
    """Read ``file`` with trimesh as one mesh; ParameterError naming the file and the
    reason when it is missing, unreadable, a binary STL of the wrong size
    (:func:`check_stl`) or holds no triangles."""
    import trimesh

    path = Path(str(file))
    if not path.is_file():
        raise ParameterError(f"{call}: file={str(file)!r} does not exist"
                             + (" (it is a directory)" if path.is_dir() else ""))
    check_stl(call, "file", file)
    try:
        tm = trimesh.load(str(path), force="mesh")
    except Exception as exc:  # trimesh raises many kinds
        raise ParameterError(f"{call}: file={str(file)!r} could not be read as a mesh: "
                             f"{type(exc).__name__}: {exc}") from None
    if not isinstance(tm, trimesh.Trimesh) or len(tm.faces) == 0:
        raise ParameterError(f"{call}: file={str(file)!r} holds no triangles (empty or not "
                             "a mesh file trimesh reads: STL, OBJ, PLY, ...)")
    return tm


#: points per block of the winding-number sum (a block's work is points x triangles)
CONTAINS_BLOCK = 1 << 20


def contains(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Mask of the points inside the closed triangle mesh (generalised winding number:
    the solid angles of the triangles seen from the point sum to +-4 pi inside, 0 outside;
    Van Oosterom and Strackee 1983, Jacobson et al. 2013). Only points in the mesh's
    bounding box are summed, in blocks."""
    points = np.asarray(points, float)
    out = np.zeros(len(points), bool)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    cand = np.flatnonzero(np.all((points >= lo) & (points <= hi), axis=1))
    tri = vertices[faces]  # (m, 3, 3)
    step = max(1, CONTAINS_BLOCK // max(1, len(faces)))
    for s in range(0, len(cand), step):
        idx = cand[s:s + step]
        d = tri[None] - points[idx][:, None, None, :]  # (k, m, 3, 3)
        a, b, c = d[:, :, 0], d[:, :, 1], d[:, :, 2]
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        det = np.einsum("kmj,kmj->km", a, np.cross(b, c))
        den = (la * lb * lc + np.einsum("kmj,kmj->km", a, b) * lc
               + np.einsum("kmj,kmj->km", b, c) * la + np.einsum("kmj,kmj->km", c, a) * lb)
        w = np.sum(np.arctan2(det, den), axis=1) / (2.0 * np.pi)
        out[idx] = np.abs(w) > 0.5
    return out


def feature_flags(tm, faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """Per face of the trimesh ``tm``: bits 0-2 edge k active (v_k v_k+1) and bits 3-5
    vertex k active, seen from the side the face normals point to (the front); bits 6-8
    and 9-11 the same seen from behind (see :class:`Mesh`). An edge between two faces is
    active on a side where it is convex: an edge convex from the front is concave from
    behind and the other way round, so a sphere touching a fold from its back (a
    two-sided chute hit from below) finds the edge that the front's rules leave to the
    faces. Open borders and non-manifold edges are active on both sides, edges between
    coplanar faces on neither; a vertex is active on a side where one of its edges is."""
    count: dict[tuple[int, int], int] = {}
    for f in faces:
        for k in range(3):
            e = tuple(sorted((int(f[k]), int(f[(k + 1) % 3]))))
            count[e] = count.get(e, 0) + 1
    # open borders (1) and non-manifold edges (>2) stay active on both sides
    front = {e: c != 2 for e, c in count.items()}
    back = dict(front)
    if len(tm.face_adjacency):
        edges = np.sort(tm.face_adjacency_edges, axis=1)
        angles = tm.face_adjacency_angles
        convex = tm.face_adjacency_convex
        for (a, b), ang, cvx in zip(edges, angles, convex, strict=True):
            e = (int(a), int(b))
            if count.get(e) == 2:
                front[e] = bool(cvx and ang > FLAT_ANGLE)
                back[e] = bool(not cvx and ang > FLAT_ANGLE)
    flags = np.zeros(len(faces), np.int64)
    for shift, active in ((0, front), (6, back)):
        vertex_active = np.zeros(n_vertices, bool)
        for (a, b), on in active.items():
            if on:
                vertex_active[a] = vertex_active[b] = True
        for n, f in enumerate(faces):
            bits = 0
            for k in range(3):
                if active[tuple(sorted((int(f[k]), int(f[(k + 1) % 3]))))]:
                    bits |= 1 << k
                if vertex_active[f[k]]:
                    bits |= 1 << (3 + k)
            flags[n] |= bits << shift
    return flags


def triangle_duals(v: np.ndarray) -> np.ndarray:
    """(m, 6): the dual in-plane vectors g1, g2 of triangles ``v`` (m, 3, 3), g_i . e_j =
    delta_ij for the edges e1 = v1 - v0, e2 = v2 - v0 and g_i in their plane, so that a
    point's barycentric coordinates are two dot products (the kernel's face test, see
    :mod:`dpm.kernels.boundary_geometry`). Zero for a degenerate triangle: the kernel then
    takes the general closest-point path."""
    e1 = v[:, 1] - v[:, 0]
    e2 = v[:, 2] - v[:, 0]
    a = np.einsum("ij,ij->i", e1, e1)
    b = np.einsum("ij,ij->i", e1, e2)
    c = np.einsum("ij,ij->i", e2, e2)
    det = a * c - b * b
    ok = det > 1e-24 * np.maximum(a * c, 1e-300)
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)[:, None]
    g1 = (c[:, None] * e1 - b[:, None] * e2) * inv
    g2 = (a[:, None] * e2 - b[:, None] * e1) * inv
    return np.concatenate([g1, g2], axis=1)


def smallest_altitudes(duals: np.ndarray) -> np.ndarray:
    """(m,): each triangle's smallest altitude from its duals (m, 6) of
    :func:`triangle_duals`: 1 / |g| for g = g1, g2, g1 + g2 (the gradients of the
    barycentric coordinates s, t and s + t). Zero for a degenerate triangle, whose duals
    are zero: the kernel's distance bound then rests on the height over its plane alone."""
    g1, g2 = duals[:, 0:3], duals[:, 3:6]
    big = np.max(np.stack([np.linalg.norm(g1, axis=1), np.linalg.norm(g2, axis=1),
                           np.linalg.norm(g1 + g2, axis=1)]), axis=0)
    return np.where(big > 0.0, 1.0 / np.where(big > 0.0, big, 1.0), 0.0)


def triangle_primitives(vertices: np.ndarray, faces: np.ndarray, h: float,
                        flags: np.ndarray) -> Primitives:
    """TRIANGLE primitives of a mesh with half thickness ``h`` and feature ``flags``."""
    v = vertices[faces]  # (m, 3, 3)
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    m = len(faces)
    par = np.zeros((m, 20))
    par[:, 0:9] = v.reshape(m, 9)
    par[:, 9] = h
    par[:, 10:13] = n
    par[:, 13:19] = triangle_duals(v)
    par[:, 19] = smallest_altitudes(par[:, 13:19])
    ids = np.zeros((m, 4), np.int64)
    ids[:, :3] = faces
    ids[:, 3] = flags
    lower = v.min(axis=1) - h
    upper = v.max(axis=1) + h
    extent = float(np.max(np.linalg.norm(vertices, axis=1))) + h
    return Primitives(np.full(m, TRIANGLE, np.int64), par, ids, lower, upper,
                      extent if math.isfinite(extent) else math.inf)
