"""The step on an NVIDIA GPU (numba-cuda): kernels around the scene's own per-contact code.

The physics has one source. A scene's step module (:mod:`dpm.plan`, the two-pass form of
:mod:`.step`) holds its contact laws, boundary geometry, integrator parts and the
per-contact functions built from them (``pair_contact``, ``boundary_contacts``,
``pre_force_body`` ...). :func:`make_kernels` takes that module and binds the functions of
this file to its namespace: the device functions below call the very functions the CPU
step calls, and numba-cuda compiles those ``@njit`` functions for the device when a kernel
calls them (numba-cuda's typing context turns a CPU dispatcher into a device function
compiled from its Python source). Only the loops around them are written here: one
thread per body, element, pair or list entry instead of ``prange``.

A step is a fixed sequence of kernel launches with no host synchronisation
(:class:`dpm.backends.cuda.CudaBackend`): the rebuild decision, overflow and NaN flags
and the largest overlap live in a small device array (``state``, slots ``S_*``); every
kernel of the rebuild returns at once unless the decision kernel set ``S_REBUILD``, and
every kernel returns at once once ``S_STATUS`` is not OK, so that a run stopped by a
status on the device wastes only empty launches until the host reads the status (once per
call, or every ``poll`` steps).

Neighbour search on the device (Green 2008, "Particle Simulation using CUDA"; the
LIGGGHTS/HOOMD cell list in hashed form): the cell of an element is floor(x / h) with
h = 2 r_max + skin (along a periodic axis: the period cut into cells at least h wide); its
bucket is a hash of the cell into a table of ``2^k >= n`` buckets; elements are sorted
into buckets by a counting sort (atomic counts, an exclusive scan, atomic scatter); an
element's candidates are the elements in the buckets of its 27 neighbour cells whose own
cell is that neighbour cell (a hash collision only adds candidates that fail this test).
The hashed table needs no bounding box (no host read-back) and no grid that grows with
the scene's extent. Each element writes its partners j > i (within r_i + r_j + skin, not
of its own body, nearest periodic image) and sorts its row, so the list is the CPU list
entry for entry: its history is carried over by partner id with the CPU's merge, and the
transposed index lists the pairs of each partner in increasing order, so that the
per-body sums add the same terms in the same order as the CPU's two-pass form.

Under the CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``) the kernels run as Python threads
and the ``@njit`` functions they call run as compiled CPU code: kernel arguments arrive
wrapped, so each kernel is entered through a wrapper that unwraps its arrays
(:func:`_raw`); on a GPU the kernels are compiled as they are.
"""
# ruff: noqa: F811
import math

import numpy as np
from numba import cuda, njit
from numba.core.dispatcher import Dispatcher

from .boundary_geometry import in_range
from .boundary_search import boundary_motion_since_rebuild, to_local
from .config import JIT
from .neighbours import minimum_image
from .step import (
    add_row,
    boundary_contacts,
    closest,
    pair_contact,
    place_elements,
    post_force_body,
    pre_force_body,
    pre_force_sphere,
    wrap_body,
)

#: threads per block of the per-item kernels
BLOCK = 128
#: threads per block of the scan (a power of two)
SCAN_BLOCK = 256

# slots of the device state array (float64)
S_STATUS = 0  # the step status (dpm.backends.base STATUS_*)
S_STEPS = 1  # steps done in this call
S_REBUILDS = 2  # list rebuilds in this call
S_NEEDED = 3  # entries a full list needed
S_WORST = 4  # largest overlap / radius since the last reset
S_WORST_E = 5  # its element
S_ACTIVE = 6  # touching contacts of the last force evaluation
S_REBUILD = 7  # 1: the lists are rebuilt in this step
S_D2 = 8  # largest squared displacement since the rebuild (this step)
S_NAN = 9  # 1: a position is NaN
S_STEP_WORST = 10  # largest overlap / radius of this step
S_STEP_WORST_E = 11  # its element (smallest index)
S_STEP_ACTIVE = 12  # touching contacts of this step
S_PAIRS = 13  # entries of the new pair list
S_WALLS = 14  # entries of the new boundary list
N_STATE = 16

