"""The quantities of interest the advisor knows: how each is measured on a run, and which
errors of the model propagate to it.

- ``settled_height``: mean height of the bodies' centres above the lowest body's bottom,
  along -g, at the end of the run (box_settle's mean height when the bed rests on z = 0);
- ``angle_of_repose``: dynamic angle of repose of a bed in a rotating drum (a ``tube``
  boundary moved by a :class:`dpm.Rotation`), the mean over samples every ``every``
  seconds in the window (default: the second half of the run) of
  :func:`dpm.analysis.angle_of_repose` (Henein, Brimacombe & Watkinson 1983);
- ``discharge_rate``: mass per second removed by the outlets in the window (default: from
  a quarter of the way between the first scheduled switch-off, the opening of a plug, and
  the end, to the end: the start-up transient left out), as ``examples/hopper_discharge.py``
  measures the silo against Beverloo (1961).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError


@dataclass(frozen=True)
class Quantity:
    """A quantity of interest: its name, unit, what it is, and the assumption of which
    errors propagate to it (the text the advice states)."""

    name: str
    unit: str
    description: str
    propagation: str
    aliases: tuple[str, ...] = ()

    def check(self, sim: Any) -> None:
        """Raise :class:`~dpm.errors.ParameterError` when the scene cannot give it."""

    def window(self, sim: Any, until: float, window: tuple[float, float] | None
               ) -> tuple[float, float]:
        return (until, until) if window is None else window

    def sample_times(self, sim: Any, until: float, window: tuple[float, float] | None
                     ) -> list[float]:
        """Times at which :meth:`sample` is called (the end always)."""
        return []

    def sample(self, sim: Any, state: dict) -> None:
        """Record what the value needs at the current time."""

    def value(self, sim: Any, state: dict, until: float,
              window: tuple[float, float] | None) -> float:
        raise NotImplementedError


class SettledHeight(Quantity):
    def check(self, sim: Any) -> None:
        if not np.linalg.norm(sim.gravity) > 0:
            raise ParameterError("quantity='settled_height' needs gravity (the scene has "
                                 "gravity=(0, 0, 0))")

    def value(self, sim, state, until, window):
        b = sim.bodies
        up = -np.asarray(sim.gravity, float) / np.linalg.norm(sim.gravity)
        h = b.position @ up
        return float(np.mean(h) - np.min(h - b.radius))


def drum_of(sim: Any) -> tuple[np.ndarray, np.ndarray, float]:
    """(axis point, axis, radius) of the scene's rotating drum: the ``tube`` boundary moved
    by a :class:`dpm.Rotation`."""
    from ..motion import Rotation

    for bd in sim.boundaries:
        if getattr(bd, "name", "") == "tube" and isinstance(bd.motion, Rotation):
            p = bd.params
            r = p["radius"] if p.get("radius") is not None else max(p["radius_start"],
                                                                   p["radius_end"])
            return np.asarray(bd.motion.pivot, float), np.asarray(bd.motion.axis), float(r)
    raise ParameterError("quantity='angle_of_repose' needs a rotating drum: a 'tube' "
                         "boundary with motion=dpm.Rotation(...); the scene has none")


class AngleOfRepose(Quantity):
    every = 0.02

    def check(self, sim: Any) -> None:
        drum_of(sim)
        if not np.linalg.norm(sim.gravity) > 0:
            raise ParameterError("quantity='angle_of_repose' needs gravity")

    def window(self, sim, until, window):
        if window is not None:
            return window
        t0 = sim.time
        return (t0 + 0.5 * (until - t0), until)

    def sample_times(self, sim, until, window):
        a, b = self.window(sim, until, window)
        n = max(1, int(round((b - a) / self.every)))
        return [a + (b - a) * k / n for k in range(1, n + 1)]

    def sample(self, sim, state):
        from ..analysis import angle_of_repose

        point, axis, radius = drum_of(sim)
        state.setdefault("angles", []).append(
            angle_of_repose(sim, point, axis, radius, gravity=sim.gravity))

    def value(self, sim, state, until, window):
        a = state.get("angles", [])
        if not a:
            raise ParameterError("angle_of_repose: no sample in the window")
        return float(np.mean(a))


class DischargeRate(Quantity):
    def check(self, sim: Any) -> None:
        if not sim.outlets:
            raise ParameterError("quantity='discharge_rate' needs an outlet "
                                 "(sim.add_outlet); the scene has none")

    def window(self, sim, until, window):
        if window is not None:
            return window
        offs = [s.time for s in sim.operations.switches.pending if not s.on]
        t_open = min(offs) if offs else sim.time
        return (t_open + 0.25 * (until - t_open), until)

    def value(self, sim, state, until, window):
        a, b = self.window(sim, until, window)
        t = np.concatenate([o.records["time"] for o in sim.outlets])
        m = np.concatenate([o.records["mass"] for o in sim.outlets])
        sel = (t > a) & (t <= b)
        return float(np.sum(m[sel]) / (b - a))


QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    SettledHeight(
        "settled_height", "m",
        "mean height of the bodies' centres above the lowest body's bottom at the end",
        "the packing a bed settles into is set by how its contacts dissipate and hold "
        "(restitution and tangential spring, both resolved by the step) and by friction; "
        "the static overlaps are exact at any step, and a contact law of another stiffness "
        "moves the height by the change of the overlap, a fraction delta/R of it",
        ("height", "bed_height", "mean_height")),
    AngleOfRepose(
        "angle_of_repose", "deg",
        "dynamic angle of repose of the bed in a rotating drum, mean over the window",
        "the angle of a rolling bed is set by friction and rolling friction and by the "
        "dissipation in the flowing layer (resolved by the step); a stiffness "
        "error enters through the overlaps (delta/R)",
        ("dynamic_angle_of_repose", "repose_angle", "angle")),
    DischargeRate(
        "discharge_rate", "kg/s",
        "mass per second leaving through the outlets in the window",
        "the rate through an orifice is set by its size, the bulk density and the arch "
        "at the orifice (Beverloo 1961): friction and packing, through the contacts the step "
        "resolves; a stiffness error enters through the overlaps (delta/R)",
        ("rate", "mass_flow_rate", "flow_rate")),
)}


def quantity(name: Any) -> Quantity:
    """The quantity named ``name`` (or one of its aliases)."""
    if isinstance(name, Quantity):
        return name
    for q in QUANTITIES.values():
        if name == q.name or name in q.aliases:
            return q
    raise ParameterError(f"dpm.advise(): quantity={name!r} is not known; allowed: "
                         + ", ".join(QUANTITIES)
                         + " (aliases: " + ", ".join(a for q in QUANTITIES.values()
                                                     for a in q.aliases) + ")")


@dataclass
class Measurement:
    """A run of the scene measured: the quantity's ``value``, the wall and the process's CPU
    time of the run's steps (the first step, which compiles or loads the kernels, left
    out), the steps taken and the bodies at the start."""

    value: float
    wall_s: float
    steps: int
    simulated_s: float
    bodies: int
    samples: dict = field(default_factory=dict)
    cpu_s: float = float("nan")

    @property
    def cost(self) -> float:
        """Wall seconds per simulated second."""
        return self.wall_s / max(self.simulated_s, 1e-300)

    @property
    def cpu_cost(self) -> float:
        """CPU seconds per simulated second (one thread: the work, less sensitive than the
        wall time to other processes on the machine)."""
        return self.cpu_s / max(self.simulated_s, 1e-300)


def run_and_measure(sim: Any, q: Any, until: float,
                    window: tuple[float, float] | None = None) -> Measurement:
    """Run ``sim`` to ``until`` [s] and measure the quantity ``q`` (a name or a
    :class:`Quantity`)."""
    q = quantity(q)
    q.check(sim)
    n0 = len(sim.bodies)
    win = q.window(sim, until, window)  # fixed before the run: the defaults read sim.time
    sim.run(steps=1, progress=False)  # compiles or loads the kernels: not timed
    steps0 = sim.step_count
    t_timed = sim.time
    state: dict = {}
    wall = cpu = 0.0
    for t in q.sample_times(sim, until, win):
        if t > sim.time + 0.5 * sim.dt:
            t0, c0 = time.perf_counter(), time.process_time()
            sim.run(until=t, progress=False)
            wall += time.perf_counter() - t0
            cpu += time.process_time() - c0
        q.sample(sim, state)
    if until > sim.time + 0.5 * sim.dt:
        t0, c0 = time.perf_counter(), time.process_time()
        sim.run(until=until, progress=False)
        wall += time.perf_counter() - t0
        cpu += time.process_time() - c0
    v = q.value(sim, state, until, win)
    if not math.isfinite(v):
        raise ParameterError(f"{q.name}: the run gave {v}")
    return Measurement(v, wall, sim.step_count - steps0, sim.time - t_timed, n0, state, cpu)
