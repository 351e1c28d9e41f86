"""The contact lists' O(n) sort (:mod:`dpm.kernels.entry_order`) against numpy's sorts."""

import numpy as np
import pytest

from dpm.kernels.entry_order import INSERTION_MAX, key_order, row_key_order


@pytest.mark.parametrize("n, n_rows, n_keys", [
    (0, 4, 4), (1, 1, 1), (5000, 2000, 2000),   # a few entries a row, as a list holds
    (3 * INSERTION_MAX, 2, 50),                  # rows past the insertion sort's reach
    (4000, 7, 3),                                # many equal (row, key) entries
])
def test_row_key_order_is_lexsort(n, n_rows, n_keys):
    rng = np.random.default_rng(n + n_rows)
    rows = rng.integers(0, n_rows, n)
    keys = rng.integers(0, n_keys, n)
    # stable as lexsort: of equal (row, key) entries the first given stays first
    np.testing.assert_array_equal(row_key_order(rows, keys, n_rows),
                                  np.lexsort((keys, rows)))
    k32 = keys.astype(np.int32)  # (a list's keys are int32)
    np.testing.assert_array_equal(row_key_order(rows, k32, n_rows), np.lexsort((k32, rows)))
    np.testing.assert_array_equal(key_order(keys, n_keys), np.argsort(keys, kind="stable"))


@pytest.mark.parametrize("rows", [False, True])
def test_a_ranks_list_from_its_pool_is_the_filtered_sorted_list(rows):
    """:func:`dpm.parallel.local.set_mapped_entries` (compiled) gives the list that the
    numpy steps give: keep the entries of kept elements with one owned, renumber, turn
    pairs to i < j negating the vector history of a swapped pair (by its pair's model),
    sort, keep the first of equal entries."""
    from types import SimpleNamespace

    from dpm.parallel.local import Entries, orient_pairs, set_entries, set_mapped_entries
    from dpm.state import Contacts, WallContacts

    rng = np.random.default_rng(5 + rows)
    n_pool, n_new, first_ghost, width = 300, 200, 150, 3
    new_el = np.full(n_pool, -1, np.int64)
    new_el[rng.choice(n_pool, n_new, replace=False)] = rng.permutation(n_new)
    n = 3000
    e = Entries(rng.integers(0, n_pool, n), rng.integers(0, n_pool, n),
                rng.normal(size=(n, width)), rng.integers(0, 2, n).astype(np.uint8))
    e.j[:50] = e.j[50:100]  # (equal entries: the first one given stays)
    e.i[:50] = e.i[50:100]
    mat = rng.integers(0, 2, n_new)
    plan = SimpleNamespace(pair_model=np.array([[0, 1], [1, 2]]),
                           history_flips=np.array([[True, True, False], [False, True, True],
                                                   [True, False, True]]))
    ni, nj = new_el[e.i], new_el[e.j]
    keep = (ni >= 0) & (nj >= 0) & (np.minimum(ni, nj) < first_ghost)
    want = orient_pairs(Entries(ni[keep], nj[keep], e.hist[keep], e.act[keep]), mat, plan)
    lists = []
    for fn in ("numpy", "compiled"):
        lst = Contacts(n_new, 16)
        lst.set_history_width(width)
        lst.use_rows(rows)
        if fn == "numpy":
            set_entries(lst, n_new, want, unique=True)
        else:
            set_mapped_entries(lst, n_new, e, new_el, first_ghost, mat, plan)
        lists.append(lst)
    a, b = lists
    m = a.count
    assert b.count == m > 100
    np.testing.assert_array_equal(a.start, b.start)
    np.testing.assert_array_equal(a.key[:m], b.key[:m])
    np.testing.assert_array_equal(a.history[:m], b.history[:m])
    np.testing.assert_array_equal(a.active[:m], b.active[:m])
    if rows:
        np.testing.assert_array_equal(a.t_start, b.t_start)
        np.testing.assert_array_equal(a.t_pair[:m], b.t_pair[:m])
    # boundary entries: the element kept and owned, the primitive as it is
    wi = new_el[e.i]
    wk = (wi >= 0) & (wi < first_ghost)
    wa, wb = WallContacts(n_new, 16), WallContacts(n_new, 16)
    wa.set_history_width(width)
    wb.set_history_width(width)
    set_entries(wa, n_new, Entries(wi[wk], e.j[wk], e.hist[wk], e.act[wk]), unique=True)
    set_mapped_entries(wb, n_new, e, new_el, first_ghost)
    m = wa.count
    assert wb.count == m > 100
    np.testing.assert_array_equal(wa.start, wb.start)
    np.testing.assert_array_equal(wa.key[:m], wb.key[:m])
    np.testing.assert_array_equal(wa.history[:m], wb.history[:m])