STATUS_OK = 0
STATUS_OVERFLOW = 1
STATUS_NAN = 2
STATUS_OVERLAP = 3
STATUS_WALL_OVERFLOW = 4

#: multipliers of the cell hash (Teschner et al. 2003)
H1 = 73856093
H2 = 19349663
H3 = 83492791


#: the type of a Python function (the kernel layer imports only numpy, numba and math)
FunctionType = type(lambda: None)


class Kernels:
    """The kernels of a scene, by name (attributes)."""

    def __init__(self, **kernels) -> None:
        self.__dict__.update(kernels)


def _raw(a):
    """The NumPy array behind a simulator kernel argument (others unchanged)."""
    item = getattr(a, "__dict__", {}).get("_item")
    if item is not None:
        return item._ary
    return a


# ---------------------------------------------------------------------- device functions
# (plain functions: :func:`make_kernels` binds them to the scene's namespace and compiles
# them as ``@njit(inline="always")`` functions, which the kernels call)

def cell_of(x, lo, length, h, nc):
    """Cell index of coordinate x along one axis: floor(x / h), or along a periodic axis
    of length ``length`` the cell of the wrapped coordinate among ``nc`` cells."""
    if length > 0.0:
        k = int(math.floor((x - lo) / length * nc))
        k = k % nc
        return k
    return int(math.floor(x / h))


def bucket_of(cx, cy, cz, mask):
    """Bucket of cell (cx, cy, cz) in a table of mask + 1 buckets."""
    return ((cx * H1) ^ (cy * H2) ^ (cz * H3)) & mask


def axis_range(c, length, nc):
    """(first, count) of the neighbour cells of cell c along one axis (wrapped on a
    periodic axis, all of its cells if it has fewer than 3)."""
    if length > 0.0 and nc < 3:
        return 0, nc
    return c - 1, 3


def search_pairs(i, e_pos, e_radius, e_owner, skin, period, h, ncell, cells, mask,
                 bucket_start, order, out_j, first, fill):
    """Partners j > i of element i (within r_i + r_j + skin, another body, nearest
    image): their number; with ``fill`` also written, sorted, to out_j[first:]."""
    xi = e_pos[i, 0]
    yi = e_pos[i, 1]
    zi = e_pos[i, 2]
    ri = e_radius[i] + skin
    oi = e_owner[i]
    fx, nx = axis_range(cells[i, 0], period[3], ncell[0])
    fy, ny = axis_range(cells[i, 1], period[4], ncell[1])
    fz, nz = axis_range(cells[i, 2], period[5], ncell[2])
    count = 0
    for tz in range(nz):
        gz = fz + tz
        if period[5] > 0.0:
            gz = gz % ncell[2]
        for ty in range(ny):
            gy = fy + ty
            if period[4] > 0.0:
                gy = gy % ncell[1]
            for tx in range(nx):
                gx = fx + tx
                if period[3] > 0.0:
                    gx = gx % ncell[0]
                bk = bucket_of(gx, gy, gz, mask)
                for s in range(bucket_start[bk], bucket_start[bk + 1]):
                    j = order[s]
                    if j <= i or cells[j, 0] != gx or cells[j, 1] != gy or cells[j, 2] != gz:
                        continue
                    dx = minimum_image(xi - e_pos[j, 0], period[3])
                    dy = minimum_image(yi - e_pos[j, 1], period[4])
                    dz = minimum_image(zi - e_pos[j, 2], period[5])
                    cut = ri + e_radius[j]
                    if dx * dx + dy * dy + dz * dz < cut * cut and e_owner[j] != oi:
                        if fill:  # insertion into the sorted row of i
                            k = first + count
                            while k > first and out_j[k - 1] > j:
                                out_j[k] = out_j[k - 1]
                                k -= 1
                            out_j[k] = j
                        count += 1
    return count


