"""Lacey's mixing index of two labelled species."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import shown
from ._common import Series, frames_of, is_run


def species_mask(ids: np.ndarray, labels: Any) -> np.ndarray:
    """True for the bodies of species A: ``labels`` is a predicate on the id array
    (``lambda ids: ids < 500``), a boolean array indexed by id (``labels[id]``), or any
    other array, list or set: the ids of species A."""
    ids = np.asarray(ids)
    if callable(labels):
        out = np.asarray(labels(ids), bool)
        if out.shape != ids.shape:
            raise ParameterError("labels(ids) must give one boolean per id")
        return out
    if isinstance(labels, set | frozenset):
        return np.isin(ids, np.fromiter(labels, np.int64))
    arr = np.asarray(labels)
    if arr.dtype == bool:
        if len(ids) and ids.max() >= len(arr):
            raise ParameterError(f"labels has {len(arr)} entries; ids go up to {ids.max()}")
        return arr[ids]
    return np.isin(ids, arr.astype(np.int64))


def lacey(frame: dict[str, Any], labels: Any | Callable, cell: Any,
          lower: Any = None, upper: Any = None, min_count: int = 5,
          by: str = "number") -> dict[str, float]:
    """Lacey's mixing index of one frame.

    The bodies are binned by their centres into cubic sample cells of size ``cell``
    (between ``lower`` and ``upper``, default the bodies' bounding box); cells with fewer
    than ``min_count`` bodies are left out. With x_k the fraction of species A in cell k
    (by number, or with ``by="mass"`` by mass), p the fraction overall, n_k the cell's
    count:

        s^2 = mean_k (x_k - p)^2,  s0^2 = p (1 - p)  (fully segregated),
        sr^2 = p (1 - p) mean_k (1 / n_k)  (random mixture),
        M = (s0^2 - s^2) / (s0^2 - sr^2)

    so M ~ 0 for segregated species and M ~ 1 for a random mixture (Lacey, P. M. C. 1954,
    "Developments in the theory of particle mixing", J. Appl. Chem. 4, 257-268; the
    review of Fan, L. T., Chen, S. J., Watson, C. A. 1970, Ind. Eng. Chem. 62, 53-69).
    M depends on the cell size: cells of a few particle diameters, ~10-50 bodies each.
    Returns ``M``, ``s2``, ``s02``, ``sr2``, ``p``, ``cells``.
    """
    if by not in ("number", "mass"):
        raise ParameterError(f"by={by!r}; allowed: 'number', 'mass'")
    x = np.asarray(frame["position"], float)
    a = species_mask(frame["id"], labels)
    w = np.asarray(frame["mass"], float) if by == "mass" else np.ones(len(x))
    lo = x.min(axis=0) if lower is None else np.asarray(lower, float)
    hi = x.max(axis=0) + 1e-12 if upper is None else np.asarray(upper, float)
    c = np.broadcast_to(np.asarray(cell, float), (3,))
    if not np.all(c > 0):
        raise ParameterError(f"cell={shown(cell)} must be > 0")
    n = np.maximum(np.ceil((hi - lo) / c).astype(int), 1)
    k = np.floor((x - lo) / c).astype(int)
    inside = np.all((k >= 0) & (k < n), axis=1)
    flat = np.ravel_multi_index(tuple(k[inside].T), tuple(n))
    count = np.bincount(flat, minlength=int(np.prod(n)))
    wa = np.bincount(flat, weights=(w * a)[inside], minlength=len(count))
    wt = np.bincount(flat, weights=w[inside], minlength=len(count))
    use = count >= max(int(min_count), 1)
    nan = {"M": float("nan"), "s2": float("nan"), "s02": float("nan"), "sr2": float("nan"),
           "p": float("nan"), "cells": int(np.count_nonzero(use))}
    if not np.any(use) or wt[use].sum() <= 0:
        return nan
    p = float(wa[use].sum() / wt[use].sum())
    xk = wa[use] / wt[use]
    s2 = float(np.mean((xk - p) ** 2))
    s02 = p * (1 - p)
    sr2 = s02 * float(np.mean(1.0 / count[use]))
    if s02 - sr2 <= 0:
        return dict(nan, p=p, s2=s2, s02=s02, sr2=sr2)
    return {"M": (s02 - s2) / (s02 - sr2), "s2": s2, "s02": s02, "sr2": sr2, "p": p,
            "cells": int(np.count_nonzero(use))}


def lacey_index(source: Any, labels: Any, cell: Any, frames: Any = None, **kw: Any
                ) -> Series:
    """Lacey's mixing index (:func:`lacey`) against time over the frames of a run (or a
    list of frame dicts)."""
    t, m = [], []
    for f in frames_of(source, frames):
        t.append(float(f.get("time", len(t))))
        m.append(lacey(f, labels, cell, **kw)["M"])
    if not t and is_run(source):
        raise ParameterError("the run has no frames")
    return Series(np.asarray(t), np.asarray(m), "-")
