"""One DEM step and the many-step loop, composed from the other kernels.

Order of a step (:func:`run_steps`):

1. ``pre_force_body``  integrator part before the forces (e.g. half kick + drift), or
   ``pre_force_sphere`` for single spheres whose orientation is not tracked
2. element world positions from body position and quaternion (skipped when every body is
   one sphere: the element positions are then the body positions)
3. neighbour lists rebuilt when an element moved more than skin/2 (history merged)
4. forces, so that no two threads write the same row and every sum adds the same terms in
   the same order whatever the number of threads, in one of two forms (``FUSED``, a
   constant of the scene):
   - every body a single sphere: :func:`fused_pass`, one chunk of elements per thread,
     each pair's force added to both bodies as it is computed;
   - otherwise two passes: a. per element (parallel, :func:`contact_pass`): each pair of
     its half list and each entry of its boundary list; the force and both torques of a
     touching pair go to that pair's row of ``nl_f``; b. per body (parallel,
     :func:`sum_pass`): gravity plus the rows of its elements (own pairs, boundary
     entries, then the pairs where it is the partner, last owner first);
   then boundary reactions summed over the boundary list
5. ``post_force_body`` integrator part after the forces (e.g. second half kick), fused
   into the last per-body loop of step 4

:mod:`dpm.plan` copies this module for each scene with the block between the
``bindings`` markers rewritten: the contact laws the scene uses become ``law_0``,
``law_1``, ... and the integrator's ``pre_force_body``/``post_force_body`` are imported, so
each scene compiles (once, cached) a step that contains only what it needs.

Diagnostics (``diag``): [0] status (0 ok, 1 pair list overflow, 2 NaN, 3 overlap
beyond the limit, 4 wall list overflow), [1] steps done, [2] rebuilds, [3] pairs needed,
[4] largest overlap / radius seen, [5] element with that overlap, [6] active contacts in
the last force evaluation.
"""
# ruff: noqa: I001  (the bindings block must stay between its markers)
import math

import numpy as np

from numba import prange

from .config import inline_jit, row18, row20, step_jit as jit
from .config import step_pjit as pjit
from .boundary_geometry import AXI, JOINED, TORUS, TRIANGLE, in_range, touching
from .boundary_geometry import off_triangle_plane, triangle_distance_within
from .boundary_search import boundary_motion_since_rebuild, to_local, to_world
from .mesh_contact import resolve_triangle_contacts
from .neighbours import _copy_back as copy_back, _merge as merge_history
from .neighbours import build_neighbour_list, copy_slots, minimum_image, rows_of_counts
from .neighbours import outgrown, slot_starts
from .rigid_rotation import place_elements
from .halo import pack_halo, unpack_halo
from .mpi_calls import mpi_wtime, vote_and_halo

# --- bindings begin (dpm.plan rewrites this block) ---
from .config import pair_row
from .law_linear import linear_normal as normal_0
from .tangential import linear_tangential as tangential_0
from .law_hertz_mindlin import hertz_tsuji_normal as normal_1
from .tangential import mindlin_tsuji_tangential as tangential_1
from .integrate_velocity_verlet import pre_force_body, pre_force_sphere, post_force_body
from .boundary_geometry import plane_distance

HAS_TRIANGLES = False
HAS_JOINTS = False
PERIODIC = False
FUSED = False


@inline_jit
def closest(kind, p, x, y, z, r):
    """Contact geometry of the boundary kinds of this scene."""
    d, nx, ny, nz = plane_distance(p, x, y, z)
    return d, nx, ny, nz, 0


#: ``closest`` for the list searches, the initial-overlap check and the pipe-joint
#: hand-over (the one per-step use: each active tube or bend contact): the same function
#: inlined for a scene of few boundary kinds, a compiled function called for more
#: (dpm.plan.INLINE_SEARCH_KINDS); the contact loop itself always inlines ``closest``
closest_call = closest

ROLLING = False


@inline_jit
def law_0(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, wx, wy, wz, dt, hist, k):
    """linear_spring_dashpot: LinearNormal x LinearTangential."""
    fn, kn = normal_0((p[0], p[1]), delta, ddelta, meff, reff, dt, hist, k, 3)
    ftx, fty, ftz = tangential_0((p[2], p[3], p[4]), fn, kn, delta, vtx, vty, vtz, nx, ny, nz,
            meff, reff, dt, hist, k, 0)
    return fn, ftx, fty, ftz, 0.0, 0.0, 0.0


@inline_jit
def normal_law_0(p, delta, ddelta, nx, ny, nz, meff, reff, dt, hist, k):
    fn, kn = normal_0((p[0], p[1]), delta, ddelta, meff, reff, dt, hist, k, 3)
    return fn


@inline_jit
def law_1(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, wx, wy, wz, dt, hist, k):
    """hertz_mindlin: HertzTsujiNormal x MindlinTsujiTangential."""
    fn, kn = normal_1((p[0], p[1]), delta, ddelta, meff, reff, dt, hist, k, 3)
    ftx, fty, ftz = tangential_1((p[2], p[1], p[3]), fn, kn, delta, vtx, vty, vtz, nx, ny, nz,
            meff, reff, dt, hist, k, 0)
    return fn, ftx, fty, ftz, 0.0, 0.0, 0.0


@inline_jit
def normal_law_1(p, delta, ddelta, nx, ny, nz, meff, reff, dt, hist, k):
    fn, kn = normal_1((p[0], p[1]), delta, ddelta, meff, reff, dt, hist, k, 3)
    return fn


@inline_jit
def pair_force(model, p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, wx, wy, wz, dt,
        hist, k):
    """F_n, F_t, rolling torque of the contact law ``model`` of this scene."""
    if model == 0:
        return law_0(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, wx, wy, wz, dt,
                hist, k)
    return law_1(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, wx, wy, wz, dt, hist, k)


@inline_jit
def pair_normal(model, p, delta, ddelta, nx, ny, nz, meff, reff, dt, hist, k):
    """The normal force F_n of the contact law ``model`` of this scene."""
    if model == 0:
        return normal_law_0(p, delta, ddelta, nx, ny, nz, meff, reff, dt, hist, k)
    return normal_law_1(p, delta, ddelta, nx, ny, nz, meff, reff, dt, hist, k)

RANGED = False


@inline_jit
def pair_attached(model, p, delta, reff, hist, k):
    """Whether a pair at negative overlap ``delta`` is in contact (laws with an interaction
    range)."""
    return False
# --- bindings end ---

STATUS_OK = 0
STATUS_OVERFLOW = 1
STATUS_NAN = 2
STATUS_OVERLAP = 3
STATUS_WALL_OVERFLOW = 4


@pjit
def update_element_positions(b_pos, b_quat, b_estart, e_offset, e_pos):
    """Element world positions of every body."""
    for b in prange(b_pos.shape[0]):
        place_elements(b, b_pos, b_quat, b_estart, e_offset, e_pos)


@inline_jit
def wrap_body(b, period, b_pos, b_estart, e_ref):
    """A body whose centre left the periodic box moves back in by whole periods, with the
    rebuild references of its elements (so no rebuild follows); its element positions are
    placed from it next (or are its position: single spheres). Every step, inside the
    kernel, so that results do not depend on where a run is split into calls."""
    for d in range(3):
        length = period[3 + d]
        if length > 0.0:
            x = b_pos[b, d]
            lo = period[d]
            if x < lo or x >= lo + length:
                shift = math.floor((x - lo) / length) * length
                b_pos[b, d] = x - shift
                for e in range(b_estart[b], b_estart[b + 1]):
                    e_ref[e, d] -= shift


