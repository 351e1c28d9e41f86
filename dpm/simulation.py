"""The Simulation: the conductor. It owns the scene description, the state, one backend
and the event schedule; the steps themselves run in the backend (:mod:`dpm.backends`)."""

from __future__ import annotations

import math
import time as _time
import warnings
from collections.abc import Sequence
from typing import Any

import numba
import numpy as np

from . import diagnosis, population, scene_check
from . import measures as _measures
from . import plan as _plan
from .backends.base import (
    STATUS_INTEGRATOR,
    STATUS_NAN,
    STATUS_OK,
    STATUS_OVERLAP,
    Backend,
    StepResult,
)
from .backends.cpu import SMALL_SCENE, default_threads  # noqa: F401  (public names)
from .boundaries.base import Boundary
from .boundaries.joints import join_pipe_ends
from .errors import ParameterError
from .flow import Inlet, Outlet
from .impact.base import ImpactModel, PairContext
from .impact.parts import pack_tables
from .material import Material
from .measures import to_body as _to_body  # noqa: F401  (used by tests and scripts)
from .motion import frames
from .parameters import Parameter, validate
from .plugins import registry
from .regions import Region
from .shapes.base import Shape
from .state import Bodies, BoundaryTable, Contacts, Elements, WallContacts
from .timestep import TimeStepReport, scene_report, smallest_pair

