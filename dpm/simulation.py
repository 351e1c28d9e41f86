"""The Simulation: owns the state, the scene description and the run loop."""

from __future__ import annotations

import math
import os
import time as _time
import warnings
from collections.abc import Sequence
from typing import Any

import numba
import numpy as np

from . import plan as _plan
from .boundaries.base import Boundary
from .errors import ParameterError, SceneError, UnstableRunError
from .flow import Inlet, Outlet, random_quaternions
from .impact.base import ImpactModel, PairContext
from .impact.parts import pack_tables
from .kernels.step import (
    STATUS_NAN,
    STATUS_OK,
    STATUS_OVERFLOW,
    STATUS_OVERLAP,
    STATUS_WALL_OVERFLOW,
)
from .material import Material
from .motion import frames
from .parameters import Parameter, validate
from .plugins import registry
from .regions import Region
from .shapes.base import Shape
from .state import Bodies, BoundaryTable, Contacts, Elements, WallContacts
from .timestep import TimeStepReport

DT_CHECKS = ("refuse", "warn", "off")
#: scenes with fewer elements run on one thread unless ``threads`` is given
SMALL_SCENE = 4000
#: most steps per kernel call while boundaries move (frames are tabulated per call)
MOVING_CHUNK = 2000
#: bodies per block of the speed check after each call
SPEED_BLOCK = 1 << 16


