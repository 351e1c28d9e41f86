"""Linked-cell binning, Verlet neighbour lists with a skin, contact history merge.

Element pairs: a half list in CSR form. For element i, ``nl_j[nl_start[i]:nl_start[i+1]]``
holds the elements j > i (sorted) within r_i + r_j + skin, excluding elements of the same
body. Each entry owns a row of contact history and an ``active`` flag (touching at the last
force evaluation), so a rebuild carries both to the new list by walking the old and new
sorted lists (no hashing). A transposed index (``t_start``, ``t_pair``) lists for every
element j the pairs where it is the second element, for the race-free force sum.

Element-plane contacts: the same CSR form keyed by (element, plane), for planes within
r + skin of the element's centre.

Both lists stay valid while no element moved more than skin/2 since the rebuild (the
step's ``needs_rebuild``). The pair search runs in parallel in two passes (count,
then fill), so the lists are identical for any number of threads.
"""

import math

import numpy as np
from numba import prange

from .config import inline_jit, jit, pjit

#: at most this many cells per element (a sparse scene gets coarser cells). A dilute
#: scene (a stream of spheres falling through a tall container) fills little of its
#: bounding box: with 2 cells per element the meshGran port's stream got cells 3x the
#: needed width and its search scanned ~27x the candidates; 32 halves its search while the
#: binning's cost per cell stays small
CELLS_PER_ELEMENT = 32
#: and never more cells than this (64 MiB of cell starts), whatever the element count
MAX_CELLS = 1 << 23


@jit
def bin_elements(e_pos, cell_size, period):
    """Counting-sort elements into a regular grid of cells at least ``cell_size`` wide.

    ``period`` (6,): lower corner and length of the periodic box per axis (length 0: that
    axis is not periodic). Along a periodic axis the grid spans exactly the period and
    positions are wrapped into it.

    Returns (lo, width, dims, cell_start, order): element order[cell_start[c]:cell_start[c+1]]
    lie in cell c = ix + dims[0] * (iy + dims[1] * iz).
    """
    n = e_pos.shape[0]
    lo = np.empty(3)
    hi = np.empty(3)
    for d in range(3):
        lo[d] = np.inf
        hi[d] = -np.inf
    for i in range(n):
        for d in range(3):
            x = e_pos[i, d]
            if x < lo[d]:
                lo[d] = x
            if x > hi[d]:
                hi[d] = x
    for d in range(3):
        if period[3 + d] > 0.0:
            lo[d] = period[d]
            hi[d] = period[d] + period[3 + d]
    dims = np.ones(3, dtype=np.int64)
    for d in range(3):
        if n > 0 and hi[d] > lo[d]:
            dims[d] = max(1, int((hi[d] - lo[d]) / cell_size))
    limit = min(CELLS_PER_ELEMENT * n + 27, MAX_CELLS)
    total = float(dims[0]) * dims[1] * dims[2]  # (float: a far-flung element's box
    # could overflow an integer product)
    if total > limit:
        f = (total / limit) ** (1.0 / 3.0)
        for d in range(3):
            dims[d] = max(1, int(dims[d] / f))
    width = np.empty(3)
    for d in range(3):
        span = hi[d] - lo[d] if n > 0 else 0.0
        width[d] = span / dims[d] if span > 0 else cell_size
        if width[d] < cell_size and period[3 + d] == 0.0:
            width[d] = cell_size
    ncell = dims[0] * dims[1] * dims[2]
    cell_of = np.empty(n, dtype=np.int32)
    cell_start = np.zeros(ncell + 1, dtype=np.int64)
    for i in range(n):
        c = 0
        stride = 1
        for d in range(3):
            k = cell_index(e_pos[i, d], lo[d], width[d], dims[d], period[3 + d])
            c += k * stride
            stride *= dims[d]
        cell_of[i] = c
        cell_start[c + 1] += 1
    for c in range(ncell):
        cell_start[c + 1] += cell_start[c]
    fill = cell_start[:-1].copy()
    order = np.empty(n, dtype=np.int32)
    for i in range(n):
        c = cell_of[i]
        order[fill[c]] = i
        fill[c] += 1
    return lo, width, dims, cell_start, order