@pjit
def pre_force(dt, ctl, bodies, elems):
    """Steps 1-2 per body: integrator pre-force part (which also sets the velocities the
    forces are evaluated with, ``bodies.vf`` and ``bodies.wf``), element positions, and each
    element's squared displacement since the last rebuild (``elems.worst``).
    ``ctl.spin_only``: every body is a single sphere whose orientation is not tracked (the
    integrator's ``pre_force_sphere``)."""
    b_pos, b_vel, b_quat, b_angvel = bodies.pos, bodies.vel, bodies.quat, bodies.angvel
    b_force, b_torque, b_invmass, b_invinertia = (bodies.force, bodies.torque, bodies.invmass,
                                                  bodies.invinertia)
    b_vf, b_wf, b_aux, b_estart = bodies.vf, bodies.wf, bodies.aux, bodies.estart
    e_offset, e_pos, e_ref, e_d2 = elems.offset, elems.pos, elems.ref, elems.worst
    update_elements = ctl.update_elements
    spin_only = ctl.spin_only
    period = ctl.period
    n_owned = ctl.n_owned
    for b in prange(b_pos.shape[0]):
        if b >= n_owned:
            # a ghost (an MPI rank's copy of another rank's body): its state, predicted
            # velocities and element positions come from its owner with the halo, and
            # its owner checks its displacement
            for e in range(b_estart[b], b_estart[b + 1]):
                e_d2[e] = 0.0
            continue
        if spin_only:
            pre_force_sphere(b, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque,
                             b_invmass, b_invinertia, dt, b_vf, b_wf, b_aux)
        else:
            pre_force_body(b, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque,
                           b_invmass, b_invinertia, dt, b_vf, b_wf, b_aux)
        if PERIODIC:  # (a constant of the scene)
            wrap_body(b, period, b_pos, b_estart, e_ref)
        if update_elements:
            place_elements(b, b_pos, b_quat, b_estart, e_offset, e_pos)
        for e in range(b_estart[b], b_estart[b + 1]):
            dx = e_pos[e, 0] - e_ref[e, 0]
            dy = e_pos[e, 1] - e_ref[e, 1]
            dz = e_pos[e, 2] - e_ref[e, 2]
            e_d2[e] = dx * dx + dy * dy + dz * dz


@pjit
def post_force(dt, ctl, bodies):
    """Step 5 alone, per body: the integrator's post-force part (e.g. the second half
    kick). :func:`compute_forces` with ``integrate`` runs it fused into its last per-body
    loop; this separate form is for backends that must act between the forces and the
    update (MPI: ghost forces handed back to their owners). Same arithmetic, same bits."""
    b_pos, b_vel, b_quat, b_angvel = bodies.pos, bodies.vel, bodies.quat, bodies.angvel
    b_force, b_torque, b_invmass, b_invinertia = (bodies.force, bodies.torque, bodies.invmass,
                                                  bodies.invinertia)
    b_aux = bodies.aux
    for b in prange(ctl.n_owned):
        post_force_body(b, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass,
                        b_invinertia, dt, b_aux)


@pjit
def clear_rows(rows, count):
    """Zero the first ``count`` force rows (after a rebuild the rows belong to new pairs;
    the contact pass writes those that touch)."""
    for k in prange(count):
        for c in range(rows.shape[1]):
            rows[k, c] = 0.0


@jit
def largest(values):
    """Largest value; NaN if any is NaN."""
    m = 0.0
    for i in range(values.shape[0]):
        v = values[i]
        if not v <= m:
            if v != v:
                return v
            m = v
    return m


@inline_jit
def joint_hand_over(q0, q1, xi, yi, zi, ri, wl_w, wl_active, wl_hist, w_kind, w_par, w_owner,
                    f_cur):
    """A sphere crossing the joint of two pipe pieces: the contact that ends beyond the
    joined end hands its history (tangential spring) to the one that starts on the next
    piece, as across the edges of a mesh."""
    nh = wl_hist.shape[1]
    for q2 in range(q0, q1):
        w2 = wl_w[q2]
        k2 = w_kind[w2]
        if not wl_active[q2] or (k2 != AXI and k2 != TORUS):
            continue
        lx, ly, lz = to_local(f_cur[w_owner[w2]], xi, yi, zi)
        if closest_call(k2, w_par[w2], lx, ly, lz, ri)[4] != JOINED:
            continue
        for q in range(q0, q1):
            w = wl_w[q]
            k = w_kind[w]
            if q == q2 or wl_active[q] or (k != AXI and k != TORUS):
                continue
            lx, ly, lz = to_local(f_cur[w_owner[w]], xi, yi, zi)
            d, _, _, _, feature = closest_call(k, w_par[w], lx, ly, lz, ri)
            if feature != JOINED and touching(k, d, ri):
                for c in range(nh):
                    wl_hist[q, c] = wl_hist[q2, c]
                    wl_hist[q2, c] = 0.0
                wl_active[q2] = 0
                wl_active[q] = 1
                break


@inline_jit
def add_row(rows, q, fx, fy, fz, tx, ty, tz):
    """The sums plus force row q's force (columns 0-2) and torque on its body (3-5)."""
    return (fx + rows[q, 0], fy + rows[q, 1], fz + rows[q, 2], tx + rows[q, 3],
            ty + rows[q, 4], tz + rows[q, 5])