def search_boundaries(i, e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                      cell_start, cell_items, prim_cells, out_w, first, fill):
    """Boundary primitives within r + skin of element i (the grid over a mesh's
    triangles as on the CPU, ``step.boundary_search_pass``): their number; with ``fill``
    also written, sorted, to out_w[first:]."""
    k = first
    r = e_radius[i]
    reach = r + skin
    for b in range(frame.shape[0]):
        f = frame[b]
        lx, ly, lz = to_local(f, e_pos[i, 0], e_pos[i, 1], e_pos[i, 2])
        g = grid_int[b]
        if g[0] == 0:
            for w in range(g[5], g[6]):
                d = closest(kind[w], par[w], lx, ly, lz, r)[0]
                if in_range(kind[w], d, r, skin):
                    if fill:
                        out_w[k] = w
                    k += 1
            continue
        hh = grid_flt[b, 3]
        q0 = max(int(math.floor((lx - reach - grid_flt[b, 0]) / hh)), 0)
        q1 = max(int(math.floor((ly - reach - grid_flt[b, 1]) / hh)), 0)
        q2 = max(int(math.floor((lz - reach - grid_flt[b, 2]) / hh)), 0)
        p0 = min(int(math.floor((lx + reach - grid_flt[b, 0]) / hh)), g[1] - 1)
        p1 = min(int(math.floor((ly + reach - grid_flt[b, 1]) / hh)), g[2] - 1)
        p2 = min(int(math.floor((lz + reach - grid_flt[b, 2]) / hh)), g[3] - 1)
        for cx in range(q0, p0 + 1):
            for cy in range(q1, p1 + 1):
                for cz in range(q2, p2 + 1):
                    cell = g[4] + (cx * g[2] + cy) * g[3] + cz
                    for t in range(cell_start[cell], cell_start[cell + 1]):
                        w = cell_items[t]
                        if (cx != max(prim_cells[w, 0], q0) or cy != max(prim_cells[w, 1], q1)
                                or cz != max(prim_cells[w, 2], q2)):
                            continue  # found in an earlier cell of this query
                        d = closest(kind[w], par[w], lx, ly, lz, r)[0]
                        if in_range(kind[w], d, r, skin):
                            if fill:
                                out_w[k] = w
                            k += 1
    if fill:  # grids yield primitives out of order: sort the row
        for a in range(first + 1, k):
            v = out_w[a]
            c = a - 1
            while c >= first and out_w[c] > v:
                out_w[c + 1] = out_w[c]
                c -= 1
            out_w[c + 1] = v
    return k - first


def merge_row(i, old_start, old_key, old_hist, old_active, new_start, new_key, new_hist,
              new_active):
    """History rows and active flags of element i's entries carried from the old sorted
    row to the new one (``neighbours._merge``, one element)."""
    h = old_hist.shape[1]
    a = old_start[i]
    a_end = old_start[i + 1]
    for k in range(new_start[i], new_start[i + 1]):
        key = new_key[k]
        while a < a_end and old_key[a] < key:
            a += 1
        if a < a_end and old_key[a] == key:
            for c in range(h):
                new_hist[k, c] = old_hist[a, c]
            new_active[k] = old_active[a]
        else:
            for c in range(h):
                new_hist[k, c] = 0.0
            new_active[k] = 0


def sort_row(a, lo, hi):
    """Sort a[lo:hi] in place (insertion: rows are short)."""
    for p in range(lo + 1, hi):
        v = a[p]
        c = p - 1
        while c >= lo and a[c] > v:
            a[c + 1] = a[c]
            c -= 1
        a[c + 1] = v


def body_pre_force(b, dt, spin_only, periodic, update_elements, n_owned, period, b_pos,
                   b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass, b_invinertia, b_vf,
                   b_wf, b_aux, b_estart, e_offset, e_pos, e_ref, e_d2):
    """``step.pre_force`` for body b; returns the largest squared displacement of its
    elements since the rebuild."""
    if b < n_owned:
        if spin_only:
            pre_force_sphere(b, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass,
                             b_invinertia, dt, b_vf, b_wf, b_aux)
        else:
            pre_force_body(b, b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass,
                           b_invinertia, dt, b_vf, b_wf, b_aux)
        if periodic:
            wrap_body(b, period, b_pos, b_estart, e_ref)
    if update_elements:
        place_elements(b, b_pos, b_quat, b_estart, e_offset, e_pos)
    worst = 0.0
    for e in range(b_estart[b], b_estart[b + 1]):
        dx = e_pos[e, 0] - e_ref[e, 0]
        dy = e_pos[e, 1] - e_ref[e, 1]
        dz = e_pos[e, 2] - e_ref[e, 2]
        d2 = dx * dx + dy * dy + dz * dz
        e_d2[e] = d2
        if not d2 <= worst:
            worst = d2
    return worst