@inline_jit
def cell_index(x, lo, width, dims, length):
    """Cell of coordinate x along one axis (wrapped if the axis has period ``length``)."""
    k = int(math.floor((x - lo) / width))
    if length > 0.0:
        k = k % dims
    elif k >= dims:
        k = dims - 1
    elif k < 0:
        k = 0
    return k


@inline_jit
def cell_range(c, dims, length):
    """(first, count) of the neighbour cells of cell c along one axis: c-1..c+1 (wrapped on
    a periodic axis; all cells if it has fewer than 3)."""
    if length > 0.0:
        if dims >= 3:
            return c - 1, 3
        return 0, dims
    first = max(c - 1, 0)
    return first, min(c + 2, dims) - first


@inline_jit
def x_runs(first, count, dims):
    """Cells first..first+count-1 along x (taken modulo ``dims``) as two runs of cells
    [x0, x1) and [xw0, xw1) (the second empty unless the range wraps round a periodic
    axis)."""
    x0 = first
    x1 = first + count
    xw0 = 0
    xw1 = 0
    if x0 < 0:
        xw0 = x0 + dims
        xw1 = dims
        x0 = 0
    elif x1 > dims:
        xw1 = x1 - dims
        x1 = dims
    return x0, x1, xw0, xw1


@inline_jit
def minimum_image(dx, length):
    """dx of the nearest periodic image (unchanged if length is 0)."""
    if length > 0.0:
        return dx - length * math.floor(dx / length + 0.5)
    return dx


@pjit
def _sorted_copies(e_pos, e_radius, e_owner, order):
    """Positions and radii (n, 4) and owners of the elements in cell order, so that the
    search reads each cell's candidates from contiguous memory."""
    n = e_pos.shape[0]
    sp = np.empty((n, 4))
    so = np.empty(n, np.int32)
    for s in prange(n):
        j = order[s]
        sp[s, 0] = e_pos[j, 0]
        sp[s, 1] = e_pos[j, 1]
        sp[s, 2] = e_pos[j, 2]
        sp[s, 3] = e_radius[j]
        so[s] = e_owner[j]
    return sp, so


@pjit
def _search(sp, so, skin, lo, width, dims, cell_start, order, visit, counts, out_start,
            out_end, out_j, fill, period, first_ghost):
    """counts[i] = partners j > i of element i (within r_i + r_j + skin, nearest image).
    With ``fill`` they are also written, sorted, into out_j[out_start[i]:out_end[i]] (as
    many as fit). The elements visited are those at the positions ``visit`` of the cell
    order (``sp``, ``so``: cell-ordered copies): all of them (``arange(n)``), or those whose
    row a second pass must fill (the others' counts untouched). Elements from
    ``first_ghost`` on (an MPI rank's ghosts) list no partners: a pair of two ghosts is its
    owners' work, and a ghost's pairs with owned elements sit in those rows."""
    periodic = period[3] > 0.0 or period[4] > 0.0 or period[5] > 0.0
    # (always a position array, also for all: numba's parfor indexes ``order`` by the loop
    # index where a branch sets si = q or si = visit[q])
    for q in prange(visit.shape[0]):
        si = visit[q]
        i = order[si]
        if i >= first_ghost:
            counts[i] = 0
            continue
        xi = sp[si, 0]
        yi = sp[si, 1]
        zi = sp[si, 2]
        ri = sp[si, 3] + skin
        oi = so[si]
        cx = cell_index(xi, lo[0], width[0], dims[0], period[3])
        cy = cell_index(yi, lo[1], width[1], dims[1], period[4])
        cz = cell_index(zi, lo[2], width[2], dims[2], period[5])
        fx, nx = cell_range(cx, dims[0], period[3])
        fy, ny = cell_range(cy, dims[1], period[4])
        fz, nz = cell_range(cz, dims[2], period[5])
        first = out_start[i] if fill else 0
        room = out_end[i] - first if fill else 0
        count = 0
        # the x neighbours of a cell are consecutive cells, and their elements one run of
        # the cell order: each row of the stencil is scanned as one or (wrapped round a
        # periodic x) two runs, not cell by cell
        x0, x1, xw0, xw1 = x_runs(fx, nx, dims[0])
        for tz in range(nz):
            gz = (fz + tz) % dims[2]
            for ty in range(ny):
                gy = (fy + ty) % dims[1]
                row = dims[0] * (gy + dims[1] * gz)
                for run in range(2):
                    a = x0 if run == 0 else xw0
                    b = x1 if run == 0 else xw1
                    for s in range(cell_start[row + a], cell_start[row + b]):
                        j = order[s]
                        if j <= i:
                            continue
                        dx = xi - sp[s, 0]
                        dy = yi - sp[s, 1]
                        dz = zi - sp[s, 2]
                        if periodic:  # (the same for every pair: hoisted by the compiler)
                            dx = minimum_image(dx, period[3])
                            dy = minimum_image(dy, period[4])
                            dz = minimum_image(dz, period[5])
                        cut = ri + sp[s, 3]
                        if dx * dx + dy * dy + dz * dz < cut * cut and so[s] != oi:
                            if count < room:  # insertion into the sorted segment of i
                                k = first + count
                                while k > first and out_j[k - 1] > j:
                                    out_j[k] = out_j[k - 1]
                                    k -= 1
                                out_j[k] = j
                            count += 1
        counts[i] = count


