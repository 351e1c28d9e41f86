"""Linked-cell binning and a Verlet neighbour list with a skin; contact history merge.

The list is a half list in CSR form: for element i, ``nl_j[nl_start[i]:nl_start[i+1]]``
holds the elements j > i (sorted) within r_i + r_j + skin, excluding elements of the same
body. Each entry owns a row of contact history, so a rebuild merges the old rows into the
new list by walking both sorted lists (no hashing). The list stays valid while no element
moved more than skin/2 since the rebuild (:func:`max_displacement_sq`).
"""

import math

import numpy as np

from .config import jit

#: at most this many cells per element (a sparse scene gets coarser cells)
CELLS_PER_ELEMENT = 2


@jit
def max_displacement_sq(e_pos, e_ref):
    """Largest squared displacement since the last rebuild; NaN if any position is NaN."""
    m = 0.0
    for i in range(e_pos.shape[0]):
        dx = e_pos[i, 0] - e_ref[i, 0]
        dy = e_pos[i, 1] - e_ref[i, 1]
        dz = e_pos[i, 2] - e_ref[i, 2]
        d2 = dx * dx + dy * dy + dz * dz
        if not d2 <= m:  # true for a larger value and for NaN
            if d2 != d2:
                return d2
            m = d2
    return m


@jit
def bin_elements(e_pos, cell_size):
    """Counting-sort elements into a regular grid of cells at least ``cell_size`` wide.

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
    dims = np.ones(3, dtype=np.int64)
    for d in range(3):
        if n > 0 and hi[d] > lo[d]:
            dims[d] = max(1, int((hi[d] - lo[d]) / cell_size))
    limit = CELLS_PER_ELEMENT * n + 27
    total = dims[0] * dims[1] * dims[2]
    if total > limit:
        f = (total / limit) ** (1.0 / 3.0)
        for d in range(3):
            dims[d] = max(1, int(dims[d] / f))
    width = np.empty(3)
    for d in range(3):
        span = hi[d] - lo[d] if n > 0 else 0.0
        width[d] = span / dims[d] if span > 0 else cell_size
        if width[d] < cell_size:
            width[d] = cell_size
    ncell = dims[0] * dims[1] * dims[2]
    cell_of = np.empty(n, dtype=np.int64)
    cell_start = np.zeros(ncell + 1, dtype=np.int64)
    for i in range(n):
        c = 0
        stride = 1
        for d in range(3):
            k = int((e_pos[i, d] - lo[d]) / width[d])
            if k >= dims[d]:
                k = dims[d] - 1
            if k < 0:
                k = 0
            c += k * stride
            stride *= dims[d]
        cell_of[i] = c
        cell_start[c + 1] += 1
    for c in range(ncell):
        cell_start[c + 1] += cell_start[c]
    fill = cell_start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = cell_of[i]
        order[fill[c]] = i
        fill[c] += 1
    return lo, width, dims, cell_start, order


@jit
def build_neighbour_list(e_pos, e_radius, e_owner, skin, nl_start, nl_j, nl_hist,
                         new_start, new_j, new_hist):
    """Rebuild the half list into ``new_*`` and merge history from ``nl_*``; copy back.

    Returns the number of pairs found. If it exceeds ``new_j.size`` nothing is copied back
    (the old list and its history are intact): the caller grows the buffers and calls again.
    """
    n = e_pos.shape[0]
    cap = new_j.shape[0]
    rmax = 0.0
    for i in range(n):
        if e_radius[i] > rmax:
            rmax = e_radius[i]
    lo, width, dims, cell_start, order = bin_elements(e_pos, 2.0 * rmax + skin)
    count = 0
    new_start[0] = 0
    for i in range(n):
        xi = e_pos[i, 0]
        yi = e_pos[i, 1]
        zi = e_pos[i, 2]
        ri = e_radius[i] + skin
        oi = e_owner[i]
        cx = min(max(int((xi - lo[0]) / width[0]), 0), dims[0] - 1)
        cy = min(max(int((yi - lo[1]) / width[1]), 0), dims[1] - 1)
        cz = min(max(int((zi - lo[2]) / width[2]), 0), dims[2] - 1)
        first = count
        for gz in range(max(cz - 1, 0), min(cz + 2, dims[2])):
            for gy in range(max(cy - 1, 0), min(cy + 2, dims[1])):
                for gx in range(max(cx - 1, 0), min(cx + 2, dims[0])):
                    c = gx + dims[0] * (gy + dims[1] * gz)
                    for s in range(cell_start[c], cell_start[c + 1]):
                        j = order[s]
                        if j <= i or e_owner[j] == oi:
                            continue
                        dx = xi - e_pos[j, 0]
                        dy = yi - e_pos[j, 1]
                        dz = zi - e_pos[j, 2]
                        cut = ri + e_radius[j]
                        if dx * dx + dy * dy + dz * dz < cut * cut:
                            if count < cap:
                                # insertion into the sorted segment of i
                                k = count
                                while k > first and new_j[k - 1] > j:
                                    new_j[k] = new_j[k - 1]
                                    k -= 1
                                new_j[k] = j
                            count += 1
        new_start[i + 1] = count
    if count > cap:
        return count
    merge_history(nl_start, nl_j, nl_hist, new_start, new_j, new_hist, n)
    for i in range(n + 1):
        nl_start[i] = new_start[i]
    h = nl_hist.shape[1]
    for k in range(count):
        nl_j[k] = new_j[k]
        for c in range(h):
            nl_hist[k, c] = new_hist[k, c]
    return count


@jit
def merge_history(old_start, old_j, old_hist, new_start, new_j, new_hist, n):
    """Carry each pair's history rows from the old sorted list to the new one."""
    h = old_hist.shape[1]
    for i in range(n):
        a = old_start[i]
        a_end = old_start[i + 1]
        for k in range(new_start[i], new_start[i + 1]):
            j = new_j[k]
            while a < a_end and old_j[a] < j:
                a += 1
            if a < a_end and old_j[a] == j:
                for c in range(h):
                    new_hist[k, c] = old_hist[a, c]
            else:
                for c in range(h):
                    new_hist[k, c] = 0.0


@jit
def brute_force_pairs(e_pos, e_radius, e_owner, skin):
    """All pairs i < j within r_i + r_j + skin, by the O(n^2) loop (reference for tests)."""
    n = e_pos.shape[0]
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            if e_owner[i] == e_owner[j]:
                continue
            d = math.sqrt((e_pos[i, 0] - e_pos[j, 0]) ** 2 + (e_pos[i, 1] - e_pos[j, 1]) ** 2
                          + (e_pos[i, 2] - e_pos[j, 2]) ** 2)
            if d < e_radius[i] + e_radius[j] + skin:
                out.append((i, j))
    return out