@inline_jit
def pair_contact(kk, j, xi, yi, zi, ri, bi, mi, dt, b_pos, b_vel, b_angvel, b_invmass, e_owner,
                 e_radius, e_mat, e_pos, nl_hist, nl_active, pair_model, pair_params, period,
                 reach):
    """Contact force of listed pair ``kk`` (element i at xi, yi, zi with radius ri, body bi,
    material mi; partner element j).

    Returns (state, overlap, smaller radius, F on i, torque on body(i), torque on body(j));
    state 1 in contact, 0 not, 2 it stopped being in contact in this call (its history was
    cleared; the caller clears its force row). In contact: overlapping, or (``RANGED``, a
    law with an interaction range: a constant of the scene) within ``reach`` of touching
    and still attached by the law (``pair_attached``).
    """
    dx = xi - e_pos[j, 0]
    dy = yi - e_pos[j, 1]
    dz = zi - e_pos[j, 2]
    if PERIODIC:  # nearest image of j (a constant of the scene: no cost otherwise)
        dx = minimum_image(dx, period[3])
        dy = minimum_image(dy, period[4])
        dz = minimum_image(dz, period[5])
    rj = e_radius[j]
    rs = ri + rj
    d2 = dx * dx + dy * dy + dz * dz
    ims = 0.0
    bj = bi
    rr = rs + reach if RANGED else rs
    if d2 < rr * rr:  # only touching pairs read the partner's body
        bj = e_owner[j]
        ims = b_invmass[bi] + b_invmass[bj]
        if RANGED and d2 >= rs * rs and ims != 0.0:  # apart: is it still attached?
            if not pair_attached(pair_model[mi, e_mat[j]], pair_row(pair_params, mi, e_mat[j]),
                                 rs - math.sqrt(d2), ri * rj / rs, nl_hist, kk):
                ims = 0.0
    if ims == 0.0:
        state = 0
        if nl_active[kk]:  # it stopped touching: clear its history
            for c in range(nl_hist.shape[1]):
                nl_hist[kk, c] = 0.0
            nl_active[kk] = 0
            state = 2
        return state, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    nl_active[kk] = 1
    dist = math.sqrt(d2)
    inv = 1.0 / dist
    nx = dx * inv
    ny = dy * inv
    nz = dz * inv
    delta = rs - dist
    # contact point: middle of the overlap, on the line of centres
    a = ri - 0.5 * delta
    cx = xi - a * nx
    cy = yi - a * ny
    cz = zi - a * nz
    aix = cx - b_pos[bi, 0]
    aiy = cy - b_pos[bi, 1]
    aiz = cz - b_pos[bi, 2]
    ajx = cx - b_pos[bj, 0]
    ajy = cy - b_pos[bj, 1]
    ajz = cz - b_pos[bj, 2]
    if PERIODIC:  # lever arm to the image of j's body
        ajx -= xi - dx - e_pos[j, 0]
        ajy -= yi - dy - e_pos[j, 1]
        ajz -= zi - dz - e_pos[j, 2]
    # relative velocity of i with respect to j at the contact point
    vx = (b_vel[bi, 0] + b_angvel[bi, 1] * aiz - b_angvel[bi, 2] * aiy
          - b_vel[bj, 0] - b_angvel[bj, 1] * ajz + b_angvel[bj, 2] * ajy)
    vy = (b_vel[bi, 1] + b_angvel[bi, 2] * aix - b_angvel[bi, 0] * aiz
          - b_vel[bj, 1] - b_angvel[bj, 2] * ajx + b_angvel[bj, 0] * ajz)
    vz = (b_vel[bi, 2] + b_angvel[bi, 0] * aiy - b_angvel[bi, 1] * aix
          - b_vel[bj, 2] - b_angvel[bj, 0] * ajy + b_angvel[bj, 1] * ajx)
    vn = vx * nx + vy * ny + vz * nz
    vtx = vx - vn * nx
    vty = vy - vn * ny
    vtz = vz - vn * nz
    mj = e_mat[j]
    p = pair_row(pair_params, mi, mj)
    reff = ri * rj / rs
    meff = 1.0 / ims
    fn, ftx, fty, ftz, rx, ry, rz = pair_force(
        pair_model[mi, mj], p, delta, -vn, vtx, vty, vtz, nx, ny, nz, meff, reff,
        b_angvel[bi, 0] - b_angvel[bj, 0], b_angvel[bi, 1] - b_angvel[bj, 1],
        b_angvel[bi, 2] - b_angvel[bj, 2], dt, nl_hist, kk)
    fx = fn * nx + ftx
    fy = fn * ny + fty
    fz = fn * nz + ftz
    tix = aiy * fz - aiz * fy
    tiy = aiz * fx - aix * fz
    tiz = aix * fy - aiy * fx
    tjx = -(ajy * fz - ajz * fy)
    tjy = -(ajz * fx - ajx * fz)
    tjz = -(ajx * fy - ajy * fx)
    if ROLLING:  # (a constant of the scene: any law with rolling resistance)
        tix += rx
        tiy += ry
        tiz += rz
        tjx -= rx
        tjy -= ry
        tjz -= rz
    return 1, delta, min(ri, rj), fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz


@inline_jit
def boundary_contacts(i, xi, yi, zi, ri, bi, mi, dt, b_pos, b_vel, b_angvel, b_mass,
                      b_invmass, wl_start, wl_w, wl_hist, wl_active, wl_f, wl_tag, w_kind,
                      w_par, w_owner, w_mat, w_ids, f_cur, pair_model, pair_params, reach):
    """Element-boundary contacts of element i, each in its boundary's frame, stored per
    row: wl_f[q] = (F, torque on the body, torque on the boundary about its frame origin);
    rows of entries that do not touch are zeroed. Returns (touching entries, largest
    overlap / radius). The boundary arrays come unpacked from ``bnd`` (the caller unpacks
    them once: taking an array out of a tuple costs numba a reference count, two atomic
    operations, each time). ``RANGED``: an entry within ``reach`` of touching is in contact
    while its law keeps it attached (``pair_attached``)."""
    nh = wl_hist.shape[1]
    count = 0
    worst = 0.0
    q0 = wl_start[i]
    q1 = wl_start[i + 1]
    if HAS_TRIANGLES:
        # the mesh rules have work only where two triangle entries touch, one touches at
        # an edge or vertex, or a contact starts while another ends (history hand-over);
        # one face contact alone (most entries on a meshed floor) skips that call
        touching_tri = 0
        rules = False
        starts = False
        ends = False
        for q in range(q0, q1):
            w = wl_w[q]
            if w_kind[w] == TRIANGLE:
                lx, ly, lz = to_local(row18(f_cur, w_owner[w]), xi, yi, zi)
                lim = ri + reach if RANGED else ri
                dist, lnx, lny, lnz, feature = triangle_distance_within(row20(w_par, w), lx,
                                                                        ly, lz, lim)
                tag = feature if dist < lim else -1
                wl_tag[q] = tag
                if tag >= 0:
                    touching_tri += 1
                    rules = rules or tag > 0
                    starts = starts or not wl_active[q]
                else:
                    ends = ends or wl_active[q] != 0
                # kept for the contact loop below, which rewrites the row in any case
                wl_f[q, 0] = dist
                wl_f[q, 1] = lnx
                wl_f[q, 2] = lny
                wl_f[q, 3] = lnz
        if touching_tri > 1 or rules or (starts and ends):
            resolve_triangle_contacts(q0, q1, wl_w, wl_tag, w_kind, w_owner, w_ids,
                                      w_par, wl_active, wl_hist, wl_f)
    if HAS_JOINTS:
        joint_hand_over(q0, q1, xi, yi, zi, ri, wl_w, wl_active, wl_hist, w_kind, w_par,
                        w_owner, f_cur)
    for q in range(q0, q1):
        w = wl_w[q]
        kind = w_kind[w]
        f = row18(f_cur, w_owner[w])  # (tuples: no reference counts per entry)
        if HAS_TRIANGLES and kind == TRIANGLE:
            # the geometry the loop above found; tag -1: not within reach, or a contact the
            # mesh rules give to another triangle
            dist = wl_f[q, 0]
            lnx = wl_f[q, 1]
            lny = wl_f[q, 2]
            lnz = wl_f[q, 3]
            feature = wl_tag[q]
            touch = feature >= 0
            if RANGED and touch and not touching(kind, dist, ri):  # still attached?
                touch = pair_attached(pair_model[mi, w_mat[w]],
                                      pair_row(pair_params, mi, w_mat[w]), ri - dist, ri,
                                      wl_hist, q)
        else:
            lx, ly, lz = to_local(f, xi, yi, zi)
            dist, lnx, lny, lnz, feature = closest(kind, row20(w_par, w), lx, ly, lz, ri)
            touch = touching(kind, dist, ri)
            if RANGED and not touch and touching(kind, dist, ri + reach):  # still attached?
                touch = pair_attached(pair_model[mi, w_mat[w]],
                                      pair_row(pair_params, mi, w_mat[w]), ri - dist, ri,
                                      wl_hist, q)
        if not touch or feature == JOINED or b_invmass[bi] == 0.0:
            if wl_active[q]:
                for c in range(nh):
                    wl_hist[q, c] = 0.0
                wl_active[q] = 0
            for c in range(9):  # (a hand-over may have deactivated it: always)
                wl_f[q, c] = 0.0
            continue
        wl_active[q] = 1
        count += 1
        delta = ri - dist
        if delta > worst * ri:
            worst = delta / ri
        # a ring contact (surface of revolution) comes with a normal shorter than 1: its
        # length scales the force, its direction is the contact's
        scale = 1.0
        nn = lnx * lnx + lny * lny + lnz * lnz
        if nn < 1.0 - 1e-12:
            scale = math.sqrt(nn)
            if scale > 1e-150:
                lnx /= scale
                lny /= scale
                lnz /= scale
            else:
                lnx, lny, lnz = 0.0, 0.0, 1.0
        nx, ny, nz = to_world(f, lnx, lny, lnz)
        a = ri - 0.5 * delta
        cx = xi - a * nx
        cy = yi - a * ny
        cz = zi - a * nz
        ax = cx - b_pos[bi, 0]
        ay = cy - b_pos[bi, 1]
        az = cz - b_pos[bi, 2]
        # boundary velocity at the contact point: v_o + omega x (c - o)
        ox = cx - f[0]
        oy = cy - f[1]
        oz = cz - f[2]
        vwx = f[12] + f[16] * oz - f[17] * oy
        vwy = f[13] + f[17] * ox - f[15] * oz
        vwz = f[14] + f[15] * oy - f[16] * ox
        vx = b_vel[bi, 0] + b_angvel[bi, 1] * az - b_angvel[bi, 2] * ay - vwx
        vy = b_vel[bi, 1] + b_angvel[bi, 2] * ax - b_angvel[bi, 0] * az - vwy
        vz = b_vel[bi, 2] + b_angvel[bi, 0] * ay - b_angvel[bi, 1] * ax - vwz
        vn = vx * nx + vy * ny + vz * nz
        vtx = vx - vn * nx
        vty = vy - vn * ny
        vtz = vz - vn * nz
        mw = w_mat[w]
        p = pair_row(pair_params, mi, mw)
        # the boundary's relative angular velocity is its frame's
        fn, ftx, fty, ftz, rx, ry, rz = pair_force(
            pair_model[mi, mw], p, delta, -vn, vtx, vty, vtz, nx, ny, nz, b_mass[bi], ri,
            b_angvel[bi, 0] - f[15], b_angvel[bi, 1] - f[16], b_angvel[bi, 2] - f[17], dt,
            wl_hist, q)
        if scale != 1.0:
            fn *= scale
            ftx *= scale
            fty *= scale
            ftz *= scale
            rx *= scale
            ry *= scale
            rz *= scale
        fx = fn * nx + ftx
        fy = fn * ny + fty
        fz = fn * nz + ftz
        tx = ay * fz - az * fy
        ty = az * fx - ax * fz
        tz = ax * fy - ay * fx
        if ROLLING:
            tx += rx
            ty += ry
            tz += rz
        wl_f[q, 0] = fx
        wl_f[q, 1] = fy
        wl_f[q, 2] = fz
        wl_f[q, 3] = tx
        wl_f[q, 4] = ty
        wl_f[q, 5] = tz
        # reaction on the boundary: -F at the contact point and the opposite rolling
        # resistance torque
        wl_f[q, 6] = -(oy * fz - oz * fy) - rx
        wl_f[q, 7] = -(oz * fx - ox * fz) - ry
        wl_f[q, 8] = -(ox * fy - oy * fx) - rz
    return count, worst