@pjit
def _merge(old_start, old_key, old_hist, old_active, new_start, new_key, new_hist,
           new_active):
    """Carry history rows and active flags from the old sorted list to the new one."""
    n = new_start.shape[0] - 1
    h = old_hist.shape[1]
    for i in prange(n):
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


@pjit
def _copy_back(count, new_start, new_key, new_hist, new_active, start, key, hist, active):
    n = new_start.shape[0]
    for i in prange(n):
        start[i] = new_start[i]
    h = hist.shape[1]
    for k in prange(count):
        key[k] = new_key[k]
        active[k] = new_active[k]
        for c in range(h):
            hist[k, c] = new_hist[k, c]


@jit
def build_transpose(nl_start, nl_j, t_start, t_pair):
    """t_pair[t_start[j]:t_start[j+1]] = the pairs (in increasing order) whose second
    element is j."""
    n = nl_start.shape[0] - 1
    for j in range(n + 1):
        t_start[j] = 0
    npairs = nl_start[n]
    for k in range(npairs):
        t_start[nl_j[k] + 1] += 1
    for j in range(n):
        t_start[j + 1] += t_start[j]
    fill = t_start[:-1].copy()
    for k in range(npairs):
        j = nl_j[k]
        t_pair[fill[j]] = k
        fill[j] += 1


#: spare slots per element when the new list is written in one pass into slots sized by
#: the previous list (see build_neighbour_list)
SLOT_SLACK = 4


@jit
def slot_starts(old_start, n):
    """Starts of the transient slots of a one-pass list build: each of the n elements
    gets its count in the previous list (``old_start``, CSR) plus ``SLOT_SLACK``."""
    slot_start = np.empty(n + 1, np.int64)
    slot_start[0] = 0
    for i in range(n):
        slot_start[i + 1] = slot_start[i] + (old_start[i + 1] - old_start[i]) + SLOT_SLACK
    return slot_start


@jit
def rows_of_counts(counts, slot_start):
    """(whether every element's count fitted its slot, the exact rows' starts)."""
    n = counts.shape[0]
    fits = True
    new_start = np.empty(n + 1, np.int64)
    new_start[0] = 0
    for i in range(n):
        if counts[i] > slot_start[i + 1] - slot_start[i]:
            fits = False
        new_start[i + 1] = new_start[i] + counts[i]
    return fits, new_start


@jit
def outgrown(counts, slot_start, order):
    """The positions s in ``order`` (the search's visiting order) whose element
    ``order[s]`` found more entries than its slot holds: the only ones a second search
    pass must visit (in that order)."""
    m = 0
    for s in range(order.shape[0]):
        i = order[s]
        if counts[i] > slot_start[i + 1] - slot_start[i]:
            m += 1
    out = np.empty(m, np.int64)
    m = 0
    for s in range(order.shape[0]):
        i = order[s]
        if counts[i] > slot_start[i + 1] - slot_start[i]:
            out[m] = s
            m += 1
    return out


