"""Element-boundary candidate lists: which primitives lie within r + skin of each element.

A boundary's primitives are stored in its own frame (see :mod:`.boundary_geometry`); an
element centre is taken into that frame (x_local = R^T (x - o)) and tested against
either every primitive of the boundary or, for boundaries with many primitives (meshes),
those in the cells of a uniform grid that the sphere's box (r + skin) overlaps. A
primitive spanning several cells is tested only in the first cell of the overlap of its
cell range with the query range, so it is found once without a scratch buffer. The cost
per element is then independent of the number of triangles (for triangles of bounded
size), the logarithmic bound of a tree being beaten by the grid's constant one.

The list keeps the layout of the element-element list: CSR per element, sorted by
primitive index, history merged across rebuilds by :func:`.neighbours._merge`. The search
itself (``boundary_search_pass``, ``build_boundary_list``) lives in :mod:`.step`, so that
it uses the scene's own ``closest`` (only the boundary kinds present are compiled).
"""

import math

from .boundary_geometry import closest_any, in_range
from .config import inline_jit, jit


@inline_jit
def to_local(f, x, y, z):
    """R^T (x - o) for the frame row f."""
    dx = x - f[0]
    dy = y - f[1]
    dz = z - f[2]
    return (f[3] * dx + f[6] * dy + f[9] * dz, f[4] * dx + f[7] * dy + f[10] * dz,
            f[5] * dx + f[8] * dy + f[11] * dz)


@inline_jit
def to_world(f, lx, ly, lz):
    """R l (a direction) for the frame row f."""
    return (f[3] * lx + f[4] * ly + f[5] * lz, f[6] * lx + f[7] * ly + f[8] * lz,
            f[9] * lx + f[10] * ly + f[11] * lz)


@jit
def boundary_motion_since_rebuild(frame, frame_ref, extent):
    """Largest displacement of any boundary point since the last rebuild: |o - o_ref| plus
    the Frobenius norm of R - R_ref (>= its spectral norm) times the boundary's extent."""
    worst = 0.0
    for b in range(frame.shape[0]):
        do = 0.0
        for d in range(3):
            do += (frame[b, d] - frame_ref[b, d]) ** 2
        dr = 0.0
        for d in range(3, 12):
            dr += (frame[b, d] - frame_ref[b, d]) ** 2
        m = math.sqrt(do)
        if dr > 0.0:
            m += math.sqrt(dr) * extent[b]
        if m > worst:
            worst = m
    return worst


@jit
def brute_force_boundary_pairs(e_pos, e_radius, skin, frame, kind, par, owner):
    """All (element, primitive) within reach by the plain double loop (reference for
    tests)."""
    out = []
    for i in range(e_pos.shape[0]):
        r = e_radius[i]
        for w in range(kind.shape[0]):
            lx, ly, lz = to_local(frame[owner[w]], e_pos[i, 0], e_pos[i, 1], e_pos[i, 2])
            d = closest_any(kind[w], par[w], lx, ly, lz, r)[0]
            if in_range(kind[w], d, r, skin):
                out.append((i, w))
    return out