@pjit
def contact_pass(dt, ctl, bodies, elems, pairs, walls, bnd):
    """Pass a: contact forces of every pair and element-boundary entry, stored per row.

    pairs.force[k] = (F on i, torque on body(i), torque on body(j)); walls.force[q] = (F,
    torque on the body, torque on the boundary about its frame origin). Rows of pairs that
    do not touch are zero. elems.worst[i], elems.count[i]: largest overlap / radius and
    number of touching contacts. Velocity-dependent forces see ``bodies.vf``/``wf``.
    """
    b_pos, b_vel, b_angvel, b_mass, b_invmass = (bodies.pos, bodies.vf, bodies.wf,
                                                 bodies.mass, bodies.invmass)
    e_owner, e_radius, e_mat, e_pos = elems.owner, elems.radius, elems.mat, elems.pos
    e_worst, e_count = elems.worst, elems.count
    nl_start, nl_j, nl_hist, nl_active, nl_f = (pairs.start, pairs.key, pairs.hist,
                                                pairs.active, pairs.force)
    wl_start, wl_w, wl_hist, wl_active, wl_f, wl_tag = (walls.start, walls.key, walls.hist,
                                                        walls.active, walls.force, walls.tag)
    pair_model, pair_params, period = ctl.pair_model, ctl.pair_params, ctl.period
    reach = ctl.reach
    w_kind, w_par, w_owner, w_mat, w_ids, f_cur = (bnd.kind, bnd.par, bnd.owner, bnd.material,
                                                   bnd.ids, bnd.frame)
    for i in prange(e_pos.shape[0]):
        xi = e_pos[i, 0]
        yi = e_pos[i, 1]
        zi = e_pos[i, 2]
        ri = e_radius[i]
        bi = e_owner[i]
        mi = e_mat[i]
        worst = 0.0
        count = 0
        for kk in range(nl_start[i], nl_start[i + 1]):
            state, delta, rmin, fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz = pair_contact(
                kk, nl_j[kk], xi, yi, zi, ri, bi, mi, dt, b_pos, b_vel, b_angvel, b_invmass,
                e_owner, e_radius, e_mat, e_pos, nl_hist, nl_active, pair_model,
                pair_params, period, reach)
            if state == 1:
                count += 1
                if delta > worst * rmin:  # (a division only for a new largest)
                    worst = delta / rmin
            elif state == 2:
                for c in range(9):
                    nl_f[kk, c] = 0.0
                continue
            else:
                continue
            nl_f[kk, 0] = fx
            nl_f[kk, 1] = fy
            nl_f[kk, 2] = fz
            nl_f[kk, 3] = tix
            nl_f[kk, 4] = tiy
            nl_f[kk, 5] = tiz
            nl_f[kk, 6] = tjx
            nl_f[kk, 7] = tjy
            nl_f[kk, 8] = tjz
        wcount, wworst = boundary_contacts(i, xi, yi, zi, ri, bi, mi, dt, b_pos, b_vel,
                                           b_angvel, b_mass, b_invmass, wl_start, wl_w,
                                           wl_hist, wl_active, wl_f, wl_tag, w_kind, w_par,
                                           w_owner, w_mat, w_ids, f_cur, pair_model,
                                           pair_params, reach)
        e_worst[i] = max(worst, wworst)
        e_count[i] = count + wcount


#: the work of an element itself (its loads, gravity, its sums, its post-force part) and
#: of one of its boundary entries, in listed pairs' worth: the weights by which
#: :func:`chunk_bounds` evens the threads' chunks (a touching pair costs ~25 ns, a listed
#: one that does not touch ~5 ns, an element's own part ~30 ns, a boundary entry a
#: closest-point test and, touching, a force)
CHUNK_ELEMENT_WEIGHT = 2
CHUNK_BOUNDARY_WEIGHT = 2


@jit
def chunk_cost(i, nl_start, wl_start):
    """The modelled work of elements ``0 .. i - 1`` (nondecreasing in ``i``)."""
    return (nl_start[i] + CHUNK_ELEMENT_WEIGHT * i
            + CHUNK_BOUNDARY_WEIGHT * wl_start[i])


@jit
def chunk_bounds(nchunks, nl_start, wl_start):
    """Bounds of ``nchunks`` contiguous element ranges holding about equal work: listed
    pairs, the elements themselves and their boundary entries (:func:`chunk_cost`; a
    bisection per bound). By listed pairs alone a scene with few pairs (spheres apart on a
    mesh floor, a dilute stream) put every element in the last chunk: one thread did all
    the work. Balancing by touching contacts as well, an O(n) pass per step, gave no
    faster step on box_settle."""
    n = nl_start.shape[0] - 1
    bounds = np.empty(nchunks + 1, np.int64)
    bounds[0] = 0
    bounds[nchunks] = n
    total = chunk_cost(n, nl_start, wl_start)
    for c in range(1, nchunks):
        target = (total * c) // nchunks
        lo = bounds[c - 1]
        hi = n
        while lo < hi:  # first element whose work starts at or after the target
            mid = (lo + hi) // 2
            if chunk_cost(mid, nl_start, wl_start) < target:
                lo = mid + 1
            else:
                hi = mid
        bounds[c] = lo
    return bounds


