"""The linked-cell Verlet list against the O(n^2) loop; history survives rebuilds."""

import numpy as np
import pytest

from dpm.kernels import neighbours
from dpm.kernels.config import N_HISTORY


def _build(pos, rad, owner, skin, cap=10000, old=None, first_ghost=None):
    n = len(pos)
    start = np.zeros(n + 1, np.int64) if old is None else old[0]
    j = np.zeros(cap, np.int64) if old is None else old[1]
    hist = np.zeros((cap, N_HISTORY)) if old is None else old[2]
    active = np.zeros(cap, np.uint8)
    count = neighbours.build_neighbour_list(
        pos, rad, owner, skin, start, j, hist, active, np.zeros(n + 1, np.int64),
        np.zeros(cap, np.int64), np.zeros(6), n if first_ghost is None else first_ghost)
    return count, start, j, hist


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_matches_brute_force_polydisperse(seed):
    rng = np.random.default_rng(seed)
    n = 400
    pos = rng.uniform(0, 0.05, (n, 3))
    pos[:50, 2] += 0.3  # a detached cluster: sparse grid, empty cells
    rad = rng.uniform(0.5e-3, 3e-3, n)
    owner = np.arange(n)
    owner[1] = owner[0]  # two elements of one body never pair
    skin = 1e-3
    count, start, j, _ = _build(pos, rad, owner, skin)
    got = {(i, int(j[k])) for i in range(n) for k in range(start[i], start[i + 1])}
    ref = set(neighbours.brute_force_pairs(pos, rad, owner, skin, np.zeros(6)))
    assert count == len(ref)
    assert got == ref
    assert (0, 1) not in got
    for i in range(n):  # each segment sorted, for the history merge
        seg = j[start[i]:start[i + 1]]
        assert np.all(np.diff(seg) > 0)


