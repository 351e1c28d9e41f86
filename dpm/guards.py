"""Run-time guards: energy created from nothing, NaN or inf in the state, particles that
escape the scene; and the energy book they read.

After each kernel call the run loop calls :func:`check`. Each guard either stops the run
(``"stop"``: an :class:`~dpm.errors.UnstableRunError` naming the step, the time, the
particles and what to change, after the failing state was written to the output and to a
checkpoint), warns once (``"warn"``) or is off. Escaping particles may instead be removed
and recorded (``"remove"``, the default, as LIGGGHTS deletes lost atoms).

Energy book (:class:`EnergyBook`): the mechanical energy E = sum (1/2 m v.v + 1/2 w.I w)
- sum m g.x of the bodies, the work the boundaries did on them (their drives; summed each
step in the kernels, :func:`dpm.kernels.step.boundary_work`), what inserted bodies
brought and removed bodies took away. What is missing is the energy dissipated (damping,
friction, plastic work) plus what the contacts store elastically:

    D = E_0 + W_boundaries + E_inserted - E_removed - E  >= 0.

A contact law or integrator that creates energy makes D negative; the energy guard acts
when -D exceeds what the start state may release (the energy of lifting every body by the
initial overlap tolerated, plus an upper estimate of the elastic energy its contacts hold,
:func:`initial_elastic_bound`) plus ``energy_growth`` times the energy scale of the run
(the largest of E_0 above the lowest body, the largest kinetic energy seen, the inserted
energy, the boundary work and that release). Scenes with an adhesive law are not
bounded (adhesion holds energy as a negative potential and releases it).
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from .errors import ParameterError
from .measures import kinetic_energy

ACTIONS = ("stop", "warn", "off")
ESCAPE_ACTIONS = ("remove", "warn", "stop", "off")


def energies(b: Any, gravity: np.ndarray, rows: Any = None) -> tuple[float, float]:
    """(kinetic, mechanical) energy [J] of the bodies ``b`` (or of ``rows`` of them):
    kinetic translational and rotational; mechanical adds the gravitational energy, zero
    at the origin."""
    if rows is not None:
        from types import SimpleNamespace

        b = SimpleNamespace(mass=b.mass[rows], velocity=b.velocity[rows],
                            orientation=b.orientation[rows],
                            angular_velocity=b.angular_velocity[rows],
                            inertia=b.inertia[rows], position=b.position[rows])
    if len(b.mass) == 0:
        return 0.0, 0.0
    kin = kinetic_energy(b)
    return kin, kin - float(np.sum(b.mass * (b.position @ np.asarray(gravity))))


def mechanical_energy(b: Any, gravity: np.ndarray, rows: Any = None) -> float:
    """Kinetic plus gravitational energy [J] of the bodies ``b`` (or ``rows`` of them)."""
    return energies(b, gravity, rows)[1]


class EnergyBook:
    """The energy balance of a run (see the module docstring); ``sim.energy``."""

    def __init__(self) -> None:
        self.started = False
        self.initial = 0.0
        self.inserted = 0.0
        self.removed = 0.0
        self.scale = 0.0
        self.kinetic_max = 0.0
        self.adhesive = False
        self.floor = 0.0

    def start(self, sim: Any) -> None:
        b = sim.bodies
        self.started = True
        # adhesive laws release energy they hold as (negative) potential: no bound then
        self.adhesive = any(getattr(law, "adhesion", None) is not None
                            for law in sim._contacts.values())
        # the least energy that counts: lifting every body by the initial overlap
        # tolerated (overlap_tolerance of its radius) against max(|g|, 9.81 m/s2); the
        # elastic energy of such overlaps is released at the start
        gref = max(float(np.linalg.norm(sim.gravity)), 9.81)
        self.floor = float(np.sum(b.mass * b.radius)) * gref * max(sim.overlap_tolerance,
                                                                    1e-3)
        self.floor += initial_elastic_bound(sim)
        self.initial = mechanical_energy(b, sim.gravity)
        g = float(np.linalg.norm(sim.gravity))
        above = 0.0
        if len(b) and g > 0:
            h = -(b.position @ sim.gravity) / g
            above = float(np.sum(b.mass * g * (h - h.min())))
        self.scale = above + kinetic_energy(b) if len(b) else 0.0

    @staticmethod
    def work(sim: Any) -> float:
        return float(sum(bd.work for bd in sim.boundaries))

    def balance(self, sim: Any) -> dict[str, float]:
        """initial, work, inserted, removed, current (E), kinetic and dissipated (D above)
        [J] (the bodies' energies from the backend: :meth:`CpuBackend.energies`, summed
        over the ranks' owned rows by an MPI backend between a run's calls)."""
        kin, now = sim.backend.energies(sim.gravity)
        w = self.work(sim)
        return {"initial": self.initial, "work": w, "inserted": self.inserted,
                "removed": self.removed, "current": now, "kinetic": kin,
                "dissipated": self.initial + w + self.inserted - self.removed - now}

    def added(self, sim: Any, rows: Any) -> None:
        if self.started:
            self.inserted += mechanical_energy(sim.bodies, sim.gravity, rows)

    def taken(self, sim: Any, rows: Any) -> None:
        if self.started:
            self.removed += mechanical_energy(sim.bodies, sim.gravity, rows)


def initial_elastic_bound(sim: Any) -> float:
    """An upper estimate [J] of the elastic energy the contacts of the start state hold
    (tolerated initial overlaps, a pre-compressed sample): sum over overlapping pairs and
    boundary entries of m (pi delta / t_c)^2, with m the smaller body mass, delta the
    overlap and t_c the shortest contact duration of the scene (a linear spring of that
    period holds 1/2 m (pi delta / t_c)^2: twice that covers stiffer Hertz contacts at
    small overlaps)."""
    if sim.plan is None or len(sim.bodies) == 0:
        return 0.0
    try:
        tc = sim.time_step_report().contact_time
    except Exception:  # noqa: BLE001  (an estimate only)
        return 0.0
    if not tc:
        return 0.0
    b, e = sim.bodies, sim.elements
    total = 0.0
    c, wc = sim.contacts, sim.wall_contacts
    if c.count:
        ratio = sim.backend.pair_overlaps()
        rows = np.repeat(np.arange(len(e)), np.diff(c.start))
        j = c.key[:c.count]
        hit = ratio > 0
        if np.any(hit):
            i, j = rows[hit], j[hit]
            delta = ratio[hit] * np.minimum(e.radius[i], e.radius[j])
            m = np.minimum(b.mass[e.owner[i]], b.mass[e.owner[j]])
            total += float(np.sum(m * (np.pi * delta / tc) ** 2))
    if wc.count:
        ratio = sim.backend.entry_overlaps()
        rows = np.repeat(np.arange(len(e)), np.diff(wc.start))
        hit = ratio > 0
        if np.any(hit):
            i = rows[hit]
            delta = ratio[hit] * e.radius[i]
            total += float(np.sum(b.mass[e.owner[i]] * (np.pi * delta / tc) ** 2))
    return total


class Guards:
    """What the run does when it meets trouble (``sim.guards``).

    energy : {"stop", "warn", "off"}
        Energy created from nothing beyond ``energy_growth`` of the run's energy scale
        (default "warn": an integrator's own error at a coarse step is the user's choice;
        "stop" for production runs).
    energy_growth : float
        The bound, as a fraction (default 0.05).
    nonfinite : {"stop", "warn", "off"}
        NaN or inf in positions, velocities, orientations, angular velocities, forces or
        torques ("warn" still stops at NaN positions: nothing can go on from there).
    escape : {"remove", "warn", "stop", "off"}
        Particles whose centre leaves the scene's box (the box around every finite
        boundary, inlet and outlet region and the particles at the start of the run,
        grown by ``escape_margin`` times its size on each side; periodic axes
        excepted): removed and recorded in ``sim.escaped`` (and ``/removed`` of the
        output, outlet index -1), warned about, or the run stops.
    escape_margin : float
        See ``escape`` (default 1.0).
    """

    _spec = {"energy": ACTIONS, "nonfinite": ACTIONS, "escape": ESCAPE_ACTIONS}

    def __init__(self, energy: str = "warn", energy_growth: float = 0.05,
                 nonfinite: str = "stop", escape: str = "remove",
                 escape_margin: float = 1.0) -> None:
        self.energy = energy
        self.energy_growth = energy_growth
        self.nonfinite = nonfinite
        self.escape = escape
        self.escape_margin = escape_margin
        self._warned: set[str] = set()

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self._spec and value not in self._spec[name]:
            raise ParameterError(f"sim.guards.{name}={value!r}; allowed: "
                                 f"{', '.join(self._spec[name])}")
        if name in ("energy_growth", "escape_margin"):
            if isinstance(value, bool | str) or not isinstance(value, int | float) \
                    or not (math.isfinite(value) and value > 0):
                raise ParameterError(f"sim.guards.{name}={value!r} must be a finite number "
                                     "> 0")
            value = float(value)
        super().__setattr__(name, value)

    def warn_once(self, key: str, message: str) -> None:
        if key not in self._warned:
            self._warned.add(key)
            warnings.warn(message, stacklevel=4)


STATE_ARRAYS = ("position", "velocity", "orientation", "angular_velocity", "force", "torque")


def nonfinite_bodies(b: Any) -> tuple[str, np.ndarray]:
    """(the state arrays with NaN or inf, comma-separated; the rows of the bodies that
    have them)."""
    names, bad = [], np.zeros(len(b), bool)
    for name in STATE_ARRAYS:
        arr = getattr(b, name)
        if not np.isfinite(arr).all():
            names.append(name)
            bad |= ~np.all(np.isfinite(arr), axis=1)
    return ", ".join(names), np.flatnonzero(bad)


def scene_box(sim: Any) -> np.ndarray:
    """(2, 3) the box of the scene for the escape guard (see :class:`Guards`)."""
    pts = [sim.bodies.position] if len(sim.bodies) else []
    for flow in [*sim.inlets, *sim.outlets]:
        r = flow.region
        if hasattr(r, "lower") and hasattr(r, "upper"):
            pts.append(np.array([r.lower, r.upper], float))
        if hasattr(r, "start") and hasattr(r, "axis"):
            s = np.asarray(r.start, float)
            e = s + np.asarray(r.axis, float) * float(getattr(r, "length", 0.0))
            rad = float(getattr(r, "radius", 0.0))
            pts.append(np.array([s - rad, s + rad, e - rad, e + rad]))
    if sim.walls is not None:  # finite boundaries: a sphere of their extent about the
        w = sim.walls          # frame origin (planes have none)
        for k in range(len(w.frame)):
            ext = float(w.extent[k])
            if math.isfinite(ext) and 0.0 < ext < 1e6:
                o = w.frame[k, :3]
                pts.append(np.array([o - ext, o + ext]))
    if not pts:
        return np.array([[-np.inf] * 3, [np.inf] * 3])
    allp = np.concatenate([np.atleast_2d(p) for p in pts])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    size = np.max(hi - lo)
    rmax = float(sim.elements.radius.max()) if len(sim.elements) else 0.0
    grow = max(sim.guards.escape_margin * size, 20 * rmax)
    lo, hi = lo - grow, hi + grow
    periodic = sim.period[3:] > 0
    lo[periodic], hi[periodic] = -np.inf, np.inf
    return np.array([lo, hi])


def check(sim: Any) -> None:
    """The guards after a kernel call (see :class:`Guards`)."""
    g = sim.guards
    b = sim.bodies
    be = sim.backend
    look = True  # (whether the host's state is to be searched)
    if getattr(be, "host_stale", False) and len(b):
        # (the host is behind the backend's state: ask the backend whether a guard
        # would find anything, and bring the host up only then)
        box = sim._scene_box
        if box is None:  # (a scene changed by a hook: the box of the current state)
            be.sync_host()
            box = sim._scene_box = scene_box(sim)
        look = be.guard_hits(g.nonfinite != "off", box if g.escape != "off" else None)
        if look:
            be.sync_host()
    if look and g.nonfinite != "off" and len(b):
        name, rows = nonfinite_bodies(b)
        if len(rows):
            from .scene_check import few

            msg = (f"{name} became NaN or inf for particle id(s) {few(b.id[rows])}; "
                   "reduce dt or check the contact parameters")
            if g.nonfinite == "stop" or {"position", "velocity"} & set(name.split(", ")):
                raise sim._failure(msg)
            g.warn_once("nonfinite", f"step {sim.step_count} (t = {sim.time:.6g} s): {msg}")
    if look and g.escape != "off" and len(b):
        box = sim._scene_box
        if box is None:
            box = sim._scene_box = scene_box(sim)
        out = np.flatnonzero(np.any((b.position < box[0]) | (b.position > box[1]), axis=1))
        if len(out):
            from .scene_check import few

            ids = b.id[out]
            msg = (f"{len(out)} particle(s) left the scene (box {box[0].round(4).tolist()} - "
                   f"{box[1].round(4).tolist()} m): id(s) {few(ids)}, e.g. at "
                   f"{b.position[out[0]].round(4).tolist()} m moving at "
                   f"{float(np.linalg.norm(b.velocity[out[0]])):.3g} m/s; close the "
                   "scene with boundaries, add an outlet, or set sim.guards.escape")
            if g.escape == "stop":
                raise sim._failure(msg)
            if g.escape == "warn":
                g.warn_once("escape", f"step {sim.step_count} (t = {sim.time:.6g} s): {msg}")
            else:
                from . import population

                g.warn_once("escape", f"step {sim.step_count} (t = {sim.time:.6g} s): {msg}; "
                            "they are removed and recorded in sim.escaped (warned once)")
                rec = population.remove_bodies(sim, ids)
                sim.escaped.record(rec)
                if sim._writer is not None:
                    sim._writer.write_removed(rec, -1)
    book = sim.energy
    if g.energy != "off" and book.started and len(b) and not book.adhesive:
        bal = book.balance(sim)
        ke = bal["kinetic"]
        book.kinetic_max = max(book.kinetic_max, ke)
        scale = max(book.scale, book.kinetic_max, abs(bal["work"]), book.inserted,
                    book.floor, 1e-300)
        if -bal["dissipated"] > g.energy_growth * scale + book.floor:
            msg = (f"energy was created: the bodies hold {bal['current']:.4g} J, "
                   f"{-bal['dissipated']:.3g} J more than they started with "
                   f"({bal['initial']:.4g} J) plus the boundaries' work ({bal['work']:.3g} J) "
                   f"and what inlets brought ({bal['inserted'] - bal['removed']:.3g} J net), "
                   f"beyond energy_growth={g.energy_growth:g} of the run's energy "
                   f"{scale:.3g} J (kinetic now {ke:.3g} J); the integrator or the contact "
                   "law is unstable at this dt: reduce dt, or choose a symplectic "
                   "integrator (velocity_verlet)")
            if g.energy == "stop":
                raise sim._failure(msg)
            g.warn_once("energy", f"step {sim.step_count} (t = {sim.time:.6g} s): {msg}")


class Escaped:
    """Records of the particles the escape guard removed (``sim.escaped``), as an
    outlet's: id, time, mass, residence_time, position, velocity."""

    FIELDS = ("id", "time", "mass", "residence_time", "position", "velocity")

    def __init__(self) -> None:
        self._parts: dict[str, list[np.ndarray]] = {k: [] for k in self.FIELDS}

    def record(self, records: dict[str, np.ndarray]) -> None:
        for k in self.FIELDS:
            self._parts[k].append(np.asarray(records[k]))

    @property
    def records(self) -> dict[str, np.ndarray]:
        out = {}
        for k in self.FIELDS:
            width = (3,) if k in ("position", "velocity") else ()
            out[k] = (np.concatenate(self._parts[k]) if self._parts[k]
                      else np.zeros((0, *width)))
        return out

    @property
    def count(self) -> int:
        return int(sum(len(a) for a in self._parts["id"]))