@pjit
def fused_pass(dt, integrate, ctl, bodies, elems, pairs, walls, bnd):
    """Passes a and b fused, for scenes whose bodies are all single spheres (element i is
    body i): each pair's force goes straight to both bodies' sums, as in LIGGGHTS, instead
    of through a force row.

    The elements are cut into ``nchunks`` contiguous ranges of about equal numbers of
    pairs (:func:`chunk_bounds`, one per thread), each swept
    backwards, last element first. A pair whose partner j lies in a later chunk
    writes its force row instead (``nl_f``: F on i, torque on i, torque on j); a second
    loop adds those rows to their partners, then (if ``integrate``) runs the integrator's
    post-force part body by body.

    The sums are bit for bit those of :func:`sum_pass`, for any ``nchunks``: a body's own
    pairs (partner j > i) and its boundary rows are added first, onto gravity, because
    within a chunk j > i was visited before i; then the pairs where it is the partner
    arrive from ever smaller i: first from its own chunk during the sweep, then, in the
    second loop, from the earlier chunks, again from the largest i down. That is the order
    in which :func:`sum_pass` adds them, so the result does not depend on the number of
    threads.

    The sweeps sit inside ``prange`` loops even for one chunk: compiled as the body of a
    parallel loop, the serial sweep runs 5x faster than the same loop in a plain ``@jit``
    function (1.0 ms against 5.2 ms per call on the settled box_settle packing, numba
    0.68); the same holds for loops that call the integrator's per-body parts (velocity
    Verlet's second half kick: 32 us against 240 us for 10,000 bodies).
    """
    b_pos, b_vel, b_quat, b_angvel = bodies.pos, bodies.vel, bodies.quat, bodies.angvel
    b_force, b_torque, b_mass, b_invmass = (bodies.force, bodies.torque, bodies.mass,
                                            bodies.invmass)
    b_invinertia, b_vf, b_wf, b_aux = bodies.invinertia, bodies.vf, bodies.wf, bodies.aux
    e_owner, e_radius, e_mat, e_pos = elems.owner, elems.radius, elems.mat, elems.pos
    e_worst, e_count = elems.worst, elems.count
    nl_start, nl_j, nl_hist, nl_active, nl_f = (pairs.start, pairs.key, pairs.hist,
                                                pairs.active, pairs.force)
    t_start, t_pair = pairs.t_start, pairs.t_pair
    wl_start, wl_w, wl_hist, wl_active, wl_f, wl_tag = (walls.start, walls.key, walls.hist,
                                                        walls.active, walls.force, walls.tag)
    pair_model, pair_params, period = ctl.pair_model, ctl.pair_params, ctl.period
    reach = ctl.reach
    w_kind, w_par, w_owner, w_mat, w_ids, f_cur = (bnd.kind, bnd.par, bnd.owner, bnd.material,
                                                   bnd.ids, bnd.frame)
    nchunks = ctl.fused
    n_owned = ctl.n_owned
    gravity = ctl.gravity
    g0 = gravity[0]
    g1 = gravity[1]
    g2 = gravity[2]
    bounds = chunk_bounds(nchunks, nl_start, wl_start)
    for c in prange(nchunks):
        lo = bounds[c]
        hi = bounds[c + 1]
        for i in range(hi - 1, lo - 1, -1):
            xi = e_pos[i, 0]
            yi = e_pos[i, 1]
            zi = e_pos[i, 2]
            ri = e_radius[i]
            mi = e_mat[i]
            m = b_mass[i]
            fx = m * g0
            fy = m * g1
            fz = m * g2
            tx = 0.0
            ty = 0.0
            tz = 0.0
            worst = 0.0
            count = 0
            for kk in range(nl_start[i], nl_start[i + 1]):
                j = nl_j[kk]
                state, delta, rmin, px, py, pz, tix, tiy, tiz, tjx, tjy, tjz = pair_contact(
                    kk, j, xi, yi, zi, ri, i, mi, dt, b_pos, b_vf, b_wf, b_invmass, e_owner,
                    e_radius, e_mat, e_pos, nl_hist, nl_active, pair_model, pair_params,
                    period, reach)
                if state != 1:
                    continue
                count += 1
                if delta > worst * rmin:  # (a division only for a new largest)
                    worst = delta / rmin
                fx += px
                fy += py
                fz += pz
                tx += tix
                ty += tiy
                tz += tiz
                if j < hi:
                    b_force[j, 0] -= px
                    b_force[j, 1] -= py
                    b_force[j, 2] -= pz
                    b_torque[j, 0] += tjx
                    b_torque[j, 1] += tjy
                    b_torque[j, 2] += tjz
                else:  # j belongs to a later chunk: its sweep may be running
                    nl_f[kk, 0] = px
                    nl_f[kk, 1] = py
                    nl_f[kk, 2] = pz
                    nl_f[kk, 6] = tjx
                    nl_f[kk, 7] = tjy
                    nl_f[kk, 8] = tjz
            wcount, wworst = boundary_contacts(i, xi, yi, zi, ri, i, mi, dt, b_pos, b_vf, b_wf,
                                               b_mass, b_invmass, wl_start, wl_w, wl_hist,
                                               wl_active, wl_f, wl_tag, w_kind, w_par,
                                               w_owner, w_mat, w_ids, f_cur, pair_model,
                                               pair_params, reach)
            if wcount > 0:
                for q in range(wl_start[i], wl_start[i + 1]):
                    fx, fy, fz, tx, ty, tz = add_row(wl_f, q, fx, fy, fz, tx, ty, tz)
            b_force[i, 0] = fx
            b_force[i, 1] = fy
            b_force[i, 2] = fz
            b_torque[i, 0] = tx
            b_torque[i, 1] = ty
            b_torque[i, 2] = tz
            e_worst[i] = max(worst, wworst)
            e_count[i] = count + wcount
    for c in prange(nchunks):
        lo = bounds[c]
        hi = bounds[c + 1]
        first = nl_start[lo]  # pairs before it belong to earlier chunks
        for j in range(lo, hi):
            if lo > 0:
                for t in range(t_start[j + 1] - 1, t_start[j] - 1, -1):
                    kk = t_pair[t]
                    if kk < first and nl_active[kk]:
                        b_force[j, 0] -= nl_f[kk, 0]
                        b_force[j, 1] -= nl_f[kk, 1]
                        b_force[j, 2] -= nl_f[kk, 2]
                        b_torque[j, 0] += nl_f[kk, 6]
                        b_torque[j, 1] += nl_f[kk, 7]
                        b_torque[j, 2] += nl_f[kk, 8]
            if integrate and j < n_owned:
                post_force_body(j, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque,
                                b_invmass, b_invinertia, dt, b_aux)