def test_far_flung_elements_get_capped_cells_and_the_brute_force_list():
    """Two clumps 1 km apart: the grid over their bounding box is capped at
    CELLS_PER_ELEMENT cells per element (coarse cells, many candidates each), and the list
    is still the plain double loop's."""
    rng = np.random.default_rng(11)
    n = 300
    pos = rng.uniform(0, 0.02, (n, 3))
    pos[n // 2:] += 1000.0
    rad = np.full(n, 1e-3)
    owner = np.arange(n)
    skin = 2e-4
    _, _, dims, cell_start, _ = neighbours.bin_elements(pos, 2 * 1e-3 + skin, np.zeros(6))
    assert np.prod(dims) <= neighbours.CELLS_PER_ELEMENT * n + 27
    assert len(cell_start) == np.prod(dims) + 1
    count, start, j, _ = _build(pos, rad, owner, skin)
    got = {(i, int(j[k])) for i in range(n) for k in range(start[i], start[i + 1])}
    ref = set(neighbours.brute_force_pairs(pos, rad, owner, skin, np.zeros(6)))
    assert count == len(ref) > 100
    assert got == ref


def test_overflow_reports_need_and_keeps_old_list():
    rng = np.random.default_rng(5)
    pos = rng.uniform(0, 0.01, (200, 3))
    rad = np.full(200, 1e-3)
    owner = np.arange(200)
    need = len(neighbours.brute_force_pairs(pos, rad, owner, 0.0, np.zeros(6)))
    count, start, j, _ = _build(pos, rad, owner, 0.0, cap=need - 1)
    assert count == need
    assert start[-1] == 0  # nothing copied back


def test_history_follows_pairs_across_rebuild():
    rng = np.random.default_rng(3)
    n = 300
    pos = rng.uniform(0, 0.03, (n, 3))
    rad = np.full(n, 1e-3)
    owner = np.arange(n)
    count, start, j, hist = _build(pos, rad, owner, 5e-4)
    # tag each pair's history with a function of (i, j)
    for i in range(n):
        for k in range(start[i], start[i + 1]):
            hist[k, :] = i * 1000 + j[k]
    old_pairs = {(i, int(j[k])) for i in range(n) for k in range(start[i], start[i + 1])}
    pos2 = pos + rng.uniform(-2e-4, 2e-4, pos.shape)
    # the rebuild writes the merged list back into the same arrays
    count2, start2, j2, hist2 = _build(pos2, rad, owner, 5e-4, old=(start, j, hist))
    kept = fresh = 0
    for i in range(n):
        for k in range(start2[i], start2[i + 1]):
            if (i, int(j2[k])) in old_pairs:
                assert np.all(hist2[k] == i * 1000 + j2[k])
                kept += 1
            else:
                assert np.all(hist2[k] == 0)
                fresh += 1
    assert kept > 50 and fresh > 0


@pytest.mark.parametrize("first_ghost", [None, 450])
def test_rebuild_from_a_thinned_list_searches_again_only_what_outgrew_its_slot(first_ghost):
    """After an MPI migration the previous list holds only the touching entries carried:
    slots sized by it fit most elements but not all. The outgrown elements' rows are
    searched again on their own; the list is still the double loop's, with the carried
    history in place and every other row copied from its slot (rows that fill their slot
    exactly among them; with an MPI rank's ghosts from ``first_ghost`` on, too)."""
    rng = np.random.default_rng(21)
    n = 600
    pos = rng.uniform(0, 0.04, (n, 3))
    rad = rng.uniform(0.8e-3, 2.4e-3, n)
    owner = np.arange(n)
    skin = 1.5e-3  # (a wide skin: rows of many partners that do not touch)
    count, start, j, hist = _build(pos, rad, owner, skin, first_ghost=first_ghost)
    cut = n if first_ghost is None else first_ghost
    ref = {(a, b) for a, b in neighbours.brute_force_pairs(pos, rad, owner, skin, np.zeros(6))
           if min(a, b) < cut}
    assert {(i, int(j[k])) for i in range(n) for k in range(start[i], start[i + 1])} == ref
    rows = np.repeat(np.arange(n), np.diff(start))
    partner = j[:count].astype(np.int64)
    touch = np.linalg.norm(pos[rows] - pos[partner], axis=1) < rad[rows] + rad[partner]
    kept = np.flatnonzero(touch)
    thin_start = np.zeros(n + 1, np.int64)
    thin_start[1:] = np.cumsum(np.bincount(rows[kept], minlength=n))
    thin_j = np.zeros_like(j)
    thin_j[:len(kept)] = partner[kept]
    thin_hist = np.zeros_like(hist)
    thin_hist[:len(kept), :] = (rows[kept] * 1000 + partner[kept])[:, None]
    full_counts = np.diff(start)
    room = np.diff(thin_start) + neighbours.SLOT_SLACK
    assert 0 < (full_counts > room).sum() < n // 2  # (both kinds of row are there)
    assert (full_counts == room).any()  # (and rows that fill their slot exactly)
    count2, start2, j2, hist2 = _build(pos, rad, owner, skin,
                                       old=(thin_start, thin_j, thin_hist),
                                       first_ghost=first_ghost)
    assert count2 == count
    assert np.array_equal(start2, start) and np.array_equal(j2[:count], j[:count])
    carried = set(zip(rows[kept].tolist(), partner[kept].tolist(), strict=True))
    for k in range(count):
        i = int(rows[k])
        want = i * 1000 + j2[k] if (i, int(j2[k])) in carried else 0
        assert np.all(hist2[k] == want)


def test_transpose_lists_second_elements():
    rng = np.random.default_rng(9)
    pos = rng.uniform(0, 0.02, (150, 3))
    rad = np.full(150, 1e-3)
    count, start, j, _ = _build(pos, rad, np.arange(150), 5e-4)
    t_start = np.zeros(151, np.int64)
    t_pair = np.zeros(count, np.int64)
    neighbours.build_transpose(start, j, t_start, t_pair)
    for e in range(150):
        ks = t_pair[t_start[e]:t_start[e + 1]]
        assert np.all(j[ks] == e) and np.all(np.diff(ks) > 0)
    assert t_start[-1] == count


def test_ghost_rows_list_no_pairs_among_themselves():
    # an MPI rank's ghosts (the rows from first_ghost on): their pairs with owned rows
    # are listed, in the owned rows; pairs of two ghosts are not
    rng = np.random.default_rng(5)
    n, first_ghost = 300, 200
    pos = rng.uniform(0, 0.03, (n, 3))
    rad = np.full(n, 1.5e-3)
    owner = np.arange(n)
    count, start, j, _ = _build(pos, rad, owner, 2e-4)
    full = {(i, int(j[k])) for i in range(n) for k in range(start[i], start[i + 1])}
    count_g, start_g, j_g, _ = _build(pos, rad, owner, 2e-4, first_ghost=first_ghost)
    got = {(i, int(j_g[k])) for i in range(n) for k in range(start_g[i], start_g[i + 1])}
    assert got == {(i, k) for i, k in full if min(i, k) < first_ghost}
    assert any(i < first_ghost <= k for i, k in got)  # (owned-ghost pairs are there)
    assert count_g == len(got) < count


@pytest.mark.parametrize("axes", [(0,), (1,), (2,), (0, 1, 2)])
@pytest.mark.parametrize("length", [0.05, 0.011, 0.006])
def test_periodic_matches_brute_force(axes, length):
    """Periodic faces: a stencil row that wraps round the x axis is scanned as two runs of
    cells; boxes of many cells a side, 2 cells and 1 cell."""
    rng = np.random.default_rng(int(length * 1e4) + len(axes))
    n = 800
    span = np.array([0.05, 0.05, 0.05])
    period = np.zeros(6)
    for a in axes:
        span[a] = length
        period[3 + a] = length
    pos = rng.uniform(0, 1, (n, 3)) * span
    rad = rng.uniform(0.8e-3, 2e-3, n)
    owner = np.arange(n)
    skin = 5e-4
    cap = n * n // 2
    start = np.zeros(n + 1, np.int64)
    j = np.zeros(cap, np.int64)
    count = neighbours.build_neighbour_list(
        pos, rad, owner, skin, start, j, np.zeros((cap, N_HISTORY)), np.zeros(cap, np.uint8),
        np.zeros(n + 1, np.int64), np.zeros(cap, np.int64), period, n)
    got = {(i, int(j[k])) for i in range(n) for k in range(start[i], start[i + 1])}
    ref = set(neighbours.brute_force_pairs(pos, rad, owner, skin, period))
    assert count == len(ref) and got == ref
    wrapped = [(a, b) for a, b in ref
               if any(abs(pos[a, x] - pos[b, x]) > length / 2 for x in axes)]
    assert wrapped  # pairs across the periodic faces are among them
