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

