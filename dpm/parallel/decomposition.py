"""Orthogonal recursive bisection (ORB, also RCB) of the scene into one box per rank.

The DPM thesis (section 2.8.2) and LAMMPS/LIGGGHTS' ``balance ... rcb``: the particles'
bounding box is cut across its longest side into two parts whose cost is in the ratio of
the ranks each part gets (1:1 for an even count, 1:2 for three), then each part is cut
again, until every rank has one box. The cost is summed over slabs of cells across the
cut axis (cells of the contact search, so that a cut falls between cells) from each body's
modelled cost: its elements and its touching contacts (``MpiBackend.TOUCHING_WEIGHT``).
Outer faces of the outer boxes reach to infinity: every point of space lies in exactly
one box.
"""

from __future__ import annotations

import numpy as np

#: at least this many slabs per rank along a cut axis (finer than the search cells when
#: the scene is thin along that axis), so that the cut can balance the cost
SLABS_PER_RANK = 16


def bisect(points: np.ndarray, weight: np.ndarray, ranks: int, cell: float) -> np.ndarray:
    """Boxes ``(ranks, 2, 3)`` (lower, upper corner) cutting space so that each holds
    about ``weight.sum() / ranks`` of the points' weight."""
    boxes = np.empty((ranks, 2, 3))
    lo = np.full(3, -np.inf)
    hi = np.full(3, np.inf)
    _split(np.asarray(points, float), np.asarray(weight, float), 0, ranks, lo, hi, cell,
           boxes)
    return boxes


def _split(p: np.ndarray, w: np.ndarray, first: int, count: int, lo: np.ndarray,
           hi: np.ndarray, cell: float, boxes: np.ndarray) -> None:
    if count == 1:
        boxes[first, 0] = lo
        boxes[first, 1] = hi
        return
    left = count // 2
    if len(p) == 0:
        cut, axis = 0.0, 0
    else:
        pmin, pmax = p.min(axis=0), p.max(axis=0)
        axis = int(np.argmax(pmax - pmin))
        span = float(pmax[axis] - pmin[axis])
        width = min(cell, span / (SLABS_PER_RANK * count)) if span > 0 else 1.0
        nslab = max(1, int(np.ceil(span / width)))
        slab = np.minimum(((p[:, axis] - pmin[axis]) / width).astype(np.int64), nslab - 1)
        cum = np.cumsum(np.bincount(slab, weights=w, minlength=nslab))
        target = cum[-1] * left / count
        k = int(np.argmin(np.abs(cum[:-1] - target))) if nslab > 1 else 0
        cut = float(pmin[axis] + (k + 1) * width) if nslab > 1 else float(np.median(
            p[:, axis]))
    below = p[:, axis] < cut
    hi_l = hi.copy()
    hi_l[axis] = cut
    lo_r = lo.copy()
    lo_r[axis] = cut
    _split(p[below], w[below], first, left, lo, hi_l, cell, boxes)
    _split(p[~below], w[~below], first + left, count - left, lo_r, hi, cell, boxes)


def owner_of(points: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """The rank whose box holds each point (lower faces closed, upper faces open)."""
    points = np.asarray(points, float)
    out = np.full(len(points), -1, np.int64)
    for r, (lo, hi) in enumerate(boxes):
        inside = np.all((points >= lo) & (points < hi), axis=1)
        out[inside] = r
    return out


def distance_to_box(points: np.ndarray, box: np.ndarray,
                    period: np.ndarray | None = None) -> np.ndarray:
    """Distance of each point from the box (0 inside); along a periodic axis
    (``period[3 + d]`` > 0, the layout of ``Simulation.period``) the nearest image of
    the point counts."""
    lo, hi = box
    d = np.maximum(np.maximum(lo - points, points - hi), 0.0)
    if period is not None:
        for ax in range(3):
            length = period[3 + ax]
            if length > 0:
                x = points[:, ax]
                for shift in (-length, length):
                    xs = x + shift
                    d[:, ax] = np.minimum(d[:, ax], np.maximum(np.maximum(
                        lo[ax] - xs, xs - hi[ax]), 0.0))
    return np.sqrt(np.einsum("ij,ij->i", d, d))


def imbalance(costs: np.ndarray) -> float:
    """Largest over mean per-rank cost (1: balanced)."""
    costs = np.asarray(costs, float)
    mean = costs.mean()
    return float(costs.max() / mean) if mean > 0 else 1.0


#: the touching weights a fit chooses among (per touching side, in elements): contact
#: laws measured here cost 0.17-0.55 of an element's share of the step
#: (``benchmarks/mpi_cost_model.py``: 0.55; fits in ``benchmarks/mpi_scaling.py``
#: runs: 0.17-0.55); 2 leaves room for dearer laws and bounds what a misleading time
#: can do to the cut
FIT_GRID = np.geomspace(0.05, 2.0, 97)
#: the fewest intervals a fit needs, and the share of the prior's residual the fitted
#: weight must leave at most (below these the prior stays: noise moves no cut)
FIT_MIN_INTERVALS = 4
FIT_MIN_GAIN = 0.5


def fit_touching_weight(samples: list[tuple[np.ndarray, np.ndarray, np.ndarray, float]],
                        prior: float, min_intervals: int = FIT_MIN_INTERVALS,
                        min_gain: float = FIT_MIN_GAIN) -> float:
    """The weight x of a touching contact side, in elements, that makes the ranks' modelled
    costs ``E_r + x T_r`` proportional to their measured seconds per step ``w_r``.

    ``samples``: per interval between list rebuilds, each rank's owned elements ``E``,
    touching sides ``T`` (a boundary contact counts twice) and ``w``, with the interval's
    steps as its weight. Each interval gets its own scale (the machine's speed drifts;
    only the ranks' ratios within an interval inform x): the residual of ``w`` against
    ``s (E + x T)`` with the best ``s``, relative to ``|w|``, summed over the intervals,
    is least at the chosen x (a grid, :data:`FIT_GRID`). The prior stays where the data
    do not decide: fewer than ``min_intervals`` intervals, a best residual above
    ``min_gain`` of the prior's (scatter that the ranks' compositions do not explain:
    with two ranks each interval alone fits some x exactly, only agreement across
    intervals tells), or a flat residual (ranks of alike composition: then x does not
    matter for the balance; the grid point nearest ``prior`` wins).
    """
    x = np.append(FIT_GRID, prior)  # (the last: the prior itself)
    total = np.zeros(len(x))
    used = 0
    for e, t, w, steps in samples:
        m = e[None, :] + x[:, None] * t[None, :]  # (grid, ranks)
        ww = float(w @ w)
        mm = np.einsum("gr,gr->g", m, m)
        if ww <= 0 or np.any(mm <= 0):
            continue
        r = w[None, :] - ((m @ w) / mm)[:, None] * m  # residual at the best scale
        total += steps * np.einsum("gr,gr->g", r, r) / ww
        used += 1
    at_prior, total, x = total[-1], total[:-1], x[:-1]
    if used < min_intervals or not np.any(total > 0) or total.min() > min_gain * at_prior:
        return float(prior)
    # (a flat residual: ties within a part in 1e-6 go to the grid point nearest the prior)
    near = total <= total.min() * (1 + 1e-6) + 1e-300
    return float(x[near][np.argmin(np.abs(np.log(x[near] / prior)))])
