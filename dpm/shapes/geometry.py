"""Geometry helpers of the clustered shapes: principal frames, distances, voxelisation.

Plain numpy (no numba: the kernel layer is ``dpm/kernels`` only). Everything here is
deterministic: no random numbers, fixed tie rules.
"""

from __future__ import annotations

import numpy as np

#: relative tolerance below which two principal moments count as equal
DEGENERATE_RTOL = 1e-7


# ------------------------------------------------------------------ principal frame
def principal_frame(tensor: np.ndarray,
                    rtol: float = DEGENERATE_RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending) and axes of a symmetric inertia tensor.

    Returns ``(moments, R)`` with ``R`` a proper rotation (det +1) whose columns are the
    principal axes written in the tensor's frame, so ``R.T @ tensor @ R = diag(moments)``
    and a vector in the principal frame maps to the tensor's frame as ``R @ v``.

    Deterministic rules: moments ascending; within a group of equal moments (relative
    difference below ``rtol``) the axes are the tensor frame's own axes projected onto the
    group's subspace, taken in axis order (x before y before z) and orthonormalised, so a
    cylinder along x keeps x, y, z; each axis is signed so that its largest component is
    positive (first one on a tie); the third axis is the cross product of the first two.
    """
    t = np.asarray(tensor, dtype=float)
    t = 0.5 * (t + t.T)
    w, v = np.linalg.eigh(t)
    scale = max(float(np.max(np.abs(w))), 1e-300)
    groups: list[list[int]] = []
    for i in range(3):
        if groups and w[i] - w[groups[-1][0]] <= rtol * scale:
            groups[-1].append(i)
        else:
            groups.append([i])
    axes = v.copy()
    for g in groups:
        if len(g) == 1:
            continue
        basis = v[:, g]
        proj = basis @ basis.T  # projector onto the degenerate subspace
        chosen: list[np.ndarray] = []
        norms = np.linalg.norm(proj, axis=0)
        for k in np.argsort(-norms, kind="stable"):
            u = proj[:, k].copy()
            for c in chosen:
                u -= (u @ c) * c
            n = np.linalg.norm(u)
            if n > 1e-6:
                chosen.append(u / n)
            if len(chosen) == len(g):
                break
        # order the group's axes by the shape axis each is closest to
        chosen.sort(key=lambda c: int(np.argmax(np.abs(c) > np.max(np.abs(c)) - 1e-9)))
        for slot, c in zip(g, chosen, strict=True):
            axes[:, slot] = c
    for i in range(2):
        col = axes[:, i]
        m = np.abs(col)
        k = int(np.argmax(m >= m.max() - 1e-9))
        if col[k] < 0:
            axes[:, i] = -col
    axes[:, 2] = np.cross(axes[:, 0], axes[:, 1])
    axes[:, 2] /= np.linalg.norm(axes[:, 2])
    moments = np.einsum("ji,jk,ki->i", axes, t, axes)
    return moments, axes


def quaternion_from_matrix(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a proper rotation matrix (Shepperd)."""
    r = np.asarray(r, dtype=float)
    tr = np.trace(r)
    diag = np.array([tr, r[0, 0], r[1, 1], r[2, 2]])
    k = int(np.argmax(diag))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif k == 1:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif k == 2:
        s = 2.0 * np.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * np.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    q = np.asarray(q)
    q /= np.linalg.norm(q)
    return -q if q[0] < 0 else q