@jit
def copy_slots(counts, slot_start, slots, new_start, out):
    """Each element's filled slot into its exact row (not an outgrown slot's: a second
    pass fills those rows)."""
    for i in range(counts.shape[0]):
        if counts[i] > slot_start[i + 1] - slot_start[i]:
            continue
        s0 = slot_start[i]
        d0 = new_start[i]
        for k in range(counts[i]):
            out[d0 + k] = slots[s0 + k]


@jit
def build_neighbour_list(e_pos, e_radius, e_owner, skin, nl_start, nl_j, nl_hist, nl_active,
                         t_start, t_pair, period, first_ghost):
    """Rebuild the half list, merge history and flags, copy back, build the transpose.
    Elements from ``first_ghost`` on are an MPI rank's ghosts: no pair among them is
    listed (``e_pos.shape[0]``: none).

    One search pass writes each element's partners into a transient slot sized by its count
    in the previous list plus ``SLOT_SLACK`` (lists change little between rebuilds); the
    slots are then copied into the exact rows, sized by that pass's counts. The rows of the
    elements that outgrew their slots are filled by a second pass over those elements only
    (after an MPI migration the previous list holds only the touching entries carried, and
    a few elements in a hundred outgrow their slots). The new list and its merged
    history live in scratch arrays of its exact size, allocated here and freed on return
    (numba frees each array after its last use, so the search's scratch is gone before the
    history's is allocated); the list's own arrays are only its capacity.

    Returns the number of pairs found. If it exceeds the capacity nothing is changed (the
    old list and its history are intact): the caller grows the buffers and calls again.
    """
    n = e_pos.shape[0]
    cap = nl_j.shape[0]
    rmax = 0.0
    for i in range(n):
        if e_radius[i] > rmax:
            rmax = e_radius[i]
    lo, width, dims, cell_start, order = bin_elements(e_pos, 2.0 * rmax + skin, period)
    sp, so = _sorted_copies(e_pos, e_radius, e_owner, order)
    counts = np.zeros(n, np.int32)
    slot_start = slot_starts(nl_start, n)
    slots = np.empty(slot_start[n], nl_j.dtype)  # transient: keys only
    every = np.arange(n)
    _search(sp, so, skin, lo, width, dims, cell_start, order, every, counts, slot_start,
            slot_start[1:], slots, n >= 0, period, first_ghost)
    fits, new_start = rows_of_counts(counts, slot_start)
    count = new_start[n]
    if count > cap:
        return count
    new_j = np.empty(count, nl_j.dtype)
    copy_slots(counts, slot_start, slots, new_start, new_j)
    if not fits:  # the elements that outgrew their slots: their exact rows, searched again
        again = outgrown(counts, slot_start, order)
        _search(sp, so, skin, lo, width, dims, cell_start, order, again, counts, new_start,
                new_start[1:], new_j, n >= 0, period, first_ghost)
    new_hist = np.empty((count, nl_hist.shape[1]))
    new_active = np.empty(count, np.uint8)
    _merge(nl_start, nl_j, nl_hist, nl_active, new_start, new_j, new_hist, new_active)
    _copy_back(count, new_start, new_j, new_hist, new_active, nl_start, nl_j, nl_hist,
               nl_active)
    if t_pair.shape[0] > 0:  # (none while no force pass needs it)
        build_transpose(nl_start, nl_j, t_start, t_pair)
    return count


@jit
def brute_force_pairs(e_pos, e_radius, e_owner, skin, period):
    """All pairs i < j within r_i + r_j + skin (nearest periodic image), by the O(n^2)
    loop (reference for tests)."""
    n = e_pos.shape[0]
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            if e_owner[i] == e_owner[j]:
                continue
            dx = minimum_image(e_pos[i, 0] - e_pos[j, 0], period[3])
            dy = minimum_image(e_pos[i, 1] - e_pos[j, 1], period[4])
            dz = minimum_image(e_pos[i, 2] - e_pos[j, 2], period[5])
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if d < e_radius[i] + e_radius[j] + skin:
                out.append((i, j))
    return out
