"""Helpers to place particles."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .parameters import Parameter, validate

_LATTICE = {
    "lower": Parameter(kind="vector", unit="m"),
    "upper": Parameter(kind="vector", unit="m"),
    "spacing": Parameter(low=0.0, low_open=True, unit="m"),
    "jitter": Parameter(default=0.0, low=0.0, unit="m"),
    "seed": Parameter(default=0, low=0, kind="int"),
}


def lattice(lower: Sequence[float], upper: Sequence[float], spacing: float,
            jitter: float = 0.0, seed: int = 0) -> np.ndarray:
    """Centres of a simple cubic lattice filling [lower + spacing/2, upper - spacing/2].

    ``jitter`` [m] adds uniform noise in (-jitter, jitter) to every coordinate. A lattice
    whose bodies would not fit in memory is refused before it is made
    (:func:`dpm._memory.check_request`).
    """
    from ._memory import check_request

    validate("dpm.lattice()", _LATTICE, dict(lower=lower, upper=upper, spacing=spacing,
                                              jitter=jitter, seed=seed))
    lo = np.asarray(lower, float)
    hi = np.asarray(upper, float)
    per_axis = np.maximum(np.floor((hi - lo) / spacing), 1.0)
    total = float(np.prod(per_axis))
    check_request(f"dpm.lattice(): spacing={spacing:g} gives {total:.4g} points;", total, total)
    counts = per_axis.astype(int)
    axes = [lo[d] + (np.arange(counts[d]) + 0.5) * spacing for d in range(3)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    if jitter > 0:
        g = g + np.random.default_rng(seed).uniform(-jitter, jitter, g.shape)
    return g
