"""Failure diagnosis: what went wrong in a run, where, and what to change.

The run loop calls :func:`check_speeds` after each kernel call and :func:`unstable` when a
kernel reports a status; the error names the step, the time, the particle, what it touches
and the time-step figures, after the output written so far was flushed.
"""

from __future__ import annotations

import math
import time as _time
from typing import Any

import numpy as np

from .errors import UnstableRunError

#: bodies per block of the speed check after each call
SPEED_BLOCK = 1 << 16


def fastest_body(velocity: np.ndarray) -> tuple[int, float]:
    """(index, speed) of the fastest body; the speed is NaN or inf if a velocity is.

    In blocks (no temporary of the population's size: at 1e6 spheres this check had set
    the run's peak memory), the columns one by one (einsum over rows of 3 took 6.3 ms per
    1e6 bodies, this 3.8 ms)."""
    k, v2 = 0, -1.0
    for first in range(0, len(velocity), SPEED_BLOCK):
        vb = velocity[first:first + SPEED_BLOCK]
        sq = vb[:, 0] * vb[:, 0]
        sq += vb[:, 1] * vb[:, 1]
        sq += vb[:, 2] * vb[:, 2]
        j = int(np.argmax(sq))  # (the first NaN, if any)
        if not sq[j] <= v2:
            k, v2 = first + j, float(sq[j])
            if not math.isfinite(v2):
                return k, v2
    return k, math.sqrt(max(v2, 0.0))


def check_speeds(sim: Any) -> float:
    """Stop the run if a velocity is NaN or a body moves more than half its radius per
    step (contacts would be missed); return the seconds the check took."""
    b = sim.bodies
    if len(b) == 0:
        return 0.0
    t0 = _time.perf_counter()
    k, speed = sim.backend.max_speed()
    if not math.isfinite(speed):
        raise unstable(sim, "a velocity became NaN or inf")
    if speed * sim.dt > 0.5 * b.radius[k]:
        raise unstable(
            sim, f"particle {b.id[k]} moves {speed * sim.dt:.3g} m per step, more than half "
            f"its radius {b.radius[k]:.3g} m (speed {speed:.3g} m/s): contacts would be "
            "missed (tunnelling) or start at unresolved overlaps; dt must stay below "
            f"{0.5 * b.radius[k] / speed:.3g} s at this speed")
    return _time.perf_counter() - t0


def locate(sim: Any, el: int) -> str:
    """Which body element ``el`` belongs to, where it is and what it touches."""
    e, b = sim.elements, sim.bodies
    if not 0 <= el < len(e):
        return ""
    k = int(e.owner[el])
    touching = []
    wc, c = sim.wall_contacts, sim.contacts
    for q in range(int(wc.start[el]), int(wc.start[el + 1])):
        if wc.active[q]:
            bi = int(sim.walls.owner[wc.key[q]])
            touching.append(f"boundary {bi} ({sim.boundaries[bi].name})")
    for kk in range(int(c.start[el]), int(c.start[el + 1])):
        if c.active[kk]:
            touching.append(f"particle {b.id[e.owner[c.key[kk]]]}")
    for kk in np.flatnonzero(c.key[:c.count] == el):  # pairs where it is second
        if c.active[kk]:
            i = int(np.searchsorted(c.start, kk, side="right") - 1)
            touching.append(f"particle {b.id[e.owner[i]]}")
    p = b.position[k]
    v = float(np.linalg.norm(b.velocity[k]))
    return (f" at particle {b.id[k]} (position ({p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g}) m, "
            f"speed {v:.3g} m/s, touching {', '.join(touching[:6]) or 'nothing now'})")


def unstable(sim: Any, what: str) -> UnstableRunError:
    """The error of an unstable run, with the time-step figures; the output is flushed
    and closed first, so every frame written so far stays readable."""
    sim.backend.sync_host()  # (the failing state, on the host)
    rep = sim.time_step_report() if np.all(np.isfinite(sim.bodies.velocity)) else None
    hint = ""
    if rep is not None and rep.contact_time is not None:
        hint = (f"; shortest contact {rep.contact_time:.3g} s = "
                f"{rep.steps_per_contact:.3g} steps")
    if rep is not None and rep.rayleigh is not None:
        hint += f"; Rayleigh step {rep.rayleigh:.3g} s"
    written = ""
    w = sim._writer
    if w is not None:
        try:  # the failing state as the last frame (unless the last frame is this step)
            if w.frames == 0 or sim._last_frame_step != sim.step_count:
                sim._write_frame()
        except Exception:  # noqa: BLE001  (the diagnosis must not be lost to the output)
            pass
        w.flush()
        written = (f"; {w.frames} frame(s) written to {w.path} stay readable (the last "
                   "is the failing state)")
    saved = failure_checkpoint(sim)
    if saved:
        written += f"; the failing state is in the checkpoint {saved}"
    sim.close()
    return UnstableRunError(
        f"unstable run at step {sim.step_count} (t = {sim.time:.6g} s): {what}. "
        f"dt = {sim.dt:g} s{hint}. Reduce dt, raise the damping or check the "
        f"stiffness{written}")


def failure_checkpoint(sim: Any) -> str:
    """Write the failing state to a checkpoint beside the output or the periodic
    checkpoints (``<name>.failed.h5``); "" when the run writes neither."""
    from pathlib import Path

    base = None
    if sim.operations.checkpoints is not None:
        base = sim.operations.checkpoints.base
    elif sim._writer is not None:
        base = Path(sim._writer.path)
    if base is None:
        return ""
    path = base.with_name(f"{base.stem}.failed{base.suffix or '.h5'}")
    try:
        sim.checkpoint(path)
    except Exception:  # noqa: BLE001  (the diagnosis must not be lost to the checkpoint)
        return ""
    return str(path)