def element_contacts(i, dt, b_pos, b_vel, b_angvel, b_mass, b_invmass, e_owner, e_radius,
                     e_mat, e_pos, e_worst, e_count, nl_start, nl_j, nl_hist, nl_active, nl_f,
                     walls, pair_model, pair_params, period, bnd):
    """Pass a of ``step.contact_pass`` for element i (its pairs and boundary entries, each
    into its force row). ``walls`` and ``bnd``: tuples of the boundary list's and the
    boundary table's arrays (a call with more than 30 arguments is compiled by CPython as
    a call with ``*args``, which numba-cuda cannot inline)."""
    wl_start, wl_w, wl_hist, wl_active, wl_f, wl_tag = walls
    w_kind, w_par, w_owner, w_mat, w_ids, f_cur = bnd
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
            e_owner, e_radius, e_mat, e_pos, nl_hist, nl_active, pair_model, pair_params,
            period, 0.0)  # (no interaction range: the CUDA backend refuses JKR)
        if state == 1:
            count += 1
            if delta > worst * rmin:
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
    wcount, wworst = boundary_contacts(i, xi, yi, zi, ri, bi, mi, dt, b_pos, b_vel, b_angvel,
                                       b_mass, b_invmass, wl_start, wl_w, wl_hist, wl_active,
                                       wl_f, wl_tag, w_kind, w_par, w_owner, w_mat, w_ids,
                                       f_cur, pair_model, pair_params, 0.0)
    e_worst[i] = max(worst, wworst)
    e_count[i] = count + wcount


def body_sum(b, dt, integrate, n_owned, g0, g1, g2, b_pos, b_vel, b_quat, b_angvel, b_force,
             b_torque, b_mass, b_invmass, b_invinertia, b_aux, b_estart, nl_start, nl_f,
             t_start, t_pair, wl_start, wl_f, e_count):
    """Pass b of ``step.sum_pass`` for body b: gravity plus its rows in the CPU's order,
    then the integrator's post-force part."""
    m = b_mass[b]
    fx = m * g0
    fy = m * g1
    fz = m * g2
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for e in range(b_estart[b], b_estart[b + 1]):
        own = e_count[e] > 0
        for kk in range(nl_start[e], nl_start[e + 1] if own else nl_start[e]):
            fx, fy, fz, tx, ty, tz = add_row(nl_f, kk, fx, fy, fz, tx, ty, tz)
        for q in range(wl_start[e], wl_start[e + 1] if own else wl_start[e]):
            fx, fy, fz, tx, ty, tz = add_row(wl_f, q, fx, fy, fz, tx, ty, tz)
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


def decide(state, skin, frame, frame_ref, extent):
    """The rebuild decision of ``step.needs_rebuild`` from the step's largest squared
    displacement (``state[S_D2]``); a NaN position sets the NaN status."""
    if state[S_NAN] != 0.0:
        state[S_STATUS] = STATUS_NAN
        return
    d2 = state[S_D2]
    moved = boundary_motion_since_rebuild(frame, frame_ref, extent)
    if d2 > 0.25 * skin * skin or math.sqrt(d2) + moved > skin:
        state[S_REBUILD] = 1.0
    else:
        state[S_REBUILD] = 0.0


