"""Joining the open ends of pipe pieces (tubes, bends, plugin boundaries that declare it).

A boundary declares that its ends can be joined by setting the class attribute
``joinable_ends = True`` and giving :meth:`~dpm.boundaries.base.Boundary.pipe_ends`
(name, centre, outward axis, radius of each open end). :func:`join_pipe_ends` (called by
the simulation before it packs the primitives) records in ``boundary.joined`` the names
of the ends that meet another piece's open end; the boundary then writes them into its
primitives' joined-end flags (AXI column 11, TORUS column 13: see
:mod:`dpm.kernels.boundary_geometry`), so that a centre beyond a joined end exerts no
force there and its contact hands its history to the next piece.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from .base import Boundary


def join_pipe_ends(boundaries: Iterable[Boundary]) -> None:
    """Mark the open ends that meet another piece's open end (same centre, opposite
    outward direction, same radius, both within 1e-9 of the radius; same motion object)
    as joined, in ``boundary.joined``; other ends of joinable boundaries are unjoined."""
    ends = []
    for bd in boundaries:
        if bd.joinable_ends:
            bd.joined = set()
            for name, c, d, r in bd.pipe_ends():
                ends.append((bd, name, np.asarray(c, float), np.asarray(d, float), r))
    for k, (b1, n1, c1, d1, r1) in enumerate(ends):
        for b2, n2, c2, d2, r2 in ends[k + 1:]:
            if b1 is b2 or b1.motion is not b2.motion:
                continue
            tol = 1e-9 * max(r1, r2)
            if (np.linalg.norm(c1 - c2) <= tol and float(d1 @ d2) < -1 + 1e-9
                    and abs(r1 - r2) <= tol):
                b1.joined.add(n1)
                b2.joined.add(n2)