@pjit
def sum_pass(dt, integrate, ctl, bodies, elems, pairs, walls):
    """Pass b: gravity plus the stored contact rows of each body's elements in a fixed
    order; then (if ``integrate``) step 5, the integrator's post-force part, for that body."""
    b_pos, b_vel, b_quat, b_angvel = bodies.pos, bodies.vel, bodies.quat, bodies.angvel
    b_force, b_torque, b_mass, b_invmass = (bodies.force, bodies.torque, bodies.mass,
                                            bodies.invmass)
    b_invinertia, b_aux, b_estart = bodies.invinertia, bodies.aux, bodies.estart
    nl_start, nl_f, t_start, t_pair = pairs.start, pairs.force, pairs.t_start, pairs.t_pair
    wl_start, wl_f = walls.start, walls.force
    e_count = elems.count
    gravity = ctl.gravity
    n_owned = ctl.n_owned
    for b in prange(b_force.shape[0]):
        m = b_mass[b]
        fx = m * gravity[0]
        fy = m * gravity[1]
        fz = m * gravity[2]
        tx = 0.0
        ty = 0.0
        tz = 0.0
        for e in range(b_estart[b], b_estart[b + 1]):
            # e_count[e]: touching contacts in e's own rows and boundary rows (contact
            # pass); none: nothing to add there (the sums are unchanged by skipping)
            own = e_count[e] > 0
            # rows of pairs that do not touch are zero (cleared when a pair stops touching
            # and at every rebuild), so they are added without a test: no mispredicted
            # branches where touching and non-touching pairs alternate
            for kk in range(nl_start[e], nl_start[e + 1] if own else nl_start[e]):
                fx, fy, fz, tx, ty, tz = add_row(nl_f, kk, fx, fy, fz, tx, ty, tz)
            for q in range(wl_start[e], wl_start[e + 1] if own else wl_start[e]):
                fx, fy, fz, tx, ty, tz = add_row(wl_f, q, fx, fy, fz, tx, ty, tz)
            # the pairs where e is the partner, from the last owner to the first (the
            # order of fused_pass, so that both give the same sums bit for bit)
            for t in range(t_start[e + 1] - 1, t_start[e] - 1, -1):
                kk = t_pair[t]
                fx -= nl_f[kk, 0]
                fy -= nl_f[kk, 1]
                fz -= nl_f[kk, 2]
                tx += nl_f[kk, 6]
                ty += nl_f[kk, 7]
                tz += nl_f[kk, 8]
        b_force[b, 0] = fx
        b_force[b, 1] = fy
        b_force[b, 2] = fz
        b_torque[b, 0] = tx
        b_torque[b, 1] = ty
        b_torque[b, 2] = tz
        if integrate and b < n_owned:
            post_force_body(b, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass,
                            b_invinertia, dt, b_aux)


@jit
def compute_forces(dt, integrate, ctl, bodies, elems, pairs, walls, bnd, diag):
    """Gravity plus all contact forces (passes a, b, c), then the integrator's post-force
    part if ``integrate``; returns the largest overlap / radius. Velocity-dependent forces
    see the velocities ``bodies.vf``, ``bodies.wf`` that the integrator's pre-force part set.

    With ``integrate`` False and ``dt`` = 0 it re-evaluates the forces of the current state
    without advancing the contact history.
    """
    if FUSED:  # a constant of the scene: only one of the two forms is compiled
        fused_pass(dt, integrate, ctl, bodies, elems, pairs, walls, bnd)
    else:
        contact_pass(dt, ctl, bodies, elems, pairs, walls, bnd)
        sum_pass(dt, integrate, ctl, bodies, elems, pairs, walls)
    w_owner = bnd.owner
    f_load = bnd.load
    wl_start, wl_w, wl_active, wl_f = walls.start, walls.key, walls.active, walls.force
    e_worst, e_count = elems.worst, elems.count
    for b in range(f_load.shape[0]):
        for d in range(6):
            f_load[b, d] = 0.0
    ne = e_worst.shape[0]
    # the load of owned elements only (ghosts' entries are their owner's to count)
    for q in range(wl_start[bodies.estart[ctl.n_owned]]):
        if wl_active[q]:
            b = w_owner[wl_w[q]]
            for d in range(3):
                f_load[b, d] -= wl_f[q, d]
                f_load[b, 3 + d] += wl_f[q, 6 + d]
    worst = 0.0
    worst_e = -1
    active = 0
    for i in range(ne):
        active += e_count[i]
        if e_worst[i] > worst:
            worst = e_worst[i]
            worst_e = i
    diag[6] = active
    if worst > diag[4]:
        diag[4] = worst
        diag[5] = worst_e
    return worst


@jit
def run_steps(nsteps, dt, ctl, bodies, elems, pairs, walls, bnd, diag, f_table):
    """Advance ``nsteps`` steps; stop early with a status in ``diag[0]``.

    ``f_table[s]`` holds the boundary frames at the end of step s (time t + (s+1) dt) for
    moving boundaries (an empty table: none moves).
    On a list overflow the step stops after :func:`pre_force`; the caller grows the
    buffers and calls :func:`finish_step` before going on.
    """
    diag[0] = STATUS_OK
    diag[1] = 0
    f_cur = bnd.frame
    for s in range(nsteps):
        if f_table.shape[0] > 0:
            row = min(s, f_table.shape[0] - 1)
            for b in range(f_cur.shape[0]):
                for c in range(f_cur.shape[1]):
                    f_cur[b, c] = f_table[row, b, c]
        pre_force(dt, ctl, bodies, elems)
        finish_step(dt, ctl, bodies, elems, pairs, walls, bnd, diag)
        if diag[0] == STATUS_OK or diag[0] == STATUS_OVERLAP:
            diag[1] = s + 1
        if diag[0] != STATUS_OK:
            return


@jit
def rebuild(ctl, bodies, elems, pairs, walls, bnd, diag):
    """Rebuild both lists; on overflow set the status and the needed size, change
    nothing."""
    # a law with an interaction range keeps contacts up to ctl.reach beyond touching
    skin = ctl.skin + ctl.reach
    e_pos, e_radius, e_ref = elems.pos, elems.radius, elems.ref
    nl_j = pairs.key
    # (an MPI rank's ghosts, the rows from first_ghost on, list no pairs among themselves
    # and no boundary entries: their owners compute those)
    first_ghost = bodies.estart[ctl.n_owned]
    need = build_neighbour_list(e_pos, e_radius, elems.owner, skin, pairs.start, nl_j,
                                pairs.hist, pairs.active, pairs.t_start, pairs.t_pair,
                                ctl.period, first_ghost)
    if need > nl_j.shape[0]:
        diag[0] = STATUS_OVERFLOW
        diag[3] = need
        return
    f_cur = bnd.frame
    wl_w = walls.key
    need = build_boundary_list(e_pos, e_radius, skin, f_cur, bnd.kind, bnd.par, bnd.grid_int,
                               bnd.grid_flt, bnd.cell_start, bnd.cell_items, bnd.prim_cells,
                               walls.start, wl_w, walls.hist, walls.active, first_ghost)
    if need > wl_w.shape[0]:
        diag[0] = STATUS_WALL_OVERFLOW
        diag[3] = need
        return
    for e in range(e_pos.shape[0]):
        for d in range(3):
            e_ref[e, d] = e_pos[e, d]
    f_ref = bnd.frame_ref
    for b in range(f_ref.shape[0]):
        for c in range(12):
            f_ref[b, c] = f_cur[b, c]
    diag[2] += 1


@jit
def needs_rebuild(ctl, elems, bnd):
    """After :func:`pre_force` (which left each element's squared displacement in
    ``elems.worst``): 1 if the lists must be rebuilt, 0 if not, -1 if a position is NaN.
    Elements may each move skin/2 before two of them can meet unseen; an element and a
    boundary together may move one skin. (An MPI backend takes the largest answer over its
    ranks: the decision is collective.)"""
    d2 = largest(elems.worst)
    if d2 != d2:
        return -1
    skin = ctl.skin
    moved = boundary_motion_since_rebuild(bnd.frame, bnd.frame_ref, bnd.extent)
    if d2 > 0.25 * skin * skin or math.sqrt(d2) + moved > skin:
        return 1
    return 0