DT_CHECKS = ("refuse", "warn", "off")
#: most steps per kernel call while boundaries move (frames are tabulated per call)
MOVING_CHUNK = 2000


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
    device : str or Backend
        Where the steps run: a registered backend name (``"cpu"``, the default; ``dpm
        plugins`` lists them) or a backend instance (e.g.
        ``dpm.backends.CpuBackend(force_pass="two_pass")``). The script is the same for
        every backend (:mod:`dpm.backends.base`).

    The order of a step and of the events around it is given in :meth:`run`.

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
                             kind="int", doc="number of threads"),
        "sphere_orientation": Parameter(default=True, kind="bool",
                                        doc="track the orientation of single spheres"),
    }

    def __init__(self, dt: float | str, gravity: Sequence[float] = (0.0, 0.0, 0.0),
                 integrator: str = "velocity_verlet", skin: float | None = None,
                 dt_check: str = "refuse", max_overlap: float = 0.5,
                 overlap_tolerance: float = 0.01, threads: int | None = None,
                 sphere_orientation: bool = True, device: str | Backend = "cpu") -> None:
        self._auto_dt = isinstance(dt, str) and dt == "auto"
        v = validate("Simulation()", self.parameters, dict(
            dt=1.0 if self._auto_dt else dt, gravity=gravity, integrator=integrator,
            skin=skin, dt_check=dt_check,
            max_overlap=max_overlap, overlap_tolerance=overlap_tolerance, threads=threads,
            sphere_orientation=sphere_orientation))
        #: track the orientation of single-sphere bodies (see the class docstring)
        self.sphere_orientation = bool(v["sphere_orientation"])
        if v["dt_check"] not in DT_CHECKS:
            raise ParameterError(f"Simulation(): dt_check={dt_check!r}; allowed: "
                                 f"{', '.join(DT_CHECKS)}")
        self._registry = registry()
        self.integrator = self._registry.lookup("integrator", integrator,
                                                "Simulation()")()
        if isinstance(device, str):
            cls = self._registry.lookup("backend", device, "Simulation()")
            device = cls(threads=None if threads is None else int(threads))
        elif not isinstance(device, Backend):
            raise ParameterError(f"Simulation(): device={device!r} is neither a registered "
                                 "backend name nor a backend instance")
        elif threads is not None:
            device.threads = int(threads)
        #: the backend the steps run on (:mod:`dpm.backends`)
        self.backend: Backend = device
        self.dt = float("nan") if self._auto_dt else float(v["dt"])
        self.gravity = np.asarray(v["gravity"], float)
        self.skin = v["skin"]
        self.dt_check = v["dt_check"]
        self.max_overlap = float(v["max_overlap"])
        self.overlap_tolerance = float(v["overlap_tolerance"])
        self.materials: list[Material] = []
        #: registered shape names; ``bodies.shape`` indexes this list
        self.shape_names: list[str] = []
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
        #: what the kernels need of this scene (:class:`dpm.plan.ScenePlan`), made when
        #: the run starts
        self.plan: _plan.ScenePlan | None = None
        self.time = 0.0
        self.step_count = 0
        self.rebuild_count = 0
        self._next_id = 0
        self._prepared = False
        self._forces_valid = False
        self._check_cost = 0.0  # seconds of the checks after the last kernel call
        #: stop the run when a body moves more than half its radius in a step (contacts
        #: would be missed); False only to measure an integrator's own error past it
        self.speed_guard = True
        self._writer = None
        #: the Writer of the latest output file (open or closed): .path, .frames
        self.last_output = None
        self._output_path: str | None = None
        self._output_every: int | None = None
        self._output_every_s: float | None = None

    @property
    def threads(self) -> int | None:
        """Threads of the step kernels (None: the backend's default)."""
        return getattr(self.backend, "threads", None)

    @threads.setter
    def threads(self, value: int | None) -> None:
        self.backend.threads = None if value is None else int(value)

    # ----------------------------------------------------------------- scene building
    def material_index(self, m: Material) -> int:
        """Index of material ``m`` in :attr:`materials` (added if new)."""
        return self._material_index(m, "sim.material_index()")

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
        return population.append_bodies(self, sh, imat, material.density, pos, vel, ang, quat)

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
        return population.remove_bodies(self, ids)



    def permute(self, order: np.ndarray | Sequence[int]) -> None:
        """Reorder the bodies: row k becomes the body that was row ``order[k]``.

        Every container follows: elements (with their rebuild references, so no rebuild is
        needed), both contact lists with each contact's history and flag (a pair stored
        the other way round has its vector history negated), the integrator's state. Ids
        do not change. The physics is the same; only the order in which a body's forces
        are summed can change, by rounding (``tests/test_permute.py``)."""
        n = len(self.bodies)
        order = np.asarray(order)
        if (order.shape != (n,) or order.dtype.kind not in "iu"
                or not np.array_equal(np.sort(order), np.arange(n))):
            raise ParameterError(f"sim.permute(): order must be a permutation of the {n} "
                                 f"body rows (integers 0..{n - 1}, each once)")
        if self.integrator.implicit and self._prepared:
            raise ParameterError(f"sim.permute(): the {self.integrator.name} integrator keeps "
                                 "its own contact state; permute before the first run")
        g = self.bodies.ghosts
        if g and not np.array_equal(np.sort(order[n - g:]), np.arange(n - g, n)):
            raise ParameterError(f"sim.permute(): the last {g} rows are ghost bodies and "
                                 "must stay in the last rows")
        order = order.astype(np.int64)
        flips = None
        if self._prepared:  # which history floats of each pair change sign if it swaps
            c, e = self.contacts, self.elements
            rows = np.repeat(np.arange(len(c.start) - 1), np.diff(c.start))
            model = self.plan.pair_model[e.material[rows], e.material[c.key[:c.count]]]
            flips = self.plan.history_flips[model]
        new_body = np.empty(n, np.int64)
        new_body[order] = np.arange(n)
        elem_order = self.bodies.permute(order)
        new_elem = np.empty(len(elem_order), np.int64)
        new_elem[elem_order] = np.arange(len(elem_order))
        self.elements.permute(elem_order, new_body)
        if self._prepared:
            self.contacts.permute(new_elem, flips)
            self.wall_contacts.permute(new_elem)
            self.backend.permute_bodies(order)
            if self.plan.spheres_only:
                population.share_sphere_arrays(self)

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

    # ----------------------------------------------------------------- checks
    def time_step_report(self) -> TimeStepReport:
        """Rayleigh step and shortest contact duration of the current scene."""
        return scene_report(self)

    def _prepare(self) -> None:
        """Validate the scene, plan it (tables, history layout, boundary kinds, step
        module) and hand it to the backend."""
        scene_check.validate_scene(self)
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
        # material-pair tables: one law per distinct composition (dpm.impact.parts); the
        # history floats per contact: the widest the laws use
        laws, pair_model, pair_params, width = pack_tables(
            self._contacts, self.materials,
            lambda a, b: PairContext(report.impact_speed, *smallest_pair(self, a, b)))
        if self.skin is None:
            self.skin = 0.4 * float(self.elements.radius.min())
        # boundaries: pipe joints, primitives, frames, search grids
        join_pipe_ends(self.boundaries)
        self.walls = BoundaryTable(self.boundaries, lambda m: self._material_index(m, ""),
                                   float(self.elements.radius.max()) + self.skin)
        spheres = population.spheres_only(self)
        if spheres:  # every body one sphere at its centre: element positions are the bodies'
            population.share_sphere_arrays(self)
        periodic = bool(np.any(self.period[3:] > 0))
        self.plan = _plan.ScenePlan(
            laws, pair_model, pair_params, width, self.integrator.kernel_module,
            sorted(set(self.walls.kind.tolist())), periodic,
            any(bd.motion is not None for bd in self.boundaries), spheres)
        scene_check.check_period(self)
        self._set_frames()
        self.backend.attach(self)
        self.backend.rebuild()  # (it wraps periodic positions into the box first)
        scene_check.check_initial_overlaps(self)
        self._prepared = True

    def _set_frames(self) -> None:
        """Boundary frames at the current time."""
        for k, bd in enumerate(self.boundaries):
            self.walls.frame[k] = frames(bd.motion, np.array([self.time]))[0]
            bd.load_time = self.time

    def _frame_table(self, n: int, step: int) -> np.ndarray:
        """Frames of moving boundaries at the ends of the n steps after ``step`` (empty if
        none moves)."""
        nb = len(self.boundaries)
        if not self.plan.moving:
            return np.zeros((0, nb, 18))
        t = (step + 1 + np.arange(n)) * self.dt
        table = np.empty((n, nb, 18))
        for k, bd in enumerate(self.boundaries):
            table[:, k] = frames(bd.motion, t)
        return table

    # ----------------------------------------------------------------- running
    def run(self, steps: int | None = None, until: float | None = None,
            progress: bool | None = None) -> None:
        """Advance ``steps`` steps, or until simulated time ``until`` [s].

        Shows a progress bar (simulated time, steps/s, ETA) when ``progress`` is True, or
        when None and standard error is a terminal. Raises :class:`UnstableRunError` with a
        diagnosis if the run goes unstable; frames written so far stay readable.

        Before the first step (and after the scene changed): an inlet may fill an empty
        scene; the scene is checked (every problem in one error), planned and handed to
        the backend; forces of the start state are computed (dt = 0) and the integrator
        started; the output file is created with the start state as its first frame.

        Each step, in the backend (:mod:`dpm.backends.base`): integrator pre-force part,
        element positions, neighbour lists rebuilt when an element moved more than
        skin/2, gravity and contact forces, integrator post-force part.

        Between kernel calls, in this order: ``dpm_after_step`` hooks (when any hook runs
        per step, every call is one step, with ``dpm_before_step`` before it); boundary
        loads, the instability checks (NaN, overlap beyond
        ``max_overlap``, tunnelling speed); the flow event (outlets remove, then inlets
        insert) when its interval is due; an output frame (then ``dpm_on_output``) when
        due. Calls are as long as these events allow, aiming at ~0.1 s each.
        """
        if (steps is None) == (until is None):
            raise ParameterError("sim.run(): give exactly one of steps or until")
        if steps is not None:
            validate("sim.run()", {"steps": Parameter(low=0, kind="int")}, {"steps": steps})
        else:
            validate("sim.run()", {"until": Parameter(low=self.time, unit="s")},
                     {"until": until})
        if not self._prepared:
            if self.inlets and self.step_count == 0 and not self._forces_valid:
                population.flow_event(self)  # an inlet may fill an empty scene
            self._prepare()
        if steps is not None:
            nsteps = int(steps)
        else:
            nsteps = max(0, math.ceil((until - self.time) / self.dt - 1e-9))
        threads_before = numba.get_num_threads()
        numba.set_num_threads(self.backend.thread_count(len(self.elements)))
        try:
            self._run(nsteps, progress)
        finally:
            numba.set_num_threads(threads_before)


    def _run(self, nsteps: int, progress: bool | None) -> None:
        self.backend.sync_form()
        if not self._forces_valid:
            self.backend.prime()
            self._forces_valid = True
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
                    population.flow_event(self)
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
        """Run ``n`` steps in as few backend calls as possible; diagnose a failure."""
        total = 0
        res = StepResult(0)
        while total < n:
            if self.integrator.implicit:
                d = self.backend.diag
                d[0] = STATUS_OK
                d[1] = self.integrator.advance(self, n - total)
                res = StepResult(int(d[1]), int(d[0]), int(d[2]), float(d[4]), int(d[5]))
                d[2] = 0
            else:
                m = n - total
                if self.plan.moving:
                    m = min(m, MOVING_CHUNK)
                res = self.backend.advance(m, self.dt,
                                           self._frame_table(m, self.step_count + total))
            total += res.steps
            self.rebuild_count += res.rebuilds
            if res.status != STATUS_OK:
                break
        self.step_count += total
        self.time = self.step_count * self.dt
        self._update_boundary_loads()
        if res.status == STATUS_NAN:
            self._fail("a position became NaN")
        if res.status == STATUS_INTEGRATOR:
            self._fail(self.integrator.failure)
        if res.status == STATUS_OVERLAP:
            self._fail(f"an overlap reached {res.worst_overlap:.3g} of the radius "
                       f"(max_overlap={self.max_overlap:g})"
                       f"{diagnosis.locate(self, res.worst_element)}")
        if self.speed_guard:
            self._check_cost = diagnosis.check_speeds(self)
        return total

    def _fail(self, what: str) -> None:
        raise diagnosis.unstable(self, what)

    def _update_boundary_loads(self) -> None:
        w = self.walls
        loads = None if w is None else self.backend.boundary_loads()
        for k, bd in enumerate(self.boundaries):
            if w is None:
                bd.record_load(self.time, np.zeros(3), np.zeros(3), bd.velocity,
                               bd.angular_velocity)
                continue
            f = loads[k, :3].copy()
            # torque about the frame origin o -> about the torque point c
            o = w.frame[k, :3]
            bd.record_load(self.time, f, loads[k, 3:6] + np.cross(o - bd.torque_point, f),
                           w.frame[k, 12:15].copy(), w.frame[k, 15:18].copy())

    def _write_frame(self) -> None:
        self._writer.write(self)
        self._registry.manager.hook.dpm_on_output(sim=self, frame=self._writer.frames - 1,
                                                  path=self._writer.path)

    # ----------------------------------------------------------------- measures
    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy [J] (principal frame)."""
        return _measures.kinetic_energy(self.bodies)

    def momentum(self) -> np.ndarray:
        """Total linear momentum [kg m/s]."""
        return _measures.momentum(self.bodies)

    def angular_momentum(self) -> np.ndarray:
        """Total angular momentum about the origin [kg m2/s]: sum m x cross v + R I R^T w."""
        return _measures.angular_momentum(self.bodies)

    def contact_count(self) -> int:
        """Touching contacts (particle pairs and particle-boundary) of the last step."""
        return self.backend.contact_count()

    @property
    def _diag(self) -> np.ndarray:
        """The backend's kernel diagnostics (old name, read by scripts: [6] is
        :meth:`contact_count`)."""
        return self.backend.diag


def _rows(call: str, name: str, value: Any, width: int, n: int | None = None) -> np.ndarray:
    from .parameters import numeric_array

    arr = numeric_array(value)
    if arr is None:
        shown = repr(value)  # the start only: a huge array's would fill the screen
        shown = shown if len(shown) <= 80 else shown[:77] + "..."
        raise ParameterError(f"{call}: {name}={shown} must be numbers in rows of {width} "
                             "(no strings, booleans or None)")
    if name == "positions" and arr.ndim == 2:  # before the copy: at least one element each
        from ._memory import check_request

        check_request(f"{call}: positions:", len(arr), len(arr))
    if arr is value:  # a float array given: a copy, as for any other input
        arr = arr.copy()
    if arr.ndim == 1 and arr.size == width and n in (None, 1):
        arr = arr[None]
    if arr.ndim != 2 or arr.shape[1] != width or (n is not None and len(arr) != n):
        want = f"({n if n is not None else 'N'}, {width})"
        raise ParameterError(f"{call}: {name} has shape {arr.shape}; allowed: {want}")
    if not np.all(np.isfinite(arr)):
        row = int(np.argmax(~np.all(np.isfinite(arr), axis=1)))
        raise ParameterError(f"{call}: {name} contains NaN or inf (row {row})")
    return np.ascontiguousarray(arr)

