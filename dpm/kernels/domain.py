"""The MPI backend's kernels at a list rebuild: which rank owns each body centre and
which ranks must hold it as a ghost, in one pass over the centres (the numpy form,
:func:`dpm.parallel.decomposition.owner_of` and ``distance_to_box``, makes a temporary
array per rank and axis); and the copy of the rows a rank keeps into its new state
arrays, run by run (:func:`dpm.parallel.local.assemble`).

A rank's box is ``boxes[r] = (lo, hi)``: a centre is inside when ``lo <= x < hi`` on every
axis (lower faces closed, upper open). Its distance from a box is the length of the
per-axis gaps ``max(lo - x, x - hi, 0)``; along a periodic axis (``period[3 + d] > 0``,
the layout of ``Simulation.period``) the nearest of the centre and its two images counts.

Cached on disk (numba's ``cache=True``) as :mod:`dpm.kernels.migrate`: they call no
function of another file, so a cached copy cannot go stale.
"""

import math

import numpy as np
from numba import njit

from .config import JIT

jit = njit(**dict(JIT, cache=True))


@jit
def _gap(x, lo, hi, length):
    g = max(max(lo - x, x - hi), 0.0)
    if length > 0.0:
        for shift in (-length, length):
            xs = x + shift
            g = min(g, max(max(lo - xs, xs - hi), 0.0))
    return g


@jit
def owners_and_near(points, boxes, period, reach, owner, near):
    """``owner[i]``: the rank whose box holds centre i (-1: none); ``near[r, i]``: the
    centre lies within ``reach[i]`` of rank r's box and r does not own it (``period``:
    zeros where no axis is periodic)."""
    n = points.shape[0]
    nr = boxes.shape[0]
    for i in range(n):
        o = -1
        for r in range(nr):
            inside = True
            for d in range(3):
                x = points[i, d]
                if not (x >= boxes[r, 0, d] and x < boxes[r, 1, d]):
                    inside = False
            if inside:
                o = r
        owner[i] = o
        for r in range(nr):
            s = 0.0
            for d in range(3):
                g = _gap(points[i, d], boxes[r, 0, d], boxes[r, 1, d], period[3 + d])
                s += g * g
            near[r, i] = r != o and math.sqrt(s) <= reach[i]


def owner_and_near(points: np.ndarray, boxes: np.ndarray, period: np.ndarray | None,
                   reach: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(owner rank of each centre, ranks x centres: within ``reach`` of another rank's
    box) for ``points`` (n, 3), ``boxes`` (ranks, 2, 3), ``reach`` (n,)."""
    points = np.ascontiguousarray(points, np.float64)
    n, nr = len(points), len(boxes)
    owner = np.empty(n, np.int64)
    near = np.empty((nr, n), np.bool_)
    per = np.zeros(6) if period is None else np.asarray(period, np.float64)
    owners_and_near(points, np.ascontiguousarray(boxes, np.float64), per,
                    np.ascontiguousarray(np.broadcast_to(reach, (n,)), np.float64),
                    owner, near)
    return owner, near


@jit
def copy_runs(head, tail, width, starts, sources, lengths, out):
    """Rows ``out[starts[m] : starts[m] + lengths[m]]`` take the consecutive rows from
    ``sources[m]`` on of ``[head; tail]``, each run copied as one flat block (a vector
    copy). The arrays are flat (rows of ``width`` values one after another); a run lies
    in the head or in the tail."""
    nh = head.shape[0] // width if width else 0
    for m in range(starts.shape[0]):
        d = starts[m] * width
        r = sources[m]
        size = lengths[m] * width
        if r < nh:
            s = r * width
            out[d:d + size] = head[s:s + size]
        else:
            s = (r - nh) * width
            out[d:d + size] = tail[s:s + size]


@jit
def stray_distance(points, box, period):
    """The largest distance of ``points`` from ``box`` ((2, 3): lo, hi; 0 when every
    point lies inside), along a periodic axis from the nearest image."""
    s_max = 0.0
    for i in range(points.shape[0]):
        s = 0.0
        for d in range(3):
            g = _gap(points[i, d], box[0, d], box[1, d], period[3 + d])
            s += g * g
        s = math.sqrt(s)
        if s > s_max:
            s_max = s
    return s_max


@jit
def uncovered_ghosts(points, boxes, period, reach, strays, me, sent):
    """How many of this rank's owned centres ``points`` lie within ``reach[i] +
    strays[r]`` of another rank r's box without being in r's ghost layer (``sent[r, i]``
    False): the ghost layers held no longer cover what the next lists need (rank r's own
    bodies lie at most ``strays[r]`` outside its box)."""
    n = points.shape[0]
    nr = boxes.shape[0]
    missing = 0
    for i in range(n):
        for r in range(nr):
            if r == me or sent[r, i]:
                continue
            s = 0.0
            for d in range(3):
                g = _gap(points[i, d], boxes[r, 0, d], boxes[r, 1, d], period[3 + d])
                s += g * g
            if math.sqrt(s) <= reach[i] + strays[r]:
                missing += 1
    return missing
