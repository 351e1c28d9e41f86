"""Where an inlet may place a body: its gap to every boundary primitive of the scene.

:mod:`dpm.plan` copies this module for each set of boundary kinds with the block between
the ``bindings`` markers rewritten to the scene's ``closest`` (plugin kinds included), as
it does the step module, so the placement test is compiled once per set of kinds and then
loaded from the disk cache: a run with an inlet no longer compiles it in every process.
"""
# ruff: noqa: I001, F401  (the bindings block must stay between its markers; it uses inline_jit)
import numpy as np

from .config import inline_jit, row20, step_jit as jit
from .boundary_search import to_local

# --- bindings begin (dpm.plan rewrites this block) ---
from .boundary_geometry import closest_any as closest
# --- bindings end ---


@jit
def boundary_gaps(points, radii, frame, kind, par, owner):
    """Smallest dist - r over all primitives for each sphere (inf without boundaries): a
    negative gap means the sphere would overlap a boundary (or lie behind a plane). A plain
    loop over primitives, for inlets placing a few bodies."""
    n = points.shape[0]
    out = np.full(n, np.inf)
    for i in range(n):
        r = radii[i]
        for w in range(kind.shape[0]):
            lx, ly, lz = to_local(frame[owner[w]], points[i, 0], points[i, 1], points[i, 2])
            g = closest(kind[w], row20(par, w), lx, ly, lz, r)[0] - r
            if g < out[i]:
                out[i] = g
    return out
