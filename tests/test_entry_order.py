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
