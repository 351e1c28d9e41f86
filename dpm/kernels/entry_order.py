"""The order of contact-list entries by row then key, in O(n): the CSR lists' sort.

A list (pairs or boundary entries) is a CSR array: entries sorted by row (the first
element), then by key (the partner element or boundary primitive). Where entries are
gathered from elsewhere (a migration's pool, the MPI gather, a renumbering), they are put
in that order again. ``np.lexsort`` does it in O(n log n) on two int64 keys, ~12 ms for
100,000 entries; a counting sort by row followed by an insertion sort by key inside each
row (a row holds a few entries: a sphere touches ~12 neighbours) is O(n) and stable, as
lexsort is, so that of equal (row, key) entries the first given stays first.

Cached on disk (numba's ``cache=True``): these functions call no function of another
file, so a cached copy cannot go stale.
"""

import numpy as np
from numba import njit

from .config import JIT

jit = njit(**dict(JIT, cache=True))

#: longer rows than this are sorted by a merge sort (insertion sort is quadratic)
INSERTION_MAX = 48


@jit
def _bucket(rows, n_rows):
    """(the stable order of the entries by ``rows``, where each row starts in it)."""
    n = rows.shape[0]
    start = np.zeros(n_rows + 1, np.int64)
    for k in range(n):
        start[rows[k] + 1] += 1
    for r in range(n_rows):
        start[r + 1] += start[r]
    fill = start[:n_rows].copy()
    order = np.empty(n, np.int64)
    for k in range(n):
        r = rows[k]
        order[fill[r]] = k
        fill[r] += 1
    return order, start


@jit
def row_key_order(rows, keys, n_rows):
    """The permutation that sorts entries by ``rows`` then ``keys`` (stable): the result
    of ``np.lexsort((keys, rows))``. ``rows`` in ``0 .. n_rows - 1``."""
    order, start = _bucket(rows, n_rows)
    for r in range(n_rows):
        a, b = start[r], start[r + 1]
        if b - a < 2:
            continue
        if b - a > INSERTION_MAX:
            seg = order[a:b].copy()
            o = np.argsort(keys[seg], kind="mergesort")
            for x in range(b - a):
                order[a + x] = seg[o[x]]
            continue
        for x in range(a + 1, b):
            v = order[x]
            kv = keys[v]
            y = x - 1
            while y >= a and keys[order[y]] > kv:
                order[y + 1] = order[y]
                y -= 1
            order[y + 1] = v
    return order


@jit
def key_order(keys, n_keys):
    """The permutation that sorts entries by ``keys`` (stable; keys in ``0 .. n_keys -
    1``): ``np.argsort(keys, kind="stable")`` by counting."""
    return _bucket(keys, n_keys)[0]