@jit
def clear_list_rows(pairs, walls, n_elements):
    """After a rebuild the rows belong to new pairs; the contact pass fills touching ones."""
    if not FUSED:  # (fused_pass reads the rows of pairs across chunks only)
        clear_rows(pairs.force, pairs.start[n_elements])
    clear_rows(walls.force, walls.start[n_elements])


@jit
def finish_step(dt, ctl, bodies, elems, pairs, walls, bnd, diag):
    """Steps 3-5 of a step (after :func:`pre_force`); sets ``diag[0]`` on trouble."""
    need = needs_rebuild(ctl, elems, bnd)
    if need < 0:
        diag[0] = STATUS_NAN
        return
    if need > 0:
        rebuild(ctl, bodies, elems, pairs, walls, bnd, diag)
        if diag[0] != STATUS_OK:
            return
        clear_list_rows(pairs, walls, elems.pos.shape[0])
    # (a run-time True: a literal would compile compute_forces a second time)
    worst = compute_forces(dt, dt == dt, ctl, bodies, elems, pairs, walls, bnd, diag)
    boundary_work(dt, bnd)
    if worst > ctl.max_overlap:
        diag[0] = STATUS_OVERLAP


@jit
def boundary_work(dt, bnd):
    """Work [J] each boundary did on the particles in the step, added to ``load[:, 6]``:
    dt P with P = -(F . v_o + T . omega) at the step's end (F, T the load on the boundary,
    T about its frame origin o moving at v_o, omega its angular velocity; zero for a
    boundary at rest)."""
    f_load, fr = bnd.load, bnd.frame
    if f_load.shape[1] > 6:
        for b in range(f_load.shape[0]):
            p = 0.0
            for d in range(3):
                p -= f_load[b, d] * fr[b, 12 + d] + f_load[b, 3 + d] * fr[b, 15 + d]
            f_load[b, 6] += dt * p


@inline_jit
def candidate_distance(kind, par, w, lx, ly, lz, r, reach):
    """Distance of a sphere (radius r, centre at lx, ly, lz in the boundary's frame) to
    primitive ``w`` for the list search; +inf for a triangle whose plane lies farther than
    ``reach`` (rejected before its closest point). A triangle's geometry is inlined here,
    every other kind goes through ``closest_call``."""
    if HAS_TRIANGLES and kind[w] == TRIANGLE:
        if off_triangle_plane(par, w, lx, ly, lz, reach):
            return np.inf
        d = triangle_distance_within(par[w], lx, ly, lz, reach)[0]
        return np.inf if d >= reach else d
    return closest_call(kind[w], par[w], lx, ly, lz, r)[0]


@pjit
def boundary_search_pass(e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                         cell_start, cell_items, prim_cells, counts, out_start, out_end, out_w,
                         fill, visit):
    """counts[i] = boundary primitives within r + skin of element i, for the elements
    ``visit`` (``arange(n)``: the first n; the rest untouched). With ``fill`` they are also
    written, sorted, into out_w[out_start[i]:out_end[i]] (as many as fit: a count above the
    room says the slot was too small)."""
    nb = frame.shape[0]
    for q in prange(visit.shape[0]):
        i = visit[q]
        k0 = out_start[i] if fill else 0
        room = out_end[i] - k0 if fill else 0
        k = k0
        r = e_radius[i]
        reach = r + skin
        for b in range(nb):
            f = frame[b]
            lx, ly, lz = to_local(f, e_pos[i, 0], e_pos[i, 1], e_pos[i, 2])
            g = grid_int[b]
            if g[0] == 0:
                for w in range(g[5], g[6]):
                    d = candidate_distance(kind, par, w, lx, ly, lz, r, reach)
                    if in_range(kind[w], d, r, skin):
                        if k - k0 < room:
                            out_w[k] = w
                        k += 1
                continue
            h = grid_flt[b, 3]
            q0 = max(int(math.floor((lx - reach - grid_flt[b, 0]) / h)), 0)
            q1 = max(int(math.floor((ly - reach - grid_flt[b, 1]) / h)), 0)
            q2 = max(int(math.floor((lz - reach - grid_flt[b, 2]) / h)), 0)
            p0 = min(int(math.floor((lx + reach - grid_flt[b, 0]) / h)), g[1] - 1)
            p1 = min(int(math.floor((ly + reach - grid_flt[b, 1]) / h)), g[2] - 1)
            p2 = min(int(math.floor((lz + reach - grid_flt[b, 2]) / h)), g[3] - 1)
            for cx in range(q0, p0 + 1):
                for cy in range(q1, p1 + 1):
                    for cz in range(q2, p2 + 1):
                        cell = g[4] + (cx * g[2] + cy) * g[3] + cz
                        for t in range(cell_start[cell], cell_start[cell + 1]):
                            w = cell_items[t]
                            pc = prim_cells[w]
                            if (cx != max(pc[0], q0) or cy != max(pc[1], q1)
                                    or cz != max(pc[2], q2)):
                                continue  # found in an earlier cell of this query
                            d = candidate_distance(kind, par, w, lx, ly, lz, r, reach)
                            if in_range(kind[w], d, r, skin):
                                if k - k0 < room:
                                    out_w[k] = w
                                k += 1
        counts[i] = k - k0
        if fill:
            # grids yield primitives out of order: sort the element's slice
            for a in range(k0 + 1, k0 + min(k - k0, room)):
                v = out_w[a]
                c = a - 1
                while c >= k0 and out_w[c] > v:
                    out_w[c + 1] = out_w[c]
                    c -= 1
                out_w[c + 1] = v


@jit
def build_boundary_list(e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                        cell_start, cell_items, prim_cells, wl_start, wl_w, wl_hist,
                        wl_active, first_ghost):
    """Rebuild the element-primitive list (primitives within r + skin), merging history.
    Elements from ``first_ghost`` on (an MPI rank's ghosts) get no entries.

    As the pair list (:func:`build_neighbour_list`): one search pass writes each element's
    primitives into a transient slot sized by its entries in the previous list plus
    ``SLOT_SLACK``, then the slots are copied into the exact rows, sized by that pass'
    counts; a second pass fills the rows of the elements that outgrew their slots, and
    only those (a search pass is most of a rebuild's boundary part: one closest point per
    candidate).
    The new list is written into scratch arrays of its exact size, freed on return.

    Returns the number of entries; above the capacity nothing is changed.
    """
    n = e_pos.shape[0]
    counts = np.zeros(n, np.int64)
    slot_start = slot_starts(wl_start, n)
    slots = np.empty(slot_start[n], wl_w.dtype)  # transient: keys only
    boundary_search_pass(e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                         cell_start, cell_items, prim_cells, counts, slot_start,
                         slot_start[1:], slots, n >= 0, np.arange(first_ghost))
    fits, new_start = rows_of_counts(counts, slot_start)
    count = new_start[n]
    if count > wl_w.shape[0]:
        return count
    new_w = np.empty(count, wl_w.dtype)
    copy_slots(counts, slot_start, slots, new_start, new_w)
    if not fits:  # the elements that outgrew their slots: their exact rows, searched again
        again = outgrown(counts, slot_start, np.arange(n))
        boundary_search_pass(e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                             cell_start, cell_items, prim_cells, counts, new_start,
                             new_start[1:], new_w, n >= 0, again)
    new_hist = np.empty((count, wl_hist.shape[1]))
    new_active = np.empty(count, np.uint8)
    merge_history(wl_start, wl_w, wl_hist, wl_active, new_start, new_w, new_hist, new_active)
    copy_back(count, new_start, new_w, new_hist, new_active, wl_start, wl_w, wl_hist,
              wl_active)
    return count


