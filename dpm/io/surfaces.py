"""Triangle surfaces of the boundaries, for viewing (ParaView) and pictures.

:func:`boundary_surface` gives a boundary's surface as triangles in its own frame (the
world frame at t = 0; a frame row of :func:`dpm.motion.frames` moves it:
x = o + R x_local). A boundary may give its own (``surface(extent)``: the box its six
faces, a mesh its triangles); otherwise the surface is drawn from its contact primitives
(:mod:`dpm.kernels.boundary_geometry`), each kind by :func:`primitive_surface`:

- plane: a square of half side ``extent`` about the point of the plane nearest the
  scene's centre (the plane is infinite; the square covers the scene);
- slab (finite wall): its six faces; triangle: itself (a plate of thickness: its mid
  surface);
- surface of revolution (tube, cone, annulus, disc): the meridian segment revolved,
  ``SEGMENTS`` facets around; torus segment (bend): the pipe swept along the bend;
- sieve plate: the plate with its holes (square holes; round ones drawn square).

Only geometry: contact treats the primitives, not these triangles.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..kernels.boundary_geometry import AXI, PLANE, SIEVE, SLAB, TORUS, TRIANGLE

#: facets around a surface of revolution, and along a bend per radian
SEGMENTS = 48


def _frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to the unit vector n and to each other."""
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def _grid(rows: int, cols: int, closed: bool) -> np.ndarray:
    """Faces of a (rows x cols) vertex grid, two triangles per quad; ``closed``: the
    last column joins the first."""
    faces = []
    ncol = cols if closed else cols - 1
    for i in range(rows - 1):
        for j in range(ncol):
            a, b = i * cols + j, i * cols + (j + 1) % cols
            c, d = a + cols, b + cols
            faces += [(a, b, d), (a, d, c)]
    return np.asarray(faces, np.int64).reshape(-1, 3)


def _quad(c: np.ndarray, u: np.ndarray, v: np.ndarray, a: float, b: float):
    """A rectangle c + s a u + t b v, s, t in [-1, 1]: 4 vertices, 2 faces."""
    verts = np.array([c - a * u - b * v, c + a * u - b * v, c + a * u + b * v,
                      c - a * u + b * v])
    return verts, np.array([[0, 1, 2], [0, 2, 3]], np.int64)


def _box(c: np.ndarray, u: np.ndarray, v: np.ndarray, w: np.ndarray,
         half: tuple[float, float, float]):
    """The six faces of the box c + s u + t v + r w, |s|, |t|, |r| <= half."""
    a, b, h = half
    signs = np.array([[sx, sy, sz] for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)])
    verts = c + signs[:, :1] * a * u + signs[:, 1:2] * b * v + signs[:, 2:] * h * w
    faces = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                      [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]],
                     np.int64)
    return verts, faces


def primitive_surface(kind: int, par: np.ndarray, extent: float,
                      centre: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3), faces (m, 3)) of one primitive in its boundary's frame;
    ``extent``/``centre``: the half size and the centre of the region an unbounded plane
    is drawn over."""
    p = np.asarray(par, float)
    if kind == PLANE:
        n = p[3:6] / np.linalg.norm(p[3:6])
        c0 = np.zeros(3) if centre is None else np.asarray(centre, float)
        c = c0 - ((c0 - p[0:3]) @ n) * n
        u, v = _frame(n)
        return _quad(c, u, v, extent, extent)
    if kind == SLAB:
        u, v = p[3:6], p[6:9]
        w = np.cross(u, v)
        if p[11] > 0:
            return _box(p[0:3], u, v, w, (p[9], p[10], p[11]))
        return _quad(p[0:3], u, v, p[9], p[10])
    if kind == TRIANGLE:
        return p[0:9].reshape(3, 3).copy(), np.array([[0, 1, 2]], np.int64)
    if kind == AXI:
        o, a = p[0:3], p[3:6] / np.linalg.norm(p[3:6])
        u, v = _frame(a)
        phi = np.arange(SEGMENTS) * (2 * np.pi / SEGMENTS)
        ring = np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v
        rows = [o + z * a + rho * ring for rho, z in ((p[6], p[7]), (p[8], p[9]))]
        return np.concatenate(rows), _grid(2, SEGMENTS, closed=True)
    if kind == TORUS:
        c, ax, e1 = p[0:3], p[3:6], p[6:9]
        e2 = np.cross(ax, e1)
        big, rp, theta = p[9], p[10], p[11]
        nphi = max(2, int(np.ceil(SEGMENTS * theta / (2 * np.pi))) + 1)
        psi = np.arange(SEGMENTS) * (2 * np.pi / SEGMENTS)
        verts = []
        for phi in np.linspace(0.0, theta, nphi):
            radial = np.cos(phi) * e1 + np.sin(phi) * e2
            verts.append(c + (big + rp * np.cos(psi))[:, None] * radial
                         + (rp * np.sin(psi))[:, None] * ax)
        return np.concatenate(verts), _grid(nphi, SEGMENTS, closed=True)
    if kind == SIEVE:
        return _sieve(p)
    return np.zeros((0, 3)), np.zeros((0, 3), np.int64)


def _sieve(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plate of a hole-model sieve: bars between square holes of width wh at pitch
    p about the centre (holes at c + (i u + j v) p), within the half extents."""
    c, u, v, a, b, wh, pitch = p[0:3], p[3:6], p[6:9], p[9], p[10], p[12], p[13]
    half = 0.5 * wh

    def cuts(extent):
        k = np.arange(-np.floor(extent / pitch), np.floor(extent / pitch) + 1)
        edges = [-extent]
        for m in k:
            lo, hi = m * pitch - half, m * pitch + half
            if lo > -extent and hi < extent:
                edges += [lo, hi]
        return np.asarray(edges + [extent])

    su, sv = cuts(a), cuts(b)
    verts, faces = [], []
    for i in range(len(su) - 1):
        for j in range(len(sv) - 1):
            if i % 2 == 1 and j % 2 == 1:
                continue  # a hole
            s0, s1, t0, t1 = su[i], su[i + 1], sv[j], sv[j + 1]
            k = len(verts)
            verts += [c + s0 * u + t0 * v, c + s1 * u + t0 * v, c + s1 * u + t1 * v,
                      c + s0 * u + t1 * v]
            faces += [(k, k + 1, k + 2), (k, k + 2, k + 3)]
    return np.asarray(verts).reshape(-1, 3), np.asarray(faces, np.int64).reshape(-1, 3)


def boundary_surface(bd: Any, extent: float = 1.0, centre: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3), faces (m, 3)) of boundary ``bd`` in its own frame: its own
    ``surface(extent)`` if it has one, else the union of its primitives' surfaces."""
    own = getattr(bd, "surface", None)
    if callable(own):
        v, f = own(extent)
        return np.asarray(v, float).reshape(-1, 3), np.asarray(f, np.int64).reshape(-1, 3)
    if not hasattr(bd, "primitives"):  # (no geometry to draw)
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    prims = bd.primitives()
    verts, faces, n = [], [], 0
    for k in range(len(prims.kind)):
        v, f = primitive_surface(int(prims.kind[k]), prims.par[k], extent, centre)
        verts.append(v)
        faces.append(f + n)
        n += len(v)
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.concatenate(verts), np.concatenate(faces)


def world(vertices: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Vertices moved by a frame row (o [0:3], R row-major [3:12]): x = o + R x_local."""
    return frame[0:3] + vertices @ frame[3:12].reshape(3, 3).T
