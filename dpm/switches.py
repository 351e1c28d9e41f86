"""Boundaries switched on and off during a run, the contact history of the rest kept.

LIGGGHTS opens an orifice under a settled bed by ``unfix``-ing the plug wall between two
``run`` commands; dpm does the same inside one scene, now or at a scheduled time::

    plug = sim.add_boundary("wall", material=steel, ...)
    sim.switch_off(plug, at=0.5)     # the bed settles on the plug, then the orifice opens
    sim.run(until=3.0)

or between runs: ``sim.run(until=0.5); sim.switch_off(plug); sim.run(until=3.0)``.

A switched-off boundary stays in ``sim.boundaries`` (its index, and the columns of the
output's boundary loads, do not change) but takes no part in the contact search: the
boundary lists are rebuilt at the switch (history merged by pair, as at every rebuild), so
the contacts with it end and every other contact, between particles or with the other
boundaries, keeps its history. Its load is zero while off, its ``work`` stays what it was.
Inlets place particles without regard to it and the start-up checks ignore it. Switching
back on finds its contacts afresh (no history: they are new contacts).

The switch lies at the end of the step whose end time is the first at or after ``at``:
forces of that step were computed with the boundary, the next step's are without. Times
are kept, not step numbers, so a change of ``dt`` between runs keeps them right.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .errors import ParameterError


@dataclass
class Switch:
    """One scheduled switch: boundary ``index`` on (True) or off (False) at ``time`` [s]."""

    index: int
    on: bool
    time: float


def _index(sim: Any, boundary: Any, call: str) -> int:
    for k, bd in enumerate(sim.boundaries):
        if bd is boundary:
            return k
    if isinstance(boundary, int) and not isinstance(boundary, bool) and \
            0 <= boundary < len(sim.boundaries):
        return int(boundary)
    raise ParameterError(f"{call}: boundary={boundary!r} is not a boundary of this "
                         f"simulation (give the object sim.add_boundary returned, or its "
                         f"index 0-{len(sim.boundaries) - 1})" if sim.boundaries else
                         f"{call}: boundary={boundary!r}: the simulation has no boundaries")


def schedule(sim: Any, boundary: Any, on: bool, at: Any) -> None:
    """Switch ``boundary`` on or off at time ``at`` [s] (None: now, before the next run)."""
    call = f"sim.switch_{'on' if on else 'off'}()"
    k = _index(sim, boundary, call)
    bd = sim.boundaries[k]
    if getattr(bd, "joined", None):
        raise ParameterError(f"{call}: boundary {k} ({bd.name}) has ends joined to another "
                             f"pipe piece ({', '.join(sorted(bd.joined))}); switching one "
                             "piece of a joined pipe is not supported")
    if getattr(sim.integrator, "implicit", False):
        raise ParameterError(f"{call}: the implicit integrator {sim.integrator.name!r} keeps "
                             "its boundaries fixed for the run; use an explicit integrator")
    if at is None:
        t = sim.time
    else:
        if isinstance(at, bool) or not isinstance(at, (int, float)) or not math.isfinite(at):
            raise ParameterError(f"{call}: at={at!r} must be a finite time in seconds")
        t = float(at)
        if t < sim.time:
            raise ParameterError(f"{call}: at={t!r} s lies before the simulation's time "
                                 f"{sim.time!r} s; allowed: at >= sim.time, or None (now)")
    sim.operations.switches.pending.append(Switch(k, bool(on), t))
    sim.operations.switches.pending.sort(key=lambda s: s.time)
    apply_due(sim)


def step_of(sim: Any, t: float) -> int:
    """The step at whose end time ``t`` is reached (the first end time >= t)."""
    return sim.step_count + max(0, math.ceil((t - sim.time) / sim.dt - 1e-9))


def next_step(sim: Any) -> int | None:
    """The step of the next pending switch, None if there is none."""
    pending = sim.operations.switches.pending
    return step_of(sim, pending[0].time) if pending else None


def apply_due(sim: Any) -> bool:
    """Apply the switches due by now; True if a boundary changed state."""
    changed = False
    pending = sim.operations.switches.pending
    while pending and step_of(sim, pending[0].time) <= sim.step_count:
        s = pending.pop(0)
        bd = sim.boundaries[s.index]
        if bd.enabled != s.on:
            bd.enabled = s.on
            changed = True
    if changed:
        refresh(sim)
    return changed


def refresh(sim: Any) -> None:
    """Bring the packed boundary table (and the lists, when running) in line with each
    boundary's ``enabled``."""
    table = sim.walls
    if table is None or len(table.frame) != len(sim.boundaries):
        return  # packed at the next run, which applies the flags
    for k, bd in enumerate(sim.boundaries):
        table.set_enabled(k, bd.enabled)
    if sim._prepared:
        sim.backend.rebuild()
        sim._update_boundary_loads()  # (set_enabled zeroed the load of those switched off)