def matrix_from_quaternion(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def inertia_from_second_moment(s: np.ndarray) -> np.ndarray:
    """Inertia tensor from the second moment S = int x x^T dV: I = tr(S) 1 - S."""
    return np.trace(s) * np.eye(3) - s


# ------------------------------------------------------------------ distances
def _chunks(n_rows: int, n_cols: int, budget: int = 2_000_000):
    step = max(1, budget // max(n_cols, 1))
    for i in range(0, n_rows, step):
        yield slice(i, min(n_rows, i + step))


def segment_distance_2d(points: np.ndarray, seg_a: np.ndarray, seg_b: np.ndarray) -> np.ndarray:
    """Distance of each 2-D point (P, 2) to the nearest of the segments a->b (S, 2)."""
    p = np.asarray(points, dtype=float)
    out = np.empty(len(p))
    d = seg_b - seg_a
    dd = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
    for sl in _chunks(len(p), len(seg_a)):
        ap = p[sl, None, :] - seg_a[None, :, :]
        t = np.clip(np.einsum("psk,sk->ps", ap, d) / dd, 0.0, 1.0)
        diff = ap - t[..., None] * d
        out[sl] = np.sqrt(np.min(np.einsum("psk,psk->ps", diff, diff), axis=1))
    return out


def triangle_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distance of each point (P, 3) to the nearest triangle of ``triangles`` (F, 3, 3).

    Exact closest point on a triangle (Ericson, Real-Time Collision Detection 5.1.5),
    evaluated only for the triangles whose bounding sphere may hold the nearest point:
    |p - centre| - R <= min over triangles of (|p - centre| + R).
    """
    p = np.asarray(points, dtype=float)
    tri = np.asarray(triangles, dtype=float)
    cen = tri.mean(axis=1)
    rad = np.linalg.norm(tri - cen[:, None, :], axis=2).max(axis=1)
    out = np.empty(len(p))
    for sl in _chunks(len(p), len(tri), 1_000_000):
        q = p[sl]
        dc = np.sqrt(np.maximum(
            np.einsum("ij,ij->i", q, q)[:, None] - 2.0 * q @ cen.T
            + np.einsum("ij,ij->i", cen, cen)[None], 0.0))
        ub = (dc + rad[None]).min(axis=1)
        pi, fi = np.nonzero(dc - rad[None] <= ub[:, None] * (1 + 1e-9) + 1e-300)
        near = _closest_on_triangles(q[pi], tri[fi, 0], tri[fi, 1], tri[fi, 2])
        d = np.linalg.norm(q[pi] - near, axis=1)
        res = np.full(len(q), np.inf)
        np.minimum.at(res, pi, d)
        out[sl] = res
    return out


def _closest_on_triangles(p, a, b, c):
    ab, ac = b - a, c - a
    ap, bp, cp = p - a, p - b, p - c
    d1 = np.einsum("...k,...k->...", ab, ap)
    d2 = np.einsum("...k,...k->...", ac, ap)
    d3 = np.einsum("...k,...k->...", ab, bp)
    d4 = np.einsum("...k,...k->...", ac, bp)
    d5 = np.einsum("...k,...k->...", ab, cp)
    d6 = np.einsum("...k,...k->...", ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        denom = np.where(denom == 0, 1.0, denom)
        v = vb / denom
        w = vc / denom
        q = a + ab * v[..., None] + ac * w[..., None]
        # edge BC
        e1, e2 = d4 - d3, d5 - d6
        wbc = e1 / np.where(e1 + e2 == 0, 1.0, e1 + e2)
        m = (va <= 0) & (e1 >= 0) & (e2 >= 0)
        q = np.where(m[..., None], b + (c - b) * wbc[..., None], q)
        # edge AC
        wac = d2 / np.where(d2 - d6 == 0, 1.0, d2 - d6)
        m = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
        q = np.where(m[..., None], a + ac * wac[..., None], q)
        # vertex C
        m = (d6 >= 0) & (d5 <= d6)
        q = np.where(m[..., None], c, q)
        # edge AB
        vab = d1 / np.where(d1 - d3 == 0, 1.0, d1 - d3)
        m = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
        q = np.where(m[..., None], a + ab * vab[..., None], q)
        # vertex B
        m = (d3 >= 0) & (d4 <= d3)
        q = np.where(m[..., None], b, q)
        # vertex A
        m = (d1 <= 0) & (d2 <= 0)
        q = np.where(m[..., None], a, q)
    return q


def ellipsoid_depth(points: np.ndarray, semi_axes: np.ndarray) -> np.ndarray:
    """Distance from points inside an axis-aligned ellipsoid to its surface.

    Solves for the closest surface point x_i = a_i^2 y_i / (a_i^2 + t) with the root t of
    sum (a_i y_i / (a_i^2 + t))^2 = 1 by bisection (Eberly, "Distance from a point to an
    ellipse, an ellipsoid, or a hyperellipsoid"); components on a symmetry plane are
    nudged by 1e-9 of the smallest axis (the distance is 1-Lipschitz, so the result moves
    by at most that much).
    """
    e = np.asarray(semi_axes, dtype=float)
    y = np.abs(np.asarray(points, dtype=float))
    y = np.maximum(y, 1e-9 * e.min())
    e2 = e**2
    lo = np.full(len(y), -e2.min()) + 1e-300
    # for inside points the root lies in (-min a^2, 0]
    hi = np.zeros(len(y))
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        f = np.sum((e * y / (e2 + mid[:, None])) ** 2, axis=1) - 1.0
        up = f > 0
        lo = np.where(up, mid, lo)
        hi = np.where(up, hi, mid)
        if np.all(hi - lo <= 1e-15 * e2.max()):
            break
    t = 0.5 * (lo + hi)
    x = e2 * y / (e2 + t[:, None])
    # put the foot point exactly on the surface: the distance error becomes second order
    x /= np.sqrt(np.sum((x / e) ** 2, axis=1))[:, None]
    return np.linalg.norm(x - y, axis=1)


# ------------------------------------------------------------------ voxelisation
def mesh_inside_grid(triangles: np.ndarray, xs: np.ndarray, ys: np.ndarray,
                     zs: np.ndarray) -> np.ndarray:
    """Inside test of a closed triangle mesh on the grid xs x ys x zs (ray parity along z).

    For every grid column (x_i, y_j) the crossings of the vertical line with the triangles
    are counted below each voxel centre; an odd count is inside. The grid should be
    offset by an irrational fraction of its spacing so that no line passes exactly through
    an edge or a vertex.
    """
    tri = np.asarray(triangles, dtype=float)
    nx, ny, nz = len(xs), len(ys), len(zs)
    hx, hy = xs[1] - xs[0], ys[1] - ys[0]
    tx, ty = tri[:, :, 0], tri[:, :, 1]
    i0 = np.clip(np.ceil((tx.min(1) - xs[0]) / hx), 0, nx).astype(np.int64)
    i1 = np.clip(np.floor((tx.max(1) - xs[0]) / hx), -1, nx - 1).astype(np.int64)
    j0 = np.clip(np.ceil((ty.min(1) - ys[0]) / hy), 0, ny).astype(np.int64)
    j1 = np.clip(np.floor((ty.max(1) - ys[0]) / hy), -1, ny - 1).astype(np.int64)
    ni = np.maximum(i1 - i0 + 1, 0)
    nj = np.maximum(j1 - j0 + 1, 0)
    cnt = ni * nj
    toggles = np.zeros((nx, ny, nz + 1), dtype=np.int32)
    total = int(cnt.sum())
    if total == 0:
        return np.zeros((nx, ny, nz), dtype=bool)
    step = 4_000_000
    starts = np.concatenate([[0], np.cumsum(cnt)])
    # candidate (triangle, column) pairs, processed in bounded batches of triangles
    f = 0
    while f < len(tri):
        g = int(np.searchsorted(starts, starts[f] + step, side="right")) - 1
        g = max(g, f + 1)
        sel = np.arange(f, min(g, len(tri)))
        c = cnt[sel]
        t_idx = np.repeat(sel, c)
        local = np.arange(int(c.sum())) - np.repeat(np.cumsum(c) - c, c)
        nj_r = np.repeat(nj[sel], c)
        ii = np.repeat(i0[sel], c) + local // np.maximum(nj_r, 1)
        jj = np.repeat(j0[sel], c) + local % np.maximum(nj_r, 1)
        qx, qy = xs[ii], ys[jj]
        a, b, cc = tri[t_idx, 0], tri[t_idx, 1], tri[t_idx, 2]
        wa = (cc[:, 0] - b[:, 0]) * (qy - b[:, 1]) - (cc[:, 1] - b[:, 1]) * (qx - b[:, 0])
        wb = (a[:, 0] - cc[:, 0]) * (qy - cc[:, 1]) - (a[:, 1] - cc[:, 1]) * (qx - cc[:, 0])
        wc = (b[:, 0] - a[:, 0]) * (qy - a[:, 1]) - (b[:, 1] - a[:, 1]) * (qx - a[:, 0])
        hit = ((wa > 0) & (wb > 0) & (wc > 0)) | ((wa < 0) & (wb < 0) & (wc < 0))
        s = wa + wb + wc
        z = (wa * a[:, 2] + wb * b[:, 2] + wc * cc[:, 2])[hit] / s[hit]
        kk = np.searchsorted(zs, z, side="right")
        np.add.at(toggles, (ii[hit], jj[hit], kk), 1)
        f = int(sel[-1]) + 1
    return (np.cumsum(toggles[:, :, :nz], axis=2) % 2).astype(bool)
