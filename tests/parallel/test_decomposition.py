"""The domain cut's pure parts (no MPI): the bisection, owners and ghost layers."""

import numpy as np
import pytest

from dpm.parallel import decomposition as dec


def test_bisection_evens_the_weight_and_tiles_space():
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 1, (20000, 3)) * [1.0, 1.0, 3.0]
    w = 1.0 + 4.0 * (p[:, 2] < 0.5)  # a dense bottom: five times the cost
    for ranks in (2, 3, 4):
        boxes = dec.bisect(p, w, ranks, cell=0.01)
        owner = dec.owner_of(p, boxes)
        assert np.all(owner >= 0)  # every point in exactly one box
        per = np.bincount(owner, weights=w, minlength=ranks)
        assert dec.imbalance(per) < 1.02, per


def test_one_pass_owner_and_ghost_ranks_match_the_box_geometry():
    """The compiled owner and ghost-layer test that a migration asks at every rebuild
    gives the rank boxes' answers (numpy's form of each), periodic images included."""
    from dpm.kernels.domain import owner_and_near

    rng = np.random.default_rng(3)
    p = rng.uniform(-1.0, 1.0, (5000, 3))
    boxes = dec.bisect(p, np.ones(len(p)), 3, cell=0.01)
    reach = rng.uniform(0.0, 0.3, len(p))
    for period in (None, np.array([-1.0, -1.0, -1.0, 2.0, 0.0, 2.0])):
        owner, near = owner_and_near(p, boxes, period, reach)
        want = dec.owner_of(p, boxes)
        assert np.array_equal(owner, want)
        for k in range(3):
            ref = (dec.distance_to_box(p, boxes[k], period) <= reach) & (want != k)
            assert np.array_equal(near[k], ref)
        assert near.any() and not near[owner, np.arange(len(p))].any()


def test_ghost_cover_check_matches_the_box_geometry():
    """The test a list rebuild asks before it keeps every row where it is: how far a
    rank's bodies lie outside its box, and which of its bodies another rank's next lists
    need (within reach + that rank's stray distance of its box) but it does not hold;
    against numpy's distances, periodic images included."""
    from dpm.kernels.domain import stray_distance, uncovered_ghosts

    rng = np.random.default_rng(5)
    p = rng.uniform(-1.0, 1.0, (4000, 3))
    boxes = dec.bisect(p, np.ones(len(p)), 3, cell=0.01)
    reach = rng.uniform(0.0, 0.2, len(p))
    for period in (None, np.array([-1.0, -1.0, -1.0, 2.0, 0.0, 2.0])):
        per = np.zeros(6) if period is None else period
        owner = dec.owner_of(p, boxes)
        for me in range(3):
            pts = np.ascontiguousarray(p[owner == me] + rng.normal(0, 0.02, (
                int(np.sum(owner == me)), 3)))  # (moved a little since the cut)
            d_own = dec.distance_to_box(pts, boxes[me], period)
            assert stray_distance(pts, boxes[me], per) == pytest.approx(d_own.max())
            if period is None:  # (a box open to infinity holds an image of every point)
                assert d_own.max() > 0.0
            strays = rng.uniform(0.0, 0.05, 3)
            r = reach[:len(pts)]
            need = np.array([dec.distance_to_box(pts, boxes[k], period) <= r + strays[k]
                             for k in range(3)])
            need[me] = False
            sent = need.copy()
            assert uncovered_ghosts(pts, boxes, per, r, strays, me, sent) == 0
            drop = np.flatnonzero(need.any(axis=0))[:7]
            for i in drop:
                sent[np.flatnonzero(need[:, i])[0], i] = False
            assert uncovered_ghosts(pts, boxes, per, r, strays, me, sent) == len(drop)
            # more held than needed covers too
            assert uncovered_ghosts(pts, boxes, per, r, strays, me,
                                    np.ones_like(sent)) == 0


def test_pool_rows_read_across_head_and_tail_without_joining_them():
    """A migration's pool reads a rank's own rows (the head) and the rows it received
    (the tail) as one numbering; runs of rows kept in place are copied as blocks."""
    from dpm.parallel.local import element_rows, take_two

    rng = np.random.default_rng(4)
    for _ in range(500):
        nh, nt = rng.integers(0, 7), rng.integers(0, 4)
        shape = (nh,) + ((rng.integers(1, 4),) if rng.random() < 0.7 else ())
        head = rng.random(shape)
        tail = rng.random((nt,) + shape[1:]) if nt else None
        whole = np.concatenate([head, tail]) if nt else head
        if len(whole) == 0:
            continue
        rows = np.r_[np.arange(rng.integers(0, len(whole) + 1)),
                     rng.integers(0, len(whole), rng.integers(0, 6)),
                     np.arange(rng.integers(0, len(whole) + 1))].astype(np.int64)
        assert np.array_equal(take_two(head, tail, rows), whole[rows])
    ids = np.arange(12).reshape(4, 3)  # (int rows, a run crossing from head to tail)
    assert take_two(ids[:2], ids[2:], np.array([1, 2, 3, 0])).tolist() == \
        ids[[1, 2, 3, 0]].tolist()
    # one element a body: element rows are the body rows; else each body's run
    est = np.arange(6)
    er, counts = element_rows(est, np.array([4, 1]))
    assert er.tolist() == [4, 1] and counts.tolist() == [1, 1]
    est = np.array([0, 1, 3, 3, 5, 6])  # (body 2 has no element: not the one-a-body case)
    er, counts = element_rows(est, np.array([4, 1, 2]))
    assert er.tolist() == [5, 1, 2] and counts.tolist() == [1, 2, 0]