def step_end(state, max_overlap, dt, f_load, frame):
    """The step's reductions into the run's: largest overlap and its element, touching
    contacts, the boundaries' work (``step.boundary_work``), the overlap status, the step
    count; then the per-step slots are reset."""
    worst = state[S_STEP_WORST]
    state[S_ACTIVE] = state[S_STEP_ACTIVE]
    if worst > state[S_WORST]:
        state[S_WORST] = worst
        state[S_WORST_E] = state[S_STEP_WORST_E]
    if f_load.shape[1] > 6:
        for b in range(f_load.shape[0]):
            p = 0.0
            for d in range(3):
                p -= f_load[b, d] * frame[b, 12 + d] + f_load[b, 3 + d] * frame[b, 15 + d]
            f_load[b, 6] += dt * p
    if worst > max_overlap:
        state[S_STATUS] = STATUS_OVERLAP
    state[S_STEPS] += 1.0
    state[S_STEP_WORST] = 0.0
    state[S_STEP_WORST_E] = 1e300
    state[S_STEP_ACTIVE] = 0.0
    state[S_D2] = 0.0


# ---------------------------------------------------------------------- kernels
# (``gate``: the kernels of the rebuild run only when the decision asked for it)

def k_set_frame(state, frame, table, row):
    t = cuda.grid(1)
    nc = frame.shape[1]
    if state[S_STATUS] == STATUS_OK and t < frame.shape[0] * nc:
        frame[t // nc, t % nc] = table[row, t // nc, t % nc]


def k_pre_force(state, n, dt, spin_only, periodic, update_elements, n_owned, period, b_pos,
                b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass, b_invinertia, b_vf,
                b_wf, b_aux, b_estart, e_offset, e_pos, e_ref, e_d2):
    b = cuda.grid(1)
    if b >= n or state[S_STATUS] != STATUS_OK:
        return
    worst = body_pre_force(b, dt, spin_only, periodic, update_elements, n_owned, period,
                           b_pos, b_vel, b_quat, b_angvel, b_force, b_torque, b_invmass,
                           b_invinertia, b_vf, b_wf, b_aux, b_estart, e_offset, e_pos, e_ref,
                           e_d2)
    if worst != worst:
        state[S_NAN] = 1.0
    elif worst > 0.0:
        cuda.atomic.max(state, S_D2, worst)


def k_decide(state, skin, frame, frame_ref, extent):
    if cuda.grid(1) == 0 and state[S_STATUS] == STATUS_OK:
        decide(state, skin, frame, frame_ref, extent)


def k_zero(state, gate, a, n):
    t = cuda.grid(1)
    if t < n and state[S_STATUS] == STATUS_OK and (gate == 0 or state[S_REBUILD] != 0.0):
        a[t] = 0


def k_cells(state, n, e_pos, period, h, ncell, mask, cells, bucket, bucket_count):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    cx = cell_of(e_pos[i, 0], period[0], period[3], h, ncell[0])
    cy = cell_of(e_pos[i, 1], period[1], period[4], h, ncell[1])
    cz = cell_of(e_pos[i, 2], period[2], period[5], h, ncell[2])
    cells[i, 0] = cx
    cells[i, 1] = cy
    cells[i, 2] = cz
    bk = bucket_of(cx, cy, cz, mask)
    bucket[i] = bk
    cuda.atomic.add(bucket_count, bk, 1)


def k_scatter(state, n, key, cursor, order):
    """Counting sort's scatter: item i to the next free slot of its key's range."""
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    slot = cuda.atomic.add(cursor, key[i], 1)
    order[slot] = i


def k_copy(state, gate, src, dst, n):
    t = cuda.grid(1)
    if t < n and state[S_STATUS] == STATUS_OK and (gate == 0 or state[S_REBUILD] != 0.0):
        dst[t] = src[t]


def k_scan_block(state, gate, vals, n, out, sums):
    """Exclusive scan within each block of SCAN_BLOCK items (Hillis-Steele in shared
    memory); sums[block] = the block's total."""
    if state[S_STATUS] != STATUS_OK or (gate != 0 and state[S_REBUILD] == 0.0):
        return
    buf = cuda.shared.array(SCAN_BLOCK, np.int64)
    t = cuda.threadIdx.x
    i = cuda.blockIdx.x * SCAN_BLOCK + t
    v = 0
    if i < n:
        v = vals[i]
    buf[t] = v
    cuda.syncthreads()
    off = 1
    while off < SCAN_BLOCK:
        x = 0
        if t >= off:
            x = buf[t - off]
        cuda.syncthreads()
        buf[t] += x
        cuda.syncthreads()
        off *= 2
    if i < n:
        out[i] = buf[t] - v
    if t == SCAN_BLOCK - 1:
        sums[cuda.blockIdx.x] = buf[t]


def k_scan_sums(state, gate, sums, nblocks, out, n, slot, capacity, status):
    """Exclusive scan of the block totals by one block of up to SCAN_BLOCK threads (chunks
    of blockDim items, a carry between them); out[n] = the total; a total above
    ``capacity`` (>= 0) sets ``status`` and the entries needed."""
    if state[S_STATUS] != STATUS_OK or (gate != 0 and state[S_REBUILD] == 0.0):
        return
    buf = cuda.shared.array(SCAN_BLOCK, np.int64)
    t = cuda.threadIdx.x
    width = cuda.blockDim.x
    carry = 0
    for c0 in range(0, nblocks, width):
        i = c0 + t
        v = 0
        if i < nblocks:
            v = sums[i]
        buf[t] = v
        cuda.syncthreads()
        off = 1
        while off < width:
            x = 0
            if t >= off:
                x = buf[t - off]
            cuda.syncthreads()
            buf[t] += x
            cuda.syncthreads()
            off *= 2
        if i < nblocks:
            sums[i] = carry + buf[t] - v
        carry += buf[width - 1]
        cuda.syncthreads()
    if t == 0:
        out[n] = carry
        if slot >= 0:
            state[slot] = carry
        if capacity >= 0 and carry > capacity:
            state[S_STATUS] = status
            state[S_NEEDED] = carry


def k_scan_add(state, gate, out, n, sums):
    i = cuda.grid(1)
    if i < n and state[S_STATUS] == STATUS_OK and (gate == 0 or state[S_REBUILD] != 0.0):
        out[i] += sums[i // SCAN_BLOCK]


def k_pair_count(state, n, e_pos, e_radius, e_owner, skin, period, h, ncell, cells, mask,
                 bucket_start, order, counts, out_j):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    counts[i] = search_pairs(i, e_pos, e_radius, e_owner, skin, period, h, ncell, cells, mask,
                             bucket_start, order, out_j, 0, False)


def k_pair_fill(state, n, e_pos, e_radius, e_owner, skin, period, h, ncell, cells, mask,
                bucket_start, order, new_start, new_j):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    search_pairs(i, e_pos, e_radius, e_owner, skin, period, h, ncell, cells, mask,
                 bucket_start, order, new_j, new_start[i], True)


def k_wall_count(state, n, e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                 cell_start, cell_items, prim_cells, counts, out_w):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    counts[i] = search_boundaries(i, e_pos, e_radius, skin, frame, kind, par, grid_int,
                                  grid_flt, cell_start, cell_items, prim_cells, out_w, 0,
                                  False)


def k_wall_fill(state, n, e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                cell_start, cell_items, prim_cells, new_start, new_w):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    search_boundaries(i, e_pos, e_radius, skin, frame, kind, par, grid_int, grid_flt,
                      cell_start, cell_items, prim_cells, new_w, new_start[i], True)


def k_merge(state, n, old_start, old_key, old_hist, old_active, new_start, new_key,
            new_hist, new_active):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    merge_row(i, old_start, old_key, old_hist, old_active, new_start, new_key, new_hist,
              new_active)


def k_copy_back(state, count_slot, new_start, new_key, new_hist, new_active, start, key, hist,
                active, force):
    """The new list over the old one; its force rows cleared."""
    t = cuda.grid(1)
    if state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    if t < new_start.shape[0]:
        start[t] = new_start[t]
    if t < state[count_slot]:
        key[t] = new_key[t]
        active[t] = new_active[t]
        for c in range(hist.shape[1]):
            hist[t, c] = new_hist[t, c]
        for c in range(force.shape[1]):
            force[t, c] = 0.0


def k_transpose_count(state, nl_start_n, nl_j, t_count):
    k = cuda.grid(1)
    if state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    if k < nl_start_n[nl_start_n.shape[0] - 1]:
        cuda.atomic.add(t_count, nl_j[k], 1)


def k_transpose_fill(state, nl_start, nl_j, cursor, t_pair):
    k = cuda.grid(1)
    if state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    if k < nl_start[nl_start.shape[0] - 1]:
        slot = cuda.atomic.add(cursor, nl_j[k], 1)
        t_pair[slot] = k


def k_sort_rows(state, n, start, a):
    i = cuda.grid(1)
    if i < n and state[S_STATUS] == STATUS_OK and state[S_REBUILD] != 0.0:
        sort_row(a, start[i], start[i + 1])


def k_rebuilt(state, n, e_pos, e_ref, frame, frame_ref):
    """References of the new lists (element positions, boundary frames); the rebuild
    counted and its flag cleared by the last thread's successor kernel."""
    t = cuda.grid(1)
    if state[S_STATUS] != STATUS_OK or state[S_REBUILD] == 0.0:
        return
    if t < n:
        for d in range(3):
            e_ref[t, d] = e_pos[t, d]
    if t < frame_ref.shape[0]:
        for c in range(12):
            frame_ref[t, c] = frame[t, c]


def k_rebuild_done(state):
    if cuda.grid(1) == 0 and state[S_STATUS] == STATUS_OK and state[S_REBUILD] != 0.0:
        state[S_REBUILDS] += 1.0
        state[S_REBUILD] = 0.0


def k_contacts(state, n, dt, b_pos, b_vel, b_angvel, b_mass, b_invmass, e_owner, e_radius,
               e_mat, e_pos, e_worst, e_count, nl_start, nl_j, nl_hist, nl_active, nl_f,
               wl_start, wl_w, wl_hist, wl_active, wl_f, wl_tag, pair_model, pair_params,
               period, w_kind, w_par, w_owner, w_mat, w_ids, f_cur):
    i = cuda.grid(1)
    if i >= n or state[S_STATUS] != STATUS_OK:
        return
    element_contacts(i, dt, b_pos, b_vel, b_angvel, b_mass, b_invmass, e_owner, e_radius,
                     e_mat, e_pos, e_worst, e_count, nl_start, nl_j, nl_hist, nl_active, nl_f,
                     (wl_start, wl_w, wl_hist, wl_active, wl_f, wl_tag), pair_model,
                     pair_params, period, (w_kind, w_par, w_owner, w_mat, w_ids, f_cur))
    w = e_worst[i]
    if w > 0.0:
        cuda.atomic.max(state, S_STEP_WORST, w)
    if e_count[i] > 0:
        cuda.atomic.add(state, S_STEP_ACTIVE, float(e_count[i]))


def k_sums(state, n, dt, integrate, n_owned, gravity, b_pos, b_vel, b_quat, b_angvel,
           b_force, b_torque, b_mass, b_invmass, b_invinertia, b_aux, b_estart, nl_start,
           nl_f, t_start, t_pair, wl_start, wl_f, e_count):
    b = cuda.grid(1)
    if b >= n or state[S_STATUS] != STATUS_OK:
        return
    body_sum(b, dt, integrate, n_owned, gravity[0], gravity[1], gravity[2], b_pos, b_vel,
             b_quat, b_angvel, b_force, b_torque, b_mass, b_invmass, b_invinertia, b_aux,
             b_estart, nl_start, nl_f, t_start, t_pair, wl_start, wl_f, e_count)


def k_zero_loads(state, f_load):
    t = cuda.grid(1)
    if t < f_load.shape[0] * 6 and state[S_STATUS] == STATUS_OK:
        f_load[t // 6, t % 6] = 0.0


def k_loads(state, n_owned, b_estart, wl_start, wl_w, wl_active, wl_f, w_owner, f_load,
            e_worst):
    """Boundary loads (owned elements' entries) and the element of the step's largest
    overlap (the smallest index holding it, as the CPU's first strict maximum)."""
    t = cuda.grid(1)
    if state[S_STATUS] != STATUS_OK:
        return
    if t < wl_start[b_estart[n_owned]] and wl_active[t]:
        b = w_owner[wl_w[t]]
        for d in range(3):
            cuda.atomic.add(f_load, (b, d), -wl_f[t, d])
            cuda.atomic.add(f_load, (b, 3 + d), wl_f[t, 6 + d])
    if t < e_worst.shape[0]:
        w = state[S_STEP_WORST]
        if w > 0.0 and e_worst[t] == w:
            cuda.atomic.min(state, S_STEP_WORST_E, float(t))


def k_step_end(state, max_overlap, dt, f_load, frame):
    if cuda.grid(1) == 0 and state[S_STATUS] == STATUS_OK:
        step_end(state, max_overlap, dt, f_load, frame)


DEVICE_FUNCTIONS = ("cell_of", "bucket_of", "axis_range", "search_pairs", "search_boundaries",
                    "merge_row", "sort_row", "body_pre_force", "element_contacts", "body_sum",
                    "decide", "step_end")
KERNELS = tuple(name for name in dir() if name.startswith("k_"))
#: names the device functions take from the scene's step module
SCENE_NAMES = ("closest", "pair_contact", "boundary_contacts", "place_elements", "wrap_body",
               "pre_force_body", "pre_force_sphere", "post_force_body", "add_row")


def _pure(fn, memo: dict):
    """The pure-Python form of a jitted function and of every jitted function it reaches
    (their module globals mirrored with the dispatchers replaced), for the simulator."""
    if not isinstance(fn, Dispatcher):
        return fn
    key = id(fn)
    if key in memo:
        return memo[key]
    py = fn.py_func
    gkey = id(py.__globals__)
    if gkey not in memo:
        memo[gkey] = dict(py.__globals__)
        mirror = memo[gkey]
        for k, v in list(mirror.items()):
            if isinstance(v, Dispatcher):
                mirror[k] = _LazyPure(v, memo)
    out = FunctionType(py.__code__, memo[gkey], py.__name__, py.__defaults__, py.__closure__)
    memo[key] = out
    return out


class _LazyPure:
    """A dispatcher's pure-Python form, made at its first call."""

    __slots__ = ("disp", "memo", "fn")

    def __init__(self, disp, memo: dict) -> None:
        self.disp, self.memo, self.fn = disp, memo, None

    def __call__(self, *args):
        if self.fn is None:
            self.fn = _pure(self.disp, self.memo)
        return self.fn(*args)


def make_kernels(step_module, simulator: bool, python: bool = False) -> Kernels:
    """The kernels of this file bound to a scene's step module (its ``closest``, contact
    laws and integrator parts); on the simulator, entered through :func:`_raw`. With
    ``python`` (the simulator only) the device functions and everything they call run as
    pure Python (the same source, nothing compiled: for small scenes, where compiling them
    for the CPU costs more than running them interpreted)."""
    ns = dict(globals())
    memo: dict = {}
    for name in SCENE_NAMES:
        ns[name] = getattr(step_module, name)
        if python:
            ns[name] = _pure(ns[name], memo)
    for name in ("in_range", "to_local", "minimum_image", "boundary_motion_since_rebuild"):
        if python:
            ns[name] = _pure(ns[name], memo)
    opts = dict(JIT, inline="always")
    opts.pop("cache", None)
    for name in DEVICE_FUNCTIONS:
        fn = globals()[name]
        fn = FunctionType(fn.__code__, ns, name, fn.__defaults__)
        ns[name] = fn if python else njit(**opts)(fn)
    out = {}
    for name in KERNELS:
        fn = globals()[name]
        body = FunctionType(fn.__code__, ns, name, fn.__defaults__)
        if simulator:
            ns[f"_{name}_body"] = body
            src = (f"def {name}(*args):\n"
                   f"    return _{name}_body(*[_raw(a) for a in args])\n")
            exec(compile(src, f"<dpm cuda kernel {name}>", "exec"), ns)
            out[name] = cuda.jit(ns[name])
        else:
            out[name] = cuda.jit(body)
    return Kernels(**out)
