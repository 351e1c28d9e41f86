"""Helpers to place particles."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def lattice(lower: Sequence[float], upper: Sequence[float], spacing: float,
            jitter: float = 0.0, seed: int = 0) -> np.ndarray:
    """Centres of a simple cubic lattice filling [lower + spacing/2, upper - spacing/2].

    ``jitter`` [m] adds uniform noise in (-jitter, jitter) to every coordinate.
    """
    lo = np.asarray(lower, float)
    hi = np.asarray(upper, float)
    counts = np.maximum(np.floor((hi - lo) / spacing).astype(int), 1)
    axes = [lo[d] + (np.arange(counts[d]) + 0.5) * spacing for d in range(3)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    if jitter > 0:
        g = g + np.random.default_rng(seed).uniform(-jitter, jitter, g.shape)
    return g