@jit
def pair_overlaps(e_pos, e_radius, nl_start, nl_j, period):
    """Overlap / smaller radius of each listed pair (negative: apart), nearest periodic
    image; for the initial-overlap check (one float per pair, no temporaries)."""
    out = np.empty(nl_start[e_pos.shape[0]])
    for i in range(e_pos.shape[0]):
        for k in range(nl_start[i], nl_start[i + 1]):
            j = nl_j[k]
            dx = minimum_image(e_pos[i, 0] - e_pos[j, 0], period[3])
            dy = minimum_image(e_pos[i, 1] - e_pos[j, 1], period[4])
            dz = minimum_image(e_pos[i, 2] - e_pos[j, 2], period[5])
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            out[k] = (e_radius[i] + e_radius[j] - d) / min(e_radius[i], e_radius[j])
    return out


@jit
def entry_overlaps(e_pos, e_radius, wl_start, wl_w, kind, par, owner, frame):
    """Overlap / radius of each element-primitive entry (0 where not touching); for the
    initial-overlap check (here, so that it is cached with the step)."""
    out = np.zeros(wl_start[e_pos.shape[0]])
    for i in range(e_pos.shape[0]):
        r = e_radius[i]
        for q in range(wl_start[i], wl_start[i + 1]):
            w = wl_w[q]
            lx, ly, lz = to_local(frame[owner[w]], e_pos[i, 0], e_pos[i, 1], e_pos[i, 2])
            d, _, _, _, feature = closest_call(kind[w], par[w], lx, ly, lz, r)
            if touching(kind[w], d, r) and feature != JOINED:
                out[q] = (r - d) / r
    return out


@jit
def ranked_pre_force(dt, ctl, bodies, elems, bnd, f_table, s):
    """One rank's start of step s (:mod:`dpm.parallel.backend`): the boundary frames of the
    step, the pre-force part of the owned bodies (ghosts take their owners' state with the
    halo that follows), then the local rebuild answer (1, 0, -1 NaN) that the ranks
    combine. One compiled call instead of three: a call's arguments cost numba ~0.3 us
    per array to unpack."""
    if f_table.shape[0] > 0:
        f_cur = bnd.frame
        row = min(s, f_table.shape[0] - 1)
        for b in range(f_cur.shape[0]):
            for c in range(f_cur.shape[1]):
                f_cur[b, c] = f_table[row, b, c]
    pre_force(dt, ctl, bodies, elems)
    return needs_rebuild(ctl, elems, bnd)


@jit
def ranked_forces(dt, ctl, bodies, elems, pairs, walls, bnd, diag):
    """One rank's rest of a step: forces, the post-force part of owned bodies, the
    boundaries' work; returns the largest overlap / radius."""
    worst = compute_forces(dt, dt == dt, ctl, bodies, elems, pairs, walls, bnd, diag)
    boundary_work(dt, bnd)
    return worst


@jit
def ranked_halo_pack(send_rows, bodies, sbuf):
    """The halo rows a rank sends (:func:`dpm.kernels.halo.pack_halo`), for a halo that
    Python sends (the Python step loop; a rebuild with no migration): compiled in the
    scene's cached module, not as the library kernel at its first call."""
    pack_halo(send_rows, bodies.pos, bodies.quat, bodies.vf, bodies.wf, sbuf)


@jit
def ranked_halo_unpack(first_ghost, rbuf, bodies, elems, place):
    """The ghosts take the halo rows received (:func:`dpm.kernels.halo.unpack_halo`)."""
    unpack_halo(first_ghost, rbuf, bodies.pos, bodies.quat, bodies.vf, bodies.wf,
                bodies.estart, elems.offset, elems.pos, place)


#: why :func:`ranked_run` returned
RUN_DONE, RUN_REBUILD, RUN_NAN, RUN_OVERLAP, RUN_MPI_ERROR = 0, 1, 2, 3, 4


@jit
def ranked_run(s0, n, dt, ctl, bodies, elems, pairs, walls, bnd, f_table, diag,
               max_overlap, first_ghost, place, send_rows, send_rank, send_off, sbuf,
               recv_rank, recv_off, rbuf, requests, statuses, h, flags, acc):
    """Steps s0, s0 + 1, ... of one MPI rank with their messages, compiled (no Python
    between steps; :mod:`dpm.kernels.mpi_calls`), until step n or until a step needs
    what only Python does. Each step: :func:`ranked_pre_force`; owned rows
    ``send_rows[send_off[k]:send_off[k + 1]]`` packed for rank ``send_rank[k]``; then one
    wait for three things at once (:func:`dpm.kernels.mpi_calls.vote_and_halo`): the
    ranks' vote (``Iallreduce``, MAX) on this step's NaN and rebuild answers and on
    whether the previous step's forces passed the overlap limit, and the halo messages;
    the ghost rows from ``first_ghost`` on unpacked from ``rbuf`` (the messages of
    ``recv_rank`` in turn, elements placed with ``place``); :func:`ranked_forces`. So a
    step waits for the other ranks once, not three times (vote, halo, overlap vote).
    ``flags[2]``: in, whether the step before ``s0`` passed the overlap limit on this
    rank and has not been voted on; out (``RUN_DONE``), the same of step n - 1, for the
    caller to vote on. Returns (the step it stopped at, why: ``RUN_DONE`` at n,
    ``RUN_REBUILD`` with that step's pre-force part done and a rebuild agreed,
    ``RUN_NAN`` before it, ``RUN_OVERLAP`` when step s - 1 passed the limit (its forces
    done, s steps counted; step s's pre-force part done as well, the vote being folded
    into step s's), ``RUN_MPI_ERROR``). ``acc`` gathers seconds in the step kernels [0],
    in the vote and the halo [1] (waits for slower ranks included), the largest overlap
    [2]."""
    for s in range(s0, n):
        t0 = mpi_wtime()
        need = ranked_pre_force(dt, ctl, bodies, elems, bnd, f_table, s)
        t1 = mpi_wtime()
        acc[0] += t1 - t0
        flags[0] = 1 if need < 0 else 0
        flags[1] = 1 if need > 0 else 0
        pack_halo(send_rows, bodies.pos, bodies.quat, bodies.vf, bodies.wf, sbuf)
        if vote_and_halo(flags[0:3], flags[3:6], send_rank, send_off, sbuf, recv_rank,
                         recv_off, rbuf, requests, statuses, h) != 0:
            return s, RUN_MPI_ERROR
        t2 = mpi_wtime()
        acc[1] += t2 - t1
        if flags[5] != 0:
            return s, RUN_OVERLAP
        if flags[3] != 0:
            return s, RUN_NAN
        if flags[4] != 0:
            return s, RUN_REBUILD
        unpack_halo(first_ghost, rbuf, bodies.pos, bodies.quat, bodies.vf, bodies.wf,
                    bodies.estart, elems.offset, elems.pos, place)
        t3 = mpi_wtime()
        worst = ranked_forces(dt, ctl, bodies, elems, pairs, walls, bnd, diag)
        acc[0] += mpi_wtime() - t3
        acc[2] = max(acc[2], worst)
        flags[2] = 1 if worst > max_overlap else 0
    return n, RUN_DONE