class Simulation:
    """A DEM simulation of rigid bodies made of sphere elements.

    Parameters
    ----------
    dt : float or "auto"
        Time step [s], > 0; ``"auto"`` takes 1/20 of the shortest contact duration and at
        most 0.2 of the Rayleigh step, chosen when the run starts (see
        :meth:`time_step_report`).
    gravity : 3-vector
        Gravitational acceleration [m/s2].
    integrator : str
        Registered integrator name (``dpm plugins`` lists them).
    skin : float, optional
        Verlet skin [m]; default 0.2 x the smallest element diameter.
    dt_check : {"refuse", "warn", "off"}
        What to do when dt exceeds the critical step (:class:`dpm.timestep.TimeStepReport`).
    max_overlap : float
        Largest overlap / radius tolerated during a run before it stops as unstable.
    overlap_tolerance : float
        Largest initial overlap / radius accepted at the first step.
    threads : int, optional
        Threads of the step kernels, at most numba's ``NUMBA_NUM_THREADS`` (the cores).
        Default: ``$DPM_THREADS`` if set, else 1 (as LIGGGHTS and Yade run one core unless
        told otherwise: several runs side by side, or a shared machine, then do not
        oversubscribe the cores, which stalls parallel loops badly). Scenes under
        ``SMALL_SCENE`` elements always run on one thread unless ``threads`` is given (there
        starting parallel loops costs more than it gains). Results are identical for any
        number of threads.
    sphere_orientation : bool
        Track the orientation of single-sphere bodies (default True). No force depends on
        it; with False their quaternion is not updated (as LIGGGHTS' ``nve/sphere``) and
        stays as inserted, which spares about a tenth of a settled packing's step.
        Positions, velocities and angular velocities are the same bit for bit either way.
        Clustered bodies always rotate.

    Order of one step (see :mod:`dpm.kernels.step`): integrator pre-force part, element
    positions, neighbour list (rebuilt when an element moved more than skin/2), gravity and
    contact forces, integrator post-force part. Hooks ``dpm_before_step``/``dpm_after_step``
    run around steps, ``dpm_on_output`` after each frame.

    Example
    -------
    >>> sim = Simulation(dt=1e-5, gravity=(0, 0, -9.81))
    """

    parameters = {
        "dt": Parameter(low=0.0, low_open=True, unit="s", doc="time step or 'auto'"),
        "gravity": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m/s2"),
        "integrator": Parameter(default="velocity_verlet", kind="str"),
        "skin": Parameter(default=None, low=0.0, low_open=True, unit="m"),
        "dt_check": Parameter(default="refuse", kind="str"),
        "max_overlap": Parameter(default=0.5, low=0.0, high=2.0, low_open=True),
        "overlap_tolerance": Parameter(default=0.01, low=0.0),
        "threads": Parameter(default=None, low=1, high=numba.config.NUMBA_NUM_THREADS,
                             doc="number of threads"),
        "sphere_orientation": Parameter(default=True, kind="bool",
                                        doc="track the orientation of single spheres"),
    }

    def __init__(self, dt: float | str, gravity: Sequence[float] = (0.0, 0.0, 0.0),
                 integrator: str = "velocity_verlet", skin: float | None = None,
                 dt_check: str = "refuse", max_overlap: float = 0.5,
                 overlap_tolerance: float = 0.01, threads: int | None = None,
                 sphere_orientation: bool = True) -> None:
        self._auto_dt = isinstance(dt, str) and dt == "auto"
        v = validate("Simulation()", self.parameters, dict(
            dt=1.0 if self._auto_dt else dt, gravity=gravity, integrator=integrator,
            skin=skin, dt_check=dt_check,
            max_overlap=max_overlap, overlap_tolerance=overlap_tolerance, threads=threads,
            sphere_orientation=sphere_orientation))
        self.threads = None if threads is None else int(threads)
        #: track the orientation of single-sphere bodies (see the class docstring)
        self.sphere_orientation = bool(v["sphere_orientation"])
        if v["dt_check"] not in DT_CHECKS:
            raise ParameterError(f"Simulation(): dt_check={dt_check!r}; allowed: "
                                 f"{', '.join(DT_CHECKS)}")
        self._registry = registry()
        self.integrator = self._registry.lookup("integrator", integrator,
                                                "Simulation()")()
        self.dt = float("nan") if self._auto_dt else float(v["dt"])
        self.gravity = np.asarray(v["gravity"], float)
        self.skin = v["skin"]
        self.dt_check = v["dt_check"]
        self.max_overlap = float(v["max_overlap"])
        self.overlap_tolerance = float(v["overlap_tolerance"])
        self.materials: list[Material] = []
        self._contacts: dict[tuple[int, int], ImpactModel] = {}
        self.boundaries: list[Boundary] = []
        self.inlets: list[Inlet] = []
        #: periodic box: lower corner [0:3] and period [3:6] per axis (0: not periodic)
        self.period = np.zeros(6)
        self.outlets: list[Outlet] = []
        self.bodies = Bodies()
        self.elements = Elements()
        self.contacts = Contacts()
        self.wall_contacts = WallContacts()
        self.walls: BoundaryTable | None = None
        self.time = 0.0
        self.step_count = 0
        self.rebuild_count = 0
        self._next_id = 0
        self._prepared = False
        self._forces_valid = False
        self._rows_stale = False  # pair force rows left stale by the fused pass
        self._check_cost = 0.0  # seconds of the checks after the last kernel call
        self._two_pass = False  # True: sum forces in two passes even for spheres (tests)
        self._writer = None
        #: the Writer of the latest output file (open or closed): .path, .frames
        self.last_output = None
        self._output_path: str | None = None
        self._output_every: int | None = None
        self._output_every_s: float | None = None
        self._diag = np.zeros(8)
        self._module = None
        self._pair_model = np.zeros((0, 0), np.int64)
        self._pair_params = np.zeros((0, 0, 8))

    # ----------------------------------------------------------------- scene building
    def _material_index(self, m: Material, call: str) -> int:
        if not isinstance(m, Material):
            raise ParameterError(f"{call}: material={m!r} must be a dpm.Material")
        for k, known in enumerate(self.materials):
            if known is m:
                return k
        if any(known.name == m.name for known in self.materials):
            raise ParameterError(f"{call}: another material is already named {m.name!r}")
        self.materials.append(m)
        return len(self.materials) - 1

    def contact(self, a: Material, b: Material, model: str = "hertz_mindlin",
                **params: Any) -> ImpactModel:
        """Set the impact model of the material pair (a, b) with its parameters.

        ``params`` are the model's (``dpm plugins`` and ``docs/impact-models.md`` list
        them), e.g. ``restitution=0.3, friction=0.5, rolling_friction=0.0``.
        """
        call = f"sim.contact({getattr(a, 'name', a)}, {getattr(b, 'name', b)})"
        ia = self._material_index(a, call)
        ib = self._material_index(b, call)
        cls = self._registry.lookup("impact_model", model, call)
        law = cls(call=call, **params)
        if law.needs_elastic_constants:
            missing = [f"{m.name}.{p}" for m in dict.fromkeys((a, b))
                       for p in ("young", "poisson") if getattr(m, p) is None]
            if missing:
                raise ParameterError(f"{call}: model={model!r} needs young and poisson; "
                                     f"missing: {', '.join(missing)}")
        self._contacts[(ia, ib)] = law
        self._contacts[(ib, ia)] = law
        self._prepared = False
        return law

    def add_boundary(self, kind: str, material: Material, **params: Any) -> Boundary:
        """Add a boundary of a registered kind (``plane``, ``box``, ...); return it."""
        call = f"sim.add_boundary({kind!r})"
        cls = self._registry.lookup("boundary", kind, call)
        self._material_index(material, call)
        b = cls(material, call=call, **params)
        self.boundaries.append(b)
        self._prepared = False
        self._forces_valid = False
        return b

    def add_particles(self, shape: str | Shape, material: Material,
                      positions: np.ndarray | Sequence[Sequence[float]],
                      velocities: np.ndarray | None = None,
                      angular_velocities: np.ndarray | None = None,
                      orientations: np.ndarray | None = None, **shape_params: Any) -> np.ndarray:
        """Add bodies of ``shape`` (a registered name or a Shape instance); return their ids.

        ``positions`` (N, 3) [m] of the centres of mass; ``velocities``,
        ``angular_velocities`` (N, 3) [m/s, rad/s]; ``orientations`` (N, 4) unit quaternions
        (w, x, y, z) rotating the shape's documented frame into the world. Shape parameters
        are keyword arguments, e.g. ``radius=1e-3`` (scalar or one per particle). The stored
        ``bodies.orientation`` is that of the principal frame (shape frame times the shape's
        principal rotation).
        """
        call = f"sim.add_particles({shape if isinstance(shape, str) else type(shape).__name__!r})"
        imat = self._material_index(material, call)
        pos = _rows(call, "positions", positions, 3)
        n = len(pos)
        vel = (np.zeros((n, 3)) if velocities is None
               else _rows(call, "velocities", velocities, 3, n))
        ang = (np.zeros((n, 3)) if angular_velocities is None
               else _rows(call, "angular_velocities", angular_velocities, 3, n))
        if orientations is None:
            quat = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
        else:
            quat = _rows(call, "orientations", orientations, 4, n)
            norm = np.linalg.norm(quat, axis=1)
            if np.any(norm == 0):
                raise ParameterError(f"{call}: orientations has a zero quaternion at row "
                                     f"{int(np.argmin(norm))}")
            quat = quat / norm[:, None]
        if isinstance(shape, Shape):
            sh = shape
        else:
            cls = self._registry.lookup("shape", shape, call)
            sh = cls(call=call, **shape_params)
        batch = sh.build(n, material.density)
        quat = _quat_multiply(quat, np.asarray(batch.principal_rotation, float))
        first = len(self.bodies)
        ids = np.arange(self._next_id, self._next_id + n, dtype=np.int64)
        self._next_id += n
        self.bodies.append(
            id=ids, position=pos, velocity=vel, angular_velocity=ang, orientation=quat,
            force=np.zeros((n, 3)), torque=np.zeros((n, 3)), mass=batch.mass,
            inertia=batch.inertia, invmass=1.0 / batch.mass, invinertia=1.0 / batch.inertia,
            radius=batch.bounding_radius, material=_filled(n, imat, np.int64),
            shape=np.zeros(n, np.int64), birth=_filled(n, self.time, float))
        b = self.bodies
        b.element_start = np.concatenate(
            [b.element_start, b.element_start[-1] + np.cumsum(batch.element_count)])
        owner = np.repeat(np.arange(first, first + n), batch.element_count)
        self.elements.append(owner, batch.element_offset, batch.element_radius,
                             _filled(len(owner), imat, np.int64))
        self._prepared = False
        self._forces_valid = False
        return ids.copy()  # (the bodies keep ``ids`` itself: see Bodies.append)

    def set_periodic(self, axis: str | int, lower: float, upper: float) -> None:
        """Make ``axis`` ("x", "y", "z" or 0-2) periodic between ``lower`` and ``upper``
        [m]: a body leaving through one face re-enters through the other, and contacts
        act between nearest images. The period must be at least twice the contact search
        cell (2 (2 r_max + skin)); checked when the run starts."""
        axes = {"x": 0, "y": 1, "z": 2, 0: 0, 1: 1, 2: 2}
        if axis not in axes:
            raise ParameterError(f"sim.set_periodic(): axis={axis!r}; allowed: x, y, z")
        if not (math.isfinite(lower) and math.isfinite(upper) and upper > lower):
            raise ParameterError(f"sim.set_periodic(): upper={upper!r} must exceed "
                                 f"lower={lower!r} (finite)")
        d = axes[axis]
        self.period[d] = float(lower)
        self.period[3 + d] = float(upper - lower)
        self._prepared = False
        self._forces_valid = False

    def _check_period(self) -> None:
        need = 2.0 * (2.0 * float(self.elements.radius.max()) + self.skin)
        for d in range(3):
            if 0.0 < self.period[3 + d] < need:
                raise ParameterError(
                    f"sim.set_periodic(): the period along {'xyz'[d]} is "
                    f"{self.period[3 + d]:.4g} m; it must be at least {need:.4g} m (twice "
                    "the contact search range 2 r_max + skin) for nearest images to be unique")

    def _wrap_periodic(self) -> None:
        """Move bodies that left the periodic box back in by whole periods (their elements
        and rebuild references move with them, so no rebuild is triggered)."""
        b, e = self.bodies, self.elements
        for d in range(3):
            length = self.period[3 + d]
            if length <= 0.0 or len(b) == 0:
                continue
            shift = np.floor((b.position[:, d] - self.period[d]) / length) * length
            moved = shift != 0.0
            if not np.any(moved):
                continue
            b.position[:, d] -= shift
            es = shift[e.owner]
            if not self._spheres_only:
                e.position[:, d] -= es
            e.reference[:, d] -= es

    def add_inlet(self, region: Region, material: Material, **params: Any) -> Inlet:
        """Insert particles during the run (:class:`dpm.flow.Inlet`: ``rate`` or
        ``mass_rate``, ``shapes`` mix or ``shape`` + parameters, ``velocity``, ``start``,
        ``stop``, ``every``, ``seed``); return the inlet."""
        self._material_index(material, "sim.add_inlet()")
        inlet = Inlet(region, material, **params)
        self.inlets.append(inlet)
        return inlet

    def add_outlet(self, region: Region, remove: str = "inside", every: float = 1e-3,
                   name: str = "") -> Outlet:
        """Remove particles whose centre is inside (or outside) ``region`` every ``every``
        seconds, recording them (:class:`dpm.flow.Outlet`); return the outlet."""
        outlet = Outlet(region, remove=remove, every=every, name=name)
        self.outlets.append(outlet)
        return outlet

    def remove_particles(self, ids: np.ndarray | Sequence[int]) -> dict[str, np.ndarray]:
        """Remove the bodies with these ids now; return their records (id, time, mass,
        residence_time, position, velocity). Contact history of the others is kept."""
        b, e = self.bodies, self.elements
        gone = np.isin(b.id, np.asarray(ids, np.int64))
        rec = {"id": b.id[gone].copy(), "time": np.full(int(gone.sum()), self.time),
               "mass": b.mass[gone].copy(), "residence_time": self.time - b.birth[gone],
               "position": b.position[gone].copy(), "velocity": b.velocity[gone].copy()}
        if not np.any(gone):
            return rec
        keep_b = ~gone
        keep_e = keep_b[e.owner]
        new_b = np.cumsum(keep_b) - 1
        new_e = np.cumsum(keep_e) - 1
        if self._prepared:
            self.contacts.keep_rows(keep_e, new_e, True)
            self.wall_contacts.keep_rows(keep_e, new_e, False)
            self._aux = np.ascontiguousarray(self._aux[keep_b])
        b.keep(keep_b)
        e.keep(keep_e, new_b)
        if self._prepared:
            self._population_changed()
        return rec

    def _population_changed(self) -> None:
        """After bodies were inserted or removed during a run: resize the per-element
        arrays (keeping the contact lists and their history), rebuild, recompute forces."""
        b, e = self.bodies, self.elements
        n_el = len(e)
        self._spheres_only = bool(len(e) == len(b) and np.all(e.offset == 0.0)
                                  and np.array_equal(e.owner, np.arange(len(b))))
        self._sync_form()
        if self._spheres_only:
            _share_sphere_arrays(b, e)
        elif len(b):
            self._module.update_element_positions(b.position, b.orientation, b.element_start,
                                                  e.offset, e.position)
        self.contacts.resize_rows(n_el)
        self.wall_contacts.resize_rows(n_el)
        self._e_worst = np.zeros(n_el)
        self._e_count = np.zeros(n_el, np.int32)
        self._vf = np.zeros((len(b), 3))
        self._wf = np.zeros((len(b), 3))
        if len(self._aux) < len(b):
            extra = np.zeros((len(b) - len(self._aux), self._aux.shape[1]))
            self._aux = np.ascontiguousarray(np.concatenate([self._aux, extra]))
        e.reference = np.full((n_el, 3), np.inf)
        self._rebuild()
        self._prime_forces()
        self._update_boundary_loads()
        self._prepared = True

    def _flow_event(self) -> None:
        """Outlets, then inlets, at the current time."""
        hooks = self._registry.manager.hook
        changed = False
        prepared = self._prepared
        for outlet in self.outlets:
            if len(self.bodies) == 0:
                break
            sel = outlet.select(self.bodies.position)
            if np.any(sel):
                rec = self.remove_particles(self.bodies.id[sel])
                outlet.record(rec)
                if self._writer is not None:
                    self._writer.write_removed(rec, self.outlets.index(outlet))
                hooks.dpm_on_particles_removed(sim=self, outlet=outlet, records=rec)
        for inlet in self.inlets:
            ids = self._insert(inlet)
            if len(ids):
                changed = True
                hooks.dpm_on_particles_inserted(sim=self, inlet=inlet, ids=ids)
        if changed and prepared:
            self._population_changed()

    def _insert(self, inlet: Inlet) -> np.ndarray:
        """Place what ``inlet`` owes now; return the new ids."""
        from scipy.spatial import cKDTree

        from .kernels.boundary_search import boundary_gaps

        owed = inlet.owed(self.time + inlet.every)  # what the coming interval brings
        by_mass = inlet.mass_rate is not None
        if (owed < 1.0 and not by_mass) or owed <= 0.0:
            return np.zeros(0, np.int64)
        b = self.bodies
        tree = cKDTree(b.position) if len(b) else None
        rmax = float(b.radius.max()) if len(b) else 0.0
        if self.walls is None or len(self.walls.frame) != len(self.boundaries):
            table = BoundaryTable(self.boundaries, lambda m: self._material_index(m, ""), 1.0)
            for k, bd in enumerate(self.boundaries):
                table.frame[k] = frames(bd.motion, np.array([self.time]))[0]
        else:
            table = self.walls
        placed_pos: list[np.ndarray] = []
        placed_r: list[float] = []
        new_ids = []
        while (owed >= 1.0) if not by_mass else (owed > 0.0):
            name, params = inlet.draw()
            cls = self._registry.lookup("shape", name, "sim.add_inlet()")
            sh = cls(call="sim.add_inlet()", **params)
            batch = sh.build(1, inlet.material.density)
            rb = float(batch.bounding_radius[0])
            cand = inlet.region.sample(inlet.rng, inlet.max_attempts, rb)
            ok = np.ones(len(cand), bool)
            if tree is not None:
                for k, hits in enumerate(tree.query_ball_point(cand, rb + rmax)):
                    if hits:
                        d = np.linalg.norm(b.position[hits] - cand[k], axis=1)
                        ok[k] = bool(np.all(d >= rb + b.radius[hits]))
            if placed_pos:
                pp = np.asarray(placed_pos)
                d = np.linalg.norm(cand[:, None, :] - pp[None], axis=2)
                ok &= np.all(d >= rb + np.asarray(placed_r)[None], axis=1)
            pick = -1
            for k in np.flatnonzero(ok):  # the first candidate clear of every boundary
                if len(table.kind) == 0 or boundary_gaps(
                        cand[k:k + 1], np.array([rb]), table.frame, table.kind, table.par,
                        table.owner)[0] >= 0.0:
                    pick = int(k)
                    break
            if pick < 0:
                break  # the region is full for now: the rest stays owed
            p = cand[pick]
            q = (random_quaternions(inlet.rng, 1) if inlet.random_orientation
                 else np.array([[1.0, 0, 0, 0]]))
            ids = self.add_particles(sh, inlet.material, positions=p[None],
                                     velocities=inlet.velocity[None], orientations=q)
            new_ids.append(ids)
            placed_pos.append(p)
            placed_r.append(rb)
            m = float(batch.mass[0])
            owed -= m if by_mass else 1.0
            inlet.inserted += 1
            inlet.inserted_mass += m
        inlet._due = owed
        out = np.concatenate(new_ids) if new_ids else np.zeros(0, np.int64)
        inlet.ids.append(out)
        return out

    def output(self, path: str, every: float | None = None,
               every_steps: int | None = None) -> None:
        """Write frames to HDF5 at ``path`` (+ XDMF beside it) every ``every`` seconds or
        ``every_steps`` steps. The file is created when the next run starts, with the state
        at that moment as its first frame."""
        if (every is None) == (every_steps is None):
            raise ParameterError("sim.output(): give exactly one of every (s) or every_steps")
        if every is not None:
            validate("sim.output()", {"every": Parameter(low=0.0, low_open=True, unit="s")},
                     {"every": every})
        else:
            validate("sim.output()", {"every_steps": Parameter(low=1, kind="float")},
                     {"every_steps": every_steps})
        self.close()
        self._writer = None
        self._output_path = str(path)
        self._output_every_s = every
        self._output_every = None if every is not None else int(every_steps)

    def close(self) -> None:
        """Close the output file; a later run appends to a new file only after a new
        :meth:`output` call."""
        if self._writer is not None:
            self._writer.close()
            self._output_path = None
            self._writer = None

    # ----------------------------------------------------------------- checks
    def time_step_report(self) -> TimeStepReport:
        """Rayleigh step and shortest contact duration of the current scene."""
        b = self.bodies
        er = self.elements.radius
        speed = float(np.max(np.linalg.norm(b.velocity, axis=1), initial=0.0))
        g = float(np.linalg.norm(self.gravity))
        if g > 0 and len(b):
            h = float(np.ptp(b.position @ (self.gravity / g))) + 2 * float(b.radius.max())
            speed = max(speed, math.sqrt(2 * g * h))
        speed = max(speed, 1e-3)
        rayleigh = None
        tc, pair = None, ""
        present = sorted(set(int(m) for m in b.material))
        wall_mats = sorted({self._material_index(x.material, "") for x in self.boundaries})
        for ia in present:
            rmin_a = float(er[self.elements.material == ia].min())
            mmin_a = float(b.mass[b.material == ia].min())
            for ib in sorted(set(present) | set(wall_mats)):
                law = self._contacts.get((ia, ib))
                if law is None:
                    continue
                ma, mb = self.materials[ia], self.materials[ib]
                if ib in present:
                    rmin_b = float(er[self.elements.material == ib].min())
                    mmin_b = float(b.mass[b.material == ib].min())
                    meff = mmin_a * mmin_b / (mmin_a + mmin_b)
                    reff = rmin_a * rmin_b / (rmin_a + rmin_b)
                    t = law.contact_time(ma, mb, meff, reff, speed)
                    if tc is None or t < tc:
                        tc, pair = t, f"{ma.name}-{mb.name}"
                if ib in wall_mats:
                    t = law.contact_time(ma, mb, mmin_a, rmin_a, speed)
                    if tc is None or t < tc:
                        tc, pair = t, f"{ma.name}-wall {mb.name}"
                if law.needs_elastic_constants:
                    r = ma.rayleigh_time_step(rmin_a)
                    if r is not None and (rayleigh is None or r < rayleigh):
                        rayleigh = r
        return TimeStepReport(self.dt, rayleigh, tc, speed, pair,
                              self.integrator.min_steps_per_contact)

    def _smallest_pair(self, ia: int, ib: int) -> tuple[float, float]:
        """(m*, R*) of the smallest bodies of materials ia and ib (a wall material alone
        counts as an infinitely large, heavy body)."""
        b, e = self.bodies, self.elements

        def small(k: int) -> tuple[float, float]:
            sel = b.material == k
            if not np.any(sel):
                return math.inf, math.inf
            return float(b.mass[sel].min()), float(e.radius[e.material == k].min())

        (ma, ra), (mb, rb) = small(ia), small(ib)
        meff = ma if math.isinf(mb) else mb if math.isinf(ma) else ma * mb / (ma + mb)
        reff = ra if math.isinf(rb) else rb if math.isinf(ra) else ra * rb / (ra + rb)
        return meff, reff

    def _validate_scene(self) -> None:
        problems: list[str] = []
        b = self.bodies
        if len(b) == 0:
            problems.append("the scene has no particles (sim.add_particles)")
        for name in ("position", "velocity", "angular_velocity", "orientation"):
            arr = getattr(b, name)
            bad = ~np.all(np.isfinite(arr), axis=1)
            if np.any(bad):
                problems.append(f"{name} is NaN or inf for particle id(s) "
                                f"{_few(b.id[bad])}")
        # every material pair that can meet needs a contact law
        present = sorted(set(int(m) for m in b.material))
        missing = []
        for i, ia in enumerate(present):
            for ib in present[i:]:
                if (ia, ib) not in self._contacts:
                    missing.append(f"{self.materials[ia].name}-{self.materials[ib].name}")
            for bd in self.boundaries:
                ib = self._material_index(bd.material, "")
                if (ia, ib) not in self._contacts:
                    pair = f"{self.materials[ia].name}-{bd.material.name} ({bd.name})"
                    if pair not in missing:
                        missing.append(pair)
        if missing:
            problems.append("no contact law for material pair(s) " + ", ".join(missing)
                            + "; set them with sim.contact(a, b, model=..., ...)")
        # particles outside a boundary
        if len(b):
            for k, bd in enumerate(self.boundaries):
                out = bd.outside(b.position, b.radius)
                if np.any(out):
                    problems.append(f"{int(out.sum())} particle(s) lie outside boundary {k} "
                                    f"({bd.name}): id(s) {_few(b.id[out])}")
        if problems:
            raise SceneError("scene check before the first step:\n  " + "\n  ".join(problems))

    def _check_initial_overlaps(self) -> None:
        """Refuse overlaps beyond ``overlap_tolerance`` (of the smaller radius) between
        particles and between particles and boundaries, all listed in one error."""
        e, b, tol = self.elements, self.bodies, self.overlap_tolerance
        problems = []
        pairs = self.contacts.count
        if pairs:
            c = self.contacts
            ratio = self._module.pair_overlaps(e.position, e.radius, c.start, c.key,
                                               self.period)
            k = int(np.argmax(ratio))
            if ratio[k] > tol:
                i = int(np.searchsorted(c.start, k, side="right") - 1)
                j = int(c.key[k])
                problems.append(
                    f"{int(np.sum(ratio > tol))} particle pair(s) overlap more than "
                    f"overlap_tolerance={tol:g} of the smaller radius; worst: particles "
                    f"{b.id[e.owner[i]]} and {b.id[e.owner[j]]} overlap by "
                    f"{ratio[k]:.3g} of the radius")
        wc, w = self.wall_contacts, self.walls
        if wc.count:
            i = np.repeat(np.arange(len(e)), np.diff(wc.start))
            p = wc.key[:wc.count]
            ratio = self._module.entry_overlaps(e.position, e.radius, wc.start, wc.key,
                                                w.kind, w.par, w.owner, w.frame)
            k = int(np.argmax(ratio))
            if ratio[k] > tol:
                bd = self.boundaries[w.owner[p[k]]]
                problems.append(
                    f"{int(np.sum(ratio > tol))} particle(s) overlap a boundary more than "
                    f"overlap_tolerance={tol:g} of the radius; worst: particle "
                    f"{b.id[e.owner[i[k]]]} overlaps boundary {int(w.owner[p[k]])} ({bd.name}) "
                    f"by {ratio[k]:.3g} of its radius")
        if problems:
            raise SceneError("initial overlap: " + "; ".join(problems))

    def _prepare(self) -> None:
        """Validate the scene, pack the tables, pick and compile the step kernels."""
        self._validate_scene()
        report = self.time_step_report()
        if self._auto_dt and not self.dt > 0:
            self.dt = report.auto()
            report.dt = self.dt
        refuse, warn = report.problems()
        if self.dt_check == "refuse" and refuse:
            raise ParameterError("Simulation(): time step too large:\n  " + "\n  ".join(refuse)
                                 + "\n  (pass dt_check='warn' to run anyway)")
        if self.dt_check != "off":
            for w in (refuse + warn):
                warnings.warn(w, stacklevel=3)
        # material-pair tables: one law per distinct composition (dpm.impact.parts); history
        # floats per contact: the widest the laws use
        laws, self._pair_model, self._pair_params, width = pack_tables(
            self._contacts, self.materials,
            lambda ia, ib: PairContext(report.impact_speed, *self._smallest_pair(ia, ib)))
        self.contacts.set_history_width(width)
        self.wall_contacts.set_history_width(width)
        n_el = len(self.elements)
        if self.skin is None:
            self.skin = 0.4 * float(self.elements.radius.min())
        # boundaries: pipe joints, primitives, frames, search grids
        self._join_pipe_ends()
        self.walls = BoundaryTable(self.boundaries, lambda m: self._material_index(m, ""),
                                   float(self.elements.radius.max()) + self.skin)
        self._moving = any(bd.motion is not None for bd in self.boundaries)
        e, b = self.elements, self.bodies
        # every body one sphere at its centre: the element positions are the body positions
        self._spheres_only = bool(len(e) == len(b) and np.all(e.offset == 0.0)
                                  and np.array_equal(e.owner, np.arange(len(b))))
        if self._spheres_only:
            _share_sphere_arrays(b, e)
        self._plan_args = (laws, self.integrator.kernel_module,
                           sorted(set(self.walls.kind.tolist())),
                           bool(np.any(self.period[3:] > 0)))
        self._module = None
        self._sync_form()
        self._check_period()
        self._set_frames()
        if len(self.contacts.start) != n_el + 1:
            self.contacts.reset(n_el, 4 * n_el)  # grows on demand
            self.wall_contacts.reset(n_el, n_el // 4 + 16)
        self._e_worst = np.zeros(n_el)
        self._vf = np.zeros((len(b), 3))  # velocities the forces see (set by the integrator)
        self._wf = np.zeros((len(b), 3))
        self._aux = np.zeros((len(b), self.integrator.aux_columns))
        self._e_count = np.zeros(n_el, np.int32)
        if not self._spheres_only:
            self._module.update_element_positions(b.position, b.orientation, b.element_start,
                                                  e.offset, e.position)
        if np.any(self.period[3:] > 0):
            self._wrap_periodic()
        self._rebuild()
        self._check_initial_overlaps()
        self._prepared = True

    def _rebuild(self) -> None:
        e, c, wc, _w = self.elements, self.contacts, self.wall_contacts, self.walls
        d = self._diag
        while True:
            d[0] = STATUS_OK
            self._module.rebuild(self.skin, e.owner, e.radius, e.position, e.reference,
                                 c.start, c.key, c.history, c.active, c.t_start, c.t_pair,
                                 wc.start, wc.key, wc.history, wc.active, self._bnd(), d)
            if d[0] == STATUS_OVERFLOW:
                c.grow(int(d[3]))
            elif d[0] == STATUS_WALL_OVERFLOW:
                wc.grow(int(d[3]))
            else:
                break
        self.rebuild_count += int(d[2])
        d[2] = 0
        c.force[:c.count] = 0.0  # rows of the new lists: the contact pass fills touching ones
        wc.force[:wc.count] = 0.0

    def _args(self) -> tuple:
        """Arguments of ``run_steps``/``finish_step`` after ``dt`` (see kernels/step.py)."""
        b, e, c, wc, _w = self.bodies, self.elements, self.contacts, self.wall_contacts, self.walls
        return (self.gravity, self.skin, self.max_overlap, not self._spheres_only,
                self._fused(), self._spheres_only and not self.sphere_orientation,
                b.position, b.velocity, b.orientation, b.angular_velocity, b.force, b.torque,
                b.mass, b.invmass, b.invinertia, self._vf, self._wf, self._aux, b.element_start,
                e.owner,
                e.offset, e.radius,
                e.material, e.position, e.reference, c.start, c.key, c.history, c.active,
                c.force, c.t_start, c.t_pair, wc.start, wc.key, wc.history, wc.active,
                wc.force, wc.tag, self._bnd(),
                self._pair_model, self._pair_params, self._e_worst, self._e_count, self._diag)

    def _sync_form(self) -> None:
        """Load the step module of the force pass the scene needs: the fused pass when
        every body is a single sphere, else the two-pass sum (``FUSED``, a constant of the
        generated module, so that a scene compiles one form only)."""
        want = self._spheres_only and not self._two_pass
        if self._module is None or self._module.FUSED != want:
            self._module = _plan.step_module(*self._plan_args, fused=want)

    def _fused(self) -> int:
        """The number of chunks (one per thread) if the step sums forces as it computes
        them (kernels/step.py ``fused_pass``); 0 for the two-pass form. The sums are bit
        for bit the same; the fused pass leaves the rows of most pairs stale, so those are
        zeroed when the two-pass form takes over again."""
        fused = numba.get_num_threads() if self._module.FUSED else 0
        # rows: the two-pass sum, and the fused pass's pairs across chunks
        self.contacts.use_rows(fused != 1)
        if not fused and self._rows_stale:
            self.contacts.force[:] = 0.0
        self._rows_stale = bool(fused)
        return fused

    def _join_pipe_ends(self) -> None:
        """Mark open ends of tubes and bends that meet another piece's open end (same
        centre, opposite outward direction, same radius, same motion object) as joined."""
        ends = []
        for bd in self.boundaries:
            if hasattr(bd, "pipe_ends"):
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

    def _bnd(self) -> tuple:
        """The boundary arrays the kernels take as one tuple (see kernels/step.py)."""
        w = self.walls
        return (w.kind, w.par, w.owner, w.material, w.ids, w.frame, w.frame_ref, w.extent,
                w.load, w.grid_int, w.grid_flt, w.cell_start, w.cell_items, w.prim_cells,
                self.period)

    def _set_frames(self) -> None:
        """Boundary frames at the current time."""
        for k, bd in enumerate(self.boundaries):
            self.walls.frame[k] = frames(bd.motion, np.array([self.time]))[0]
            bd._time = self.time

    def _frame_table(self, n: int, step: int) -> np.ndarray:
        """Frames of moving boundaries at the ends of the n steps after ``step`` (empty if
        none moves)."""
        nb = len(self.boundaries)
        if not self._moving:
            return np.zeros((0, nb, 18))
        t = (step + 1 + np.arange(n)) * self.dt
        table = np.empty((n, nb, 18))
        for k, bd in enumerate(self.boundaries):
            table[:, k] = frames(bd.motion, t)
        return table

    def _prime_forces(self) -> None:
        """Forces of the current state without advancing contact history (dt = 0)."""
        b, e, c, wc, _w = self.bodies, self.elements, self.contacts, self.wall_contacts, self.walls
        self._vf[:] = b.velocity
        self._wf[:] = b.angular_velocity
        self._module.compute_forces(
            0.0, False, self._fused(), self.gravity, b.position, b.velocity, b.orientation,
            b.angular_velocity,
            b.force, b.torque, b.mass, b.invmass, b.invinertia, self._vf, self._wf, self._aux,
            b.element_start, e.owner,
            e.radius, e.material, e.position,
            c.start, c.key, c.history, c.active, c.force, c.t_start, c.t_pair, wc.start,
            wc.key, wc.history, wc.active, wc.force, wc.tag, self._bnd(), self._pair_model,
            self._pair_params, self._e_worst, self._e_count, self._diag)
        self._forces_valid = True

    # ----------------------------------------------------------------- running
    def run(self, steps: int | None = None, until: float | None = None,
            progress: bool | None = None) -> None:
        """Advance ``steps`` steps, or until simulated time ``until`` [s].

        Shows a progress bar (simulated time, steps/s, ETA) when ``progress`` is True, or
        when None and standard error is a terminal. Raises :class:`UnstableRunError` with a
        diagnosis if the run goes unstable; frames written so far stay readable.
        """
        if (steps is None) == (until is None):
            raise ParameterError("sim.run(): give exactly one of steps or until")
        if steps is not None:
            validate("sim.run()", {"steps": Parameter(low=0)}, {"steps": steps})
        else:
            validate("sim.run()", {"until": Parameter(low=self.time, unit="s")},
                     {"until": until})
        if not self._prepared:
            if self.inlets and self.step_count == 0 and not self._forces_valid:
                self._flow_event()  # an inlet may fill an empty scene
            self._prepare()
        if steps is not None:
            nsteps = int(steps)
        else:
            nsteps = max(0, math.ceil((until - self.time) / self.dt - 1e-9))
        threads_before = numba.get_num_threads()
        if self.threads is not None:
            numba.set_num_threads(self.threads)
        elif len(self.elements) < SMALL_SCENE:
            numba.set_num_threads(1)
        else:
            numba.set_num_threads(_default_threads())
        try:
            self._run(nsteps, progress)
        finally:
            numba.set_num_threads(threads_before)

    def _run(self, nsteps: int, progress: bool | None) -> None:
        self._sync_form()
        if not self._forces_valid:
            self._prime_forces()
            self._update_boundary_loads()
            self.integrator.start(self)
        from .progress import Progress

        hooks = self._registry.manager.hook
        per_step_hooks = bool(hooks.dpm_before_step.get_hookimpls()
                              or hooks.dpm_after_step.get_hookimpls())
        bar = Progress(nsteps, self.dt, self.time, enabled=progress)
        if self._output_path is not None and self._writer is None:
            from .io.hdf5 import Writer

            if self._output_every_s is not None:
                self._output_every = max(1, round(self._output_every_s / self.dt))
            self._writer = Writer(self._output_path, self)
            self.last_output = self._writer
            self._write_frame()
        flows = self.inlets + self.outlets
        flow_every = (max(1, round(min(f.every for f in flows) / self.dt)) if flows else 0)
        done = 0
        chunk = 10
        try:
            while done < nsteps:
                n = min(nsteps - done, chunk)
                if per_step_hooks:
                    n = 1
                if self._writer is not None:
                    n = min(n, self._output_every - self.step_count % self._output_every)
                if flow_every:
                    n = min(n, flow_every - self.step_count % flow_every)
                if per_step_hooks:
                    hooks.dpm_before_step(sim=self)
                t0 = _time.perf_counter()
                ran = self._advance(n)
                elapsed = _time.perf_counter() - t0
                done += ran
                if per_step_hooks:
                    hooks.dpm_after_step(sim=self)
                if flow_every and self.step_count % flow_every == 0:
                    self._flow_event()
                if self._writer is not None and self.step_count % self._output_every == 0:
                    self._write_frame()
                bar.update(ran, self.time)
                # aim at ~0.1 s of work per call (Python runs only at these events), and
                # at least 100x the checks after each call: at 1e6 spheres a step takes
                # ~60 ms and the checks ~4 ms, which at one or two steps per call had cost
                # a tenth of the run
                if elapsed > 0:
                    aim = max(0.1, 100.0 * self._check_cost)
                    chunk = int(min(max(chunk * min(aim / elapsed, 4.0), 1), 100000))
        finally:
            bar.close()
            if self._writer is not None:
                self._writer.flush()

    def _advance(self, n: int) -> int:
        """Run ``n`` steps in as few kernel calls as possible; diagnose a failure."""
        d = self._diag
        total = 0
        while total < n:
            if self.integrator.implicit:
                d[0] = STATUS_OK
                d[1] = self.integrator.advance(self, n - total)
            else:
                m = n - total
                if self._moving:
                    m = min(m, MOVING_CHUNK)
                table = self._frame_table(m, self.step_count + total)
                self._module.run_steps(m, self.dt, *self._args(), table)
            ran = int(d[1])
            if d[0] in (STATUS_OVERFLOW, STATUS_WALL_OVERFLOW):
                # stopped after begin_step: grow, then finish that step
                while d[0] in (STATUS_OVERFLOW, STATUS_WALL_OVERFLOW):
                    (self.contacts if d[0] == STATUS_OVERFLOW else self.wall_contacts).grow(
                        int(d[3]))
                    d[0] = STATUS_OK
                    self._module.finish_step(self.dt, *self._args())
                if d[0] in (STATUS_OK, STATUS_OVERLAP):
                    ran += 1
            total += ran
            if d[0] != STATUS_OK:
                break
        self.step_count += total
        self.time = self.step_count * self.dt
        if np.any(self.period[3:] > 0):
            self._wrap_periodic()
        self.rebuild_count += int(d[2])
        d[2] = 0
        self._update_boundary_loads()
        if d[0] == STATUS_NAN:
            self._fail("a position became NaN")
        if d[0] == STATUS_OVERLAP:
            self._fail(f"an overlap reached {d[4]:.3g} of the radius (max_overlap="
                       f"{self.max_overlap:g}){self._where(int(d[5]))}")
        self._check_speeds()
        return total

    def _where(self, el: int) -> str:
        """Which body element ``el`` belongs to, where it is and what it touches."""
        e, b = self.elements, self.bodies
        if not 0 <= el < len(e):
            return ""
        k = int(e.owner[el])
        touching = []
        wc, c = self.wall_contacts, self.contacts
        for q in range(int(wc.start[el]), int(wc.start[el + 1])):
            if wc.active[q]:
                bi = int(self.walls.owner[wc.key[q]])
                touching.append(f"boundary {bi} ({self.boundaries[bi].name})")
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

    def _check_speeds(self) -> None:
        b = self.bodies
        if len(b) == 0:
            return
        # the fastest body, in blocks (no temporary of the population's size: at 1e6
        # spheres this check had set the run's peak memory); the columns one by one
        # (einsum over rows of 3 took 6.3 ms per 1e6 bodies, this 3.8 ms)
        t0 = _time.perf_counter()
        k, v2 = 0, -1.0
        for first in range(0, len(b), SPEED_BLOCK):
            vb = b.velocity[first:first + SPEED_BLOCK]
            sq = vb[:, 0] * vb[:, 0]
            sq += vb[:, 1] * vb[:, 1]
            sq += vb[:, 2] * vb[:, 2]
            j = int(np.argmax(sq))  # (the first NaN, if any)
            if not sq[j] <= v2:
                k, v2 = first + j, float(sq[j])
                if not math.isfinite(v2):
                    self._fail("a velocity became NaN or inf")
        speed = math.sqrt(v2)
        if speed * self.dt > 0.5 * b.radius[k]:
            self._fail(f"particle {b.id[k]} moves {speed * self.dt:.3g} m per step, more "
                       f"than half its radius {b.radius[k]:.3g} m (speed {speed:.3g} m/s): "
                       "contacts would be missed (tunnelling) or start at unresolved "
                       f"overlaps; dt must stay below {0.5 * b.radius[k] / speed:.3g} s at this "
                       "speed")
        self._check_cost = _time.perf_counter() - t0

    def _fail(self, what: str) -> None:
        rep = self.time_step_report() if np.all(np.isfinite(self.bodies.velocity)) else None
        hint = ""
        if rep is not None and rep.contact_time is not None:
            hint = (f"; shortest contact {rep.contact_time:.3g} s = "
                    f"{rep.steps_per_contact:.3g} steps")
        if rep is not None and rep.rayleigh is not None:
            hint += f"; Rayleigh step {rep.rayleigh:.3g} s"
        written = ""
        w = self._writer
        if w is not None:
            w.flush()
            written = f"; {w.frames} frame(s) written to {w.path} stay readable"
        self.close()
        raise UnstableRunError(
            f"unstable run at step {self.step_count} (t = {self.time:.6g} s): {what}. "
            f"dt = {self.dt:g} s{hint}. Reduce dt, raise the damping or check the "
            f"stiffness{written}")

    def _update_boundary_loads(self) -> None:
        w = self.walls
        for k, bd in enumerate(self.boundaries):
            if w is None:
                bd.force = np.zeros(3)
                bd.torque = np.zeros(3)
                continue
            f = w.load[k, :3].copy()
            # torque about the frame origin o -> about the torque point c
            o = w.frame[k, :3]
            bd.force = f
            bd.torque = w.load[k, 3:6] + np.cross(o - bd.torque_point, f)
            bd.velocity = w.frame[k, 12:15].copy()
            bd.angular_velocity = w.frame[k, 15:18].copy()
            bd._time = self.time

    def _write_frame(self) -> None:
        self._writer.write(self)
        self._registry.manager.hook.dpm_on_output(sim=self, frame=self._writer.frames - 1,
                                                  path=self._writer.path)

    # ----------------------------------------------------------------- measures
    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy [J] (principal frame)."""
        b = self.bodies
        trans = 0.5 * np.sum(b.mass * np.einsum("ij,ij->i", b.velocity, b.velocity))
        w_body = _to_body(b.orientation, b.angular_velocity)
        rot = 0.5 * np.sum(b.inertia * w_body**2)
        return float(trans + rot)

    def momentum(self) -> np.ndarray:
        """Total linear momentum [kg m/s]."""
        return (self.bodies.mass[:, None] * self.bodies.velocity).sum(axis=0)

    def angular_momentum(self) -> np.ndarray:
        """Total angular momentum about the origin [kg m2/s]: sum m x cross v + R I R^T w."""
        b = self.bodies
        spin_body = b.inertia * _to_body(b.orientation, b.angular_velocity)
        spin = _to_body(b.orientation * np.array([1.0, -1.0, -1.0, -1.0]), spin_body)
        orbital = np.cross(b.position, b.mass[:, None] * b.velocity)
        return (orbital + spin).sum(axis=0)


def _default_threads() -> int:
    value = os.environ.get("DPM_THREADS", "1")
    if value == "all":
        return numba.config.NUMBA_NUM_THREADS
    try:
        n = int(value)
    except ValueError:
        raise ParameterError(f"DPM_THREADS={value!r} is not an integer or 'all'") from None
    if not 1 <= n <= numba.config.NUMBA_NUM_THREADS:
        raise ParameterError(f"DPM_THREADS={n} is outside [1, "
                             f"{numba.config.NUMBA_NUM_THREADS}] (NUMBA_NUM_THREADS)")
    return n


def _quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Hamilton product a (x) b of (N, 4) quaternions (w, x, y, z)."""
    a0, a1, a2, a3 = np.moveaxis(a, -1, 0)
    b0, b1, b2, b3 = np.moveaxis(np.broadcast_to(b, a.shape), -1, 0)
    return np.stack([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                     a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
                     a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0], axis=-1)


def _to_body(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate world vectors v into the body frames of quaternions q (R(q)^T v)."""
    w, x, y, z = q.T
    qv = np.stack([-x, -y, -z], axis=1)  # conjugate
    t = 2.0 * np.cross(qv, v)
    return v + w[:, None] * t + np.cross(qv, t)


def _filled(n: int, value, dtype) -> np.ndarray:
    """np.full(n, value), by np.zeros when value is 0: its pages then stay unmapped until
    written, so a field that stays 0 (the material of a one-material scene, the birth time
    of bodies placed at t = 0) costs no resident memory."""
    return np.zeros(n, dtype) if value == 0 else np.full(n, value, dtype)


def _share_sphere_arrays(b: Bodies, e: Elements) -> None:
    """Every body a single sphere at its centre: its element's position, and its radius
    and material where they agree (they do for built-in spheres), are the body's own
    arrays, not copies (16 B per sphere less besides the position)."""
    e.position = b.position
    if np.array_equal(e.radius, b.radius):
        e.radius = b.radius
    if np.array_equal(e.material, b.material):
        e.material = b.material


def _rows(call: str, name: str, value: Any, width: int, n: int | None = None) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(f"{call}: {name} is not numeric") from None
    if arr.ndim == 1 and arr.size == width and n in (None, 1):
        arr = arr[None]
    if arr.ndim != 2 or arr.shape[1] != width or (n is not None and len(arr) != n):
        want = f"({n if n is not None else 'N'}, {width})"
        raise ParameterError(f"{call}: {name} has shape {arr.shape}; allowed: {want}")
    if not np.all(np.isfinite(arr)):
        row = int(np.argmax(~np.all(np.isfinite(arr), axis=1)))
        raise ParameterError(f"{call}: {name} contains NaN or inf (row {row})")
    return np.ascontiguousarray(arr)


def _few(ids: np.ndarray, k: int = 5) -> str:
    s = ", ".join(str(int(i)) for i in ids[:k])
    return s + (f", ... ({len(ids)} in all)" if len(ids) > k else "")
