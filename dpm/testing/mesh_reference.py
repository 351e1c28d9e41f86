"""A brute-force reference for the contacts of spheres with triangle meshes.

The step kernels find a sphere's triangle contacts through the boundary list (candidates
within reach, kept between rebuilds), a face test by dual in-plane vectors, a distance
bound that skips the closest-point search, and the mesh rules that make a mesh act as one
surface (:mod:`dpm.kernels.mesh_contact`). The reference here takes none of these
shortcuts: every element against every triangle, the closest point by trimesh (an
independent implementation of Ericson's), its feature from the barycentric coordinates of
that point, and the same rules written over sets, independent of list order:

1. every face contact counts, two coplanar neighbours seeing the centre over their common
   edge count once;
2. an edge or vertex contact counts only if the mesh marks that feature active on the
   side of the triangle the centre is on (front: the face normal's side);
3. an active edge or vertex counts once, and not at all if a triangle holding the whole
   feature has a face contact.

:func:`compare` runs it on a simulation's current state against the contacts the kernels
counted in the last force evaluation (the boundary list's tags), as distance and closest
point per counted contact.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..kernels.boundary_geometry import TRIANGLE

#: barycentric coordinates below this are zero (the closest point on an edge or vertex)
ZERO = 1e-7
#: between ZERO and this the feature is ambiguous: such an element is not compared
AMBIGUOUS = 1e-5


def classify(tri: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, ...]:
    """Closest points (k, 3) of triangles ``tri`` (k, 3, 3) to ``points`` (k, 3), their
    distances, the feature codes of :func:`dpm.kernels.boundary_geometry.triangle_closest`
    (0 face, 1-3 edges v0v1, v1v2, v2v0, 4-6 vertices) and an ambiguity mask."""
    import trimesh

    q = trimesh.triangles.closest_point(tri, points)
    d = np.linalg.norm(points - q, axis=1)
    bc = trimesh.triangles.points_to_barycentric(tri, q)
    zero = bc < ZERO
    amb = np.any((bc >= ZERO) & (bc < AMBIGUOUS), axis=1)
    nz = zero.sum(axis=1)
    code = np.zeros(len(points), np.int64)
    edge = nz == 1
    code[edge & zero[:, 2]] = 1
    code[edge & zero[:, 0]] = 2
    code[edge & zero[:, 1]] = 3
    vert = nz == 2
    code[vert & ~zero[:, 0]] = 4
    code[vert & ~zero[:, 1]] = 5
    code[vert & ~zero[:, 2]] = 6
    return q, d, code, amb


def _feature(ids: np.ndarray, code: int) -> tuple[int, int]:
    """The global vertex ids of feature ``code`` of a triangle (a == b for a vertex)."""
    if code <= 3:
        a, b = int(ids[code - 1]), int(ids[code % 3])
        return (a, b) if a < b else (b, a)
    a = int(ids[code - 4])
    return (a, a)


def reference_contacts(pos: np.ndarray, rad: np.ndarray, tri: np.ndarray, ids: np.ndarray,
                       flags: np.ndarray, normals: np.ndarray,
                       counts: dict[str, int] | None = None) -> dict[int, list | None]:
    """Per element: the sorted (distance, closest point) of the contacts that count, or
    None where a feature is ambiguous or a distance within 1e-9 r of touching. ``counts``
    (if given) adds up the counted contacts by feature kind."""
    out: dict[int, list | None] = {}
    lo, hi = tri.min(axis=1), tri.max(axis=1)
    for i in range(len(pos)):
        near = np.flatnonzero(np.all(lo <= pos[i] + rad[i], axis=1)
                              & np.all(hi >= pos[i] - rad[i], axis=1))
        if len(near) == 0:
            continue
        q, d, code, amb = classify(tri[near], np.repeat(pos[i][None], len(near), axis=0))
        touch = d < rad[i]
        if not touch.any():
            continue
        if np.any(amb[touch]) or np.any(np.abs(d - rad[i]) < 1e-9 * rad[i]):
            out[i] = None
            continue
        faces: list[tuple[int, tuple]] = []
        features: dict[tuple[int, int], tuple] = {}
        for k in np.flatnonzero(touch):
            w = near[k]
            hit = (float(d[k]), tuple(np.round(q[k], 12)))
            if code[k] == 0:
                faces.append((w, hit))
            else:  # rule 2: active features only, seen from the centre's side
                behind = float((pos[i] - q[k]) @ normals[w]) < 0.0
                if (flags[w] >> (code[k] - 1 + (6 if behind else 0))) & 1:
                    features.setdefault(_feature(ids[w], code[k]), hit)
        res, kept = [], []
        for w, hit in faces:  # rule 1
            if not any(len(set(ids[w][:3]) & set(ids[w2][:3])) >= 2
                       and float(normals[w] @ normals[w2]) > 1.0 - 1e-12 for w2 in kept):
                res.append(hit)
                kept.append(w)
        n_faces = len(res)
        face_tris = [w for w, _ in faces]
        for (a, b), hit in features.items():  # rule 3
            if not any(a in ids[w][:3] and b in ids[w][:3] for w in face_tris):
                res.append(hit)
        if counts is not None:
            counts["face"] = counts.get("face", 0) + n_faces
            counts["edge or vertex"] = counts.get("edge or vertex", 0) + len(res) - n_faces
        if res:
            out[i] = sorted(res)
    return out


def kernel_contacts(sim: Any) -> dict[int, list]:
    """Per element: the sorted (distance, closest point) of the triangle contacts the
    kernels counted in the last force evaluation (entries with a tag >= 0)."""
    import trimesh

    wc, w = sim.wall_contacts, sim.walls
    pos = sim.elements.position
    n = len(wc.start) - 1
    rows = np.repeat(np.arange(n), np.diff(wc.start[:n + 1]))
    out: dict[int, list] = {}
    for q in range(int(wc.start[n])):
        p = wc.key[q]
        if w.kind[p] != TRIANGLE or wc.tag[q] < 0:
            continue
        i = int(rows[q])
        tri = w.par[p, 0:9].reshape(1, 3, 3)
        c = trimesh.triangles.closest_point(tri, pos[i][None])[0]
        out.setdefault(i, []).append((float(np.linalg.norm(pos[i] - c)),
                                      tuple(np.round(c, 12))))
    return {i: sorted(v) for i, v in out.items()}


def mesh_table(sim: Any) -> tuple[np.ndarray, ...]:
    """(triangles (m, 3, 3), ids (m, 4), feature flags (m,), normals (m, 3)) of every
    triangle primitive of the scene (static meshes: local = world)."""
    w = sim.walls
    sel = np.flatnonzero(w.kind == TRIANGLE)
    return w.par[sel, 0:9].reshape(-1, 3, 3), w.ids[sel], w.ids[sel, 3], w.par[sel, 10:13]


def compare(sim: Any, flags: np.ndarray | None = None, tol: float = 1e-9,
            counts: dict[str, int] | None = None) -> list[tuple[int, list, list]]:
    """Elements whose counted triangle contacts differ from the reference: (element,
    reference, kernel). ``flags`` replaces the mesh's feature flags in the reference (a
    test that the comparison can fail)."""
    tri, ids, own_flags, normals = mesh_table(sim)
    ref = reference_contacts(sim.elements.position, sim.elements.radius, tri, ids,
                             own_flags if flags is None else flags, normals, counts)
    ker = kernel_contacts(sim)
    bad = []
    for i in sorted(set(ref) | set(ker)):
        r = ref.get(i, [])
        if r is None:
            continue
        k = ker.get(i, [])
        if len(r) != len(k) or any(
                abs(a[0] - b[0]) > tol * max(1.0, a[0])
                or float(np.max(np.abs(np.subtract(a[1], b[1])))) > 1e-8
                for a, b in zip(r, k, strict=True)):
            bad.append((i, r, k))
    return bad
