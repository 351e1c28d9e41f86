"""Which triangle contacts of one element count, so that a mesh acts as one surface.

A sphere near a shared edge or vertex of a mesh finds the same surface in several
triangles. Summing them all would give bumps where a sphere rolls across edges of a flat
meshed floor and double forces at convex edges. The rules (the "inactive features"
approach of LIGGGHTS' mesh walls and of Hu et al., Granular Matter 2013), per element and
per mesh, applied to the contacts the closest-point test found (``tag``: feature code of
:func:`.boundary_geometry.triangle_closest`, -1 not touching):

1. A face contact always counts; two face contacts of adjacent coplanar triangles (the
   centre lies over their common edge) count once.
2. A contact whose closest point is an edge or vertex that the mesh marks inactive
   (edges between coplanar or concave neighbours, vertices whose edges are all inactive)
   does not count: a neighbouring face carries that contact. Convex and concave are as
   seen on the side of the triangle the sphere's centre is on (the sign of the contact
   normal along the face normal): a fold concave at the front is convex behind, where a
   two-sided mesh is touched too (a chute plate hit from below).
3. A contact at an active (convex or open) edge or vertex does not count if a face contact
   of a triangle sharing that edge or vertex counts, nor if an earlier triangle already
   has a contact at the same edge or vertex.

When a triangle contact starts while another triangle contact of the same element and mesh
ends, the new one takes over the contact history (tangential spring), so a sphere
crossing an edge keeps its friction state.

Triangle feature flags (``ids[w, 3]``): bit k (k = 0, 1, 2) edge k active (v0v1, v1v2,
v2v0); bit 3 + k vertex k active, seen from the front (the face normal's side); bits
6 + k and 9 + k the same seen from behind (:func:`dpm.boundaries.mesh.feature_flags`).
"""

from .boundary_geometry import TRIANGLE
from .config import inline_jit, jit


@inline_jit
def _feature_vertices(tag, ids):
    """The vertex ids (a, b) of feature ``tag`` (a == b for a vertex) and its flag bit."""
    if tag <= 3:
        return ids[tag - 1], ids[tag % 3], tag - 1
    return ids[tag - 4], ids[tag - 4], tag - 1


@inline_jit
def _has_vertex(ids, v):
    return ids[0] == v or ids[1] == v or ids[2] == v


@jit
def resolve_triangle_contacts(q0, q1, wl_w, wl_tag, w_kind, w_owner, w_ids, w_par, wl_active,
                              wl_hist, wl_f):
    """Apply rules 1-3 to the entries q0..q1 of one element (tags set to -1 where a contact
    does not count), then hand over history to contacts that start. ``wl_f[q, 1:4]``: the
    contact normal of entry q (centre minus closest point, in the boundary's frame), whose
    sign along the face normal says which side's feature flags apply."""
    for q in range(q0, q1):
        w = wl_w[q]
        if w_kind[w] != TRIANGLE:
            continue
        t = wl_tag[q]
        if t < 0:
            continue
        ids = w_ids[w]
        if t == 0:
            # rule 1: coplanar neighbour with a face contact earlier in the list
            for q2 in range(q0, q):
                w2 = wl_w[q2]
                if w_kind[w2] != TRIANGLE or w_owner[w2] != w_owner[w] or wl_tag[q2] != 0:
                    continue
                ids2 = w_ids[w2]
                shared = 0
                for c in range(3):
                    if _has_vertex(ids2, ids[c]):
                        shared += 1
                dot = (w_par[w, 10] * w_par[w2, 10] + w_par[w, 11] * w_par[w2, 11]
                       + w_par[w, 12] * w_par[w2, 12])
                if shared >= 2 and dot > 1.0 - 1e-12:
                    wl_tag[q] = -1
                    break
            continue
        va, vb, bit = _feature_vertices(t, ids)
        if (wl_f[q, 1] * w_par[w, 10] + wl_f[q, 2] * w_par[w, 11]
                + wl_f[q, 3] * w_par[w, 12]) < 0.0:
            bit += 6  # the centre is behind this triangle: the back's flags
        if not (ids[3] >> bit) & 1:
            wl_tag[q] = -1  # rule 2
            continue
        for q2 in range(q0, q1):
            if q2 == q:
                continue
            w2 = wl_w[q2]
            if w_kind[w2] != TRIANGLE or w_owner[w2] != w_owner[w]:
                continue
            t2 = wl_tag[q2]
            if t2 < 0:
                continue
            ids2 = w_ids[w2]
            if not (_has_vertex(ids2, va) and _has_vertex(ids2, vb)):
                continue
            if t2 == 0:
                wl_tag[q] = -1  # rule 3: an adjacent face carries it
                break
            if q2 < q:
                a2, b2, _ = _feature_vertices(t2, ids2)
                if (a2 == va and b2 == vb) or (a2 == vb and b2 == va):
                    wl_tag[q] = -1  # rule 3: the same edge or vertex, counted once
                    break
    # history hand-over
    nh = wl_hist.shape[1]
    for q in range(q0, q1):
        w = wl_w[q]
        if w_kind[w] != TRIANGLE or wl_tag[q] < 0 or wl_active[q]:
            continue
        for q2 in range(q0, q1):
            w2 = wl_w[q2]
            if (q2 != q and w_kind[w2] == TRIANGLE and w_owner[w2] == w_owner[w]
                    and wl_active[q2] and wl_tag[q2] < 0):
                for c in range(nh):
                    wl_hist[q, c] = wl_hist[q2, c]
                    wl_hist[q2, c] = 0.0
                wl_active[q2] = 0
                wl_active[q] = 1
                break
