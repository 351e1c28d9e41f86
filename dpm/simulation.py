"""The Simulation: the conductor. It owns the scene description, the state, one backend
and the event schedule; the steps themselves run in the backend (:mod:`dpm.backends`)."""

from __future__ import annotations

import inspect
import math
import os
import sys
import time as _time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numba
import numpy as np

from . import diagnosis, guards, population, scene_check, switches
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
from .backends.cpu import threading_layer_advice
from .boundaries.base import Boundary
from .boundaries.joints import join_pipe_ends
from .declared import Declared
from .errors import OutputError, ParameterError
from .flow import Inlet, Outlet
from .guards import EnergyBook, Escaped, Guards
from .impact.base import ImpactModel, PairContext
from .impact.design_speed import design_speed_warnings, overlap_hint
from .impact.parts import contact_reach, pack_tables
from .material import Material
from .motion import frames
from .operations import Operations
from .parameters import Parameter, validate
from .plugins import call_hook, registry
from .regions import Region
from .shapes.base import Shape
from .state import Bodies, BoundaryTable, Contacts, Elements, WallContacts
from .timestep import TimeStepReport, scene_report, smallest_pair
from .warm import _quiet

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
        ``dpm.backends.cpu.SMALL_SCENE`` (4,000) elements always run on one thread unless
        ``threads`` is given (there starting parallel loops costs more than it gains).
        Results are identical for any number of threads.
    sphere_orientation : bool
        Track the orientation of single-sphere bodies (default True). No force depends on
        it; with False their quaternion is not updated (as LIGGGHTS' ``nve/sphere``) and
        stays as inserted, which spares about a tenth of a settled packing's step.
        Positions, velocities and angular velocities are the same bit for bit either way.
        Clustered bodies always rotate.
    device : str or Backend, optional
        Where the steps run: a registered backend name (``"cpu"``, ``"mpi"``; ``dpm
        plugins`` lists them) or a backend instance (e.g.
        ``dpm.backends.CpuBackend(force_pass="two_pass")``). Default: ``"mpi"`` when the
        process was started by ``mpiexec`` with more than one rank (the scene is cut into
        one sub-domain per rank, :mod:`dpm.parallel`), else ``"cpu"``; ``"cpu"`` under
        ``mpiexec`` runs a whole copy of the scene on each rank. The script is the same
        for every backend (:mod:`dpm.backends.base`).

    Notes
    -----
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

    def __init__(self, dt: float | str | None = None, gravity: Sequence[float] = (0.0, 0.0, 0.0),
                 integrator: str = "velocity_verlet", skin: float | None = None,
                 dt_check: str = "refuse", max_overlap: float = 0.5,
                 overlap_tolerance: float = 0.01, threads: int | None = None,
                 sphere_orientation: bool = True, device: str | Backend | None = None,
                 **unknown: Any) -> None:
        self._auto_dt = isinstance(dt, str) and dt == "auto"
        v = validate("Simulation()", self.parameters, dict(
            dt=1.0 if self._auto_dt else dt, gravity=gravity, integrator=integrator,
            skin=skin, dt_check=dt_check,
            max_overlap=max_overlap, overlap_tolerance=overlap_tolerance, threads=threads,
            sphere_orientation=sphere_orientation, **unknown))
        #: track the orientation of single-sphere bodies (see the class docstring)
        self.sphere_orientation = bool(v["sphere_orientation"])
        if v["dt_check"] not in DT_CHECKS:
            raise ParameterError(f"Simulation(): dt_check={dt_check!r}; allowed: "
                                 f"{', '.join(DT_CHECKS)}")
        self._registry = registry()
        self.integrator = self._registry.lookup("integrator", integrator,
                                                "Simulation()")()
        if device is None:  # "mpi" when started by mpiexec on several ranks, else "cpu"
            from .parallel import default_device

            device = default_device()
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
        # time is t0 + (step_count - step0) dt: (t0, step0) move when dt changes, so that
        # time stays the sum of the steps taken (and is step_count * dt, bit for bit, while
        # dt has never changed)
        self._t0 = 0.0
        self._step0 = 0
        self._dt = float("nan") if self._auto_dt else float(v["dt"])
        self._dt_checked = False
        self._gravity = np.asarray(v["gravity"], float)
        self._skin = v["skin"]
        self._dt_check = v["dt_check"]
        self._max_overlap = float(v["max_overlap"])
        self._overlap_tolerance = float(v["overlap_tolerance"])
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
        self.step_count = 0
        #: the material-pair tables of the laws, packed once and kept while neither the
        #: laws nor the materials change (a particle added after a run must not recalibrate
        #: the contacts of the others): (version, laws, pair_model, pair_params, width)
        self._tables: tuple | None = None
        self._contacts_version = 0
        #: elements checked for initial overlaps (those added later are checked against
        #: their neighbours only)
        self._checked_elements = 0
        #: what the run loop does between kernel calls, each with its trigger (output
        #: frames, flow events, boundary switches, checkpoints, the cell-order sort, the
        #: script's own callbacks): :mod:`dpm.operations`
        self.operations = Operations()
        #: forces by id of the bodies before the population changed (population.py)
        self._force_snapshot: dict | None = None
        #: bodies with ids below this have integrator state (started)
        self._integrated_ids = 0
        self.rebuild_count = 0
        self._next_id = 0
        self._prepared = False
        self._forces_valid = False
        self._check_cost = 0.0  # seconds of the checks after the last kernel call
        #: (seconds per step per body, the call length in steps) of the last run's last
        #: kernel call: the next run starts its calls from it instead of 10 steps
        self._call_rate: tuple[float, int] | None = None
        #: stop the run when a body moves more than half its radius in a step (contacts
        #: would be missed); False only to measure an integrator's own error past it
        self.speed_guard = True
        #: the run-time guards: energy, NaN/inf, escaping particles (:mod:`dpm.guards`)
        self.guards = Guards()
        #: the energy balance of the run (:class:`dpm.guards.EnergyBook`)
        self.energy = EnergyBook()
        #: particles the escape guard removed (:class:`dpm.guards.Escaped`)
        self.escaped = Escaped()
        self._scene_box: np.ndarray | None = None
        self._last_frame_step = -1
        self._writer = None
        #: the Writer of the latest output file (open or closed): .path, .frames
        self.last_output = None
        self._output_path: str | None = None

    # ----------------------------------------------------------------- settable state
    @property
    def time(self) -> float:
        """Simulated time [s]: the sum of the steps taken (read-only)."""
        if self.step_count == self._step0:
            return self._t0
        return self._t0 + (self.step_count - self._step0) * self._dt

    @time.setter
    def time(self, value: Any) -> None:
        raise ParameterError("sim.time is the sum of the steps taken and cannot be set; "
                             "run(until=...) advances it")

    @property
    def dt(self) -> float:
        """Time step [s]. May be changed between runs: the time-step check runs again
        before the next step (``dt_check``), ``time`` stays the sum of the steps taken,
        output and flow intervals given in seconds are kept in seconds, and the
        integrator's state is rescaled (:meth:`dpm.integrators.base.Integrator.dt_changed`)."""
        return self._dt

    @dt.setter
    def dt(self, value: Any) -> None:
        if isinstance(value, str) and value == "auto":
            if self.step_count:
                raise ParameterError("sim.dt='auto' is chosen before the first step only; "
                                     "give a number of seconds after a run")
            self._auto_dt = True
            self._dt = float("nan")
            self._prepared = False
            return
        validate("sim.dt", {"dt": Parameter(low=0.0, low_open=True, unit="s")}, {"dt": value})
        value = float(value)
        if not math.isfinite(value):
            raise ParameterError(f"sim.dt={value!r} must be a finite number of seconds > 0")
        if value == self._dt:
            return
        old = self._dt
        self._t0 = self.time
        self._step0 = self.step_count
        self._dt = value
        self._auto_dt = False
        self._dt_checked = False
        self.operations.dt_changed(self)  # (intervals in seconds stay in seconds)
        if self._forces_valid and math.isfinite(old):
            self.integrator.dt_changed(self, old)

    gravity = Declared("Gravitational acceleration [m/s2] (a 3-vector; may be changed "
                       "between runs).", convert=lambda v: np.asarray(v, float).copy())
    skin = Declared("Verlet skin [m] (None: 0.2 x the smallest element diameter, set at "
                    "the first run). Changing it rebuilds the neighbour lists before the "
                    "next step.", after="_replan")
    dt_check = Declared('What a too large time step does: "refuse", "warn" or "off".',
                        convert=str, after="_recheck_dt", choices=DT_CHECKS)
    max_overlap = Declared("Largest overlap / radius tolerated during a run before it "
                           "stops as unstable.")
    overlap_tolerance = Declared("Largest initial overlap / radius accepted for particles "
                                 "when they are added.")

    def _replan(self) -> None:
        self._prepared = False

    def _recheck_dt(self) -> None:
        self._dt_checked = False

    @property
    def rank(self) -> int:
        """This process's MPI rank (0 on one process): a script or hook that runs on
        every rank tells them apart by it."""
        return int(self.backend.rank)

    @property
    def ranks(self) -> int:
        """The number of MPI ranks running this scene (1 on one process)."""
        return int(self.backend.ranks)

    @property
    def threads(self) -> int | None:
        """Threads of the step kernels (None: the backend's default)."""
        return self.backend.threads

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
        self._contacts_version += 1
        self._prepared = False
        return law

    def add_boundary(self, kind: str | Boundary, material: Material | None = None,
                     **params: Any) -> Boundary:
        """Add a boundary of a registered kind (``plane``, ``box``, ...); return it.

        Parameters
        ----------
        kind : str or Boundary
            a registered boundary name: the built-in kinds below, or a plugin's (``dpm
            plugins`` lists them; ``help(dpm.registry().lookup("boundary", kind))`` shows
            one's parameters); or a boundary built already
            (``dpm.boundaries.Tube(steel, radius=0.05, length=1)``), added as it is (then
            no ``material`` or parameters here).
        material : Material
            the boundary's material (its contact laws with the particles' materials are
            set by :meth:`contact`).
        **params
            the kind's parameters as keywords, and ``motion`` (a :class:`dpm.Motion`,
            default None: at rest). An unknown or misspelt name, a missing required one or
            a value out of range raises :class:`~dpm.errors.ParameterError` naming the
            call, the parameter, its value and what is allowed.
        """
        if isinstance(kind, Boundary):
            b = kind
            call = f"sim.add_boundary({type(b).__name__}(...))"
            if params or (material is not None and material is not b.material):
                given = ", ".join(["material"] * (material is not None) + sorted(params))
                raise ParameterError(f"{call}: the boundary is built already (its material "
                                     f"and parameters are its own); given also: {given}")
            if any(b is other for other in self.boundaries):
                raise ParameterError(f"{call}: this boundary was added already (boundary "
                                     f"{next(k for k, o in enumerate(self.boundaries) if o is b)})")
            self._material_index(b.material, call)
        else:
            call = f"sim.add_boundary({kind!r})"
            if not isinstance(kind, str):
                raise ParameterError(f"{call}: kind={kind!r}; allowed: a registered "
                                     "boundary name or a Boundary object")
            cls = self._registry.lookup("boundary", kind, call)
            if material is None:
                raise ParameterError(f"{call}: material is required (a dpm.Material)")
            self._material_index(material, call)
            b = cls(material, call=call, **params)
        self.boundaries.append(b)
        self._scene_box = None
        self._prepared = False
        self._forces_valid = False
        self._force_snapshot = None
        return b

    def switch_off(self, boundary: Boundary | int, at: float | None = None) -> None:
        """Switch ``boundary`` off at time ``at`` [s] (None: now): it leaves the contact
        search, its contacts end, every other contact keeps its history; it stays in
        ``sim.boundaries`` with zero load (:mod:`dpm.switches`). Opens an orifice under a
        settled bed, as LIGGGHTS' ``unfix`` of a plug wall."""
        switches.schedule(self, boundary, False, at)

    def switch_on(self, boundary: Boundary | int, at: float | None = None) -> None:
        """Switch ``boundary`` back on at time ``at`` [s] (None: now); its contacts are
        found afresh (:mod:`dpm.switches`)."""
        switches.schedule(self, boundary, True, at)

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
        self._force_snapshot = None


    def add_inlet(self, region: Region, material: Material, *, rate: float | None = None,
                  mass_rate: float | None = None, shapes: Sequence[dict] | None = None,
                  shape: str = "sphere", velocity: Sequence[float] = (0.0, 0.0, 0.0),
                  start: float = 0.0, stop: float = math.inf, every: float = 1e-3,
                  seed: int = 0, random_orientation: bool = True, max_attempts: int = 30,
                  count: int | None = None, mass: float | None = None,
                  **shape_params: Any) -> Inlet:
        """Insert particles during the run; return the inlet (:class:`dpm.flow.Inlet`,
        whose docstring gives the insertion rules).

        Parameters
        ----------
        region : Region
            where bodies are placed (:class:`dpm.BoxRegion`, :class:`dpm.CylinderRegion`).
        material : Material
            their material.
        rate : float, optional
            bodies per second [1/s] (give ``rate`` or ``mass_rate``).
        mass_rate : float, optional
            mass per second [kg/s].
        shapes : list of dict, optional
            a mix: ``[{"shape": name, "fraction": f, **parameters}, ...]``; a parameter
            given as a pair ``(low, high)`` is drawn uniformly per body.
        shape : str
            without ``shapes``: the one shape inserted (default ``"sphere"``), its
            parameters given as further keywords (e.g. ``radius=(1e-3, 2e-3)``).
        velocity : 3-vector
            initial velocity [m/s] (default 0).
        start, stop : float
            the inlet's time window [s] (default 0 to inf: never stops).
        every : float
            interval between insertions [s] (default 1e-3).
        seed : int
            random seed (default 0): the insertion is reproducible.
        random_orientation : bool
            uniform random orientations (default True).
        max_attempts : int
            places tried per body at each event (default 30).
        count : int, optional
            bodies in all; then the inlet stops (with ``rate`` or ``mass_rate`` setting
            how fast; alone: all due at ``start``).
        mass : float, optional
            mass in all [kg]: bodies until their mass reaches it (as ``count``).
        **shape_params
            the shape's parameters when ``shapes`` is not given; a misspelt inlet or
            shape parameter raises :class:`~dpm.errors.ParameterError` naming it.
        """
        self._material_index(material, "sim.add_inlet()")
        inlet = Inlet(region, material, rate=rate, mass_rate=mass_rate, shapes=shapes,
                      shape=shape, velocity=velocity, start=start, stop=stop, every=every,
                      seed=seed, random_orientation=random_orientation,
                      max_attempts=max_attempts, count=count, mass=mass, **shape_params)
        self.inlets.append(inlet)
        self._scene_box = None
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
        are summed can change, by rounding (``tests/kernels/test_permute.py``)."""
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
               every_steps: int | None = None, overwrite: bool = False,
               fields: str | tuple[str, ...] = (), contacts: bool = False,
               solids: bool = False) -> None:
        """Write frames to HDF5 at ``path`` (+ XDMF beside it) every ``every`` seconds or
        ``every_steps`` steps. The file is created when the next run starts, with the state
        at that moment as its first frame.

        ``fields`` adds per-particle fields to each frame (a name or a tuple of names;
        ``"all"`` for every one): ``force`` and ``torque`` (the contact and body forces of
        the step, gravity included), ``contact_count`` (touching contacts of each body,
        other bodies and boundaries), ``rotation`` (the rotation matrix, 9 components, for
        ParaView's tensor glyphs). ``contacts=True`` writes the touching pairs of each
        frame with their forces, drawn as lines in ``run.contacts.xdmf`` (force chains).
        ``solids=True`` writes the solid shape of each clustered body (its ideal solid's
        triangle surface, stored once per shape, placed at the body's pose in each frame),
        drawn in ``run.solids.xdmf`` beside the element spheres of ``run.elements.xdmf``.
        The scene's description (and a TOML scene file's text) is stored in every file.
        Layout: docs/output-format.md.

        An existing file at ``path`` is kept: this raises :class:`ParameterError` unless
        ``overwrite=True``, which replaces it (and its XDMF sidecars) when the run starts.
        Calling ``output()`` again with the path of the file this simulation is writing
        keeps appending to it (with the new interval); another path closes it first. The
        path is checked here, before any compile: its directory is created if needed and
        must be writable, the path must not be a directory."""
        import os

        from .io.hdf5 import check_output_fields, check_output_path

        call = "sim.output()"
        if isinstance(path, bool) or not isinstance(path, str | os.PathLike):
            raise ParameterError(f"{call}: path={path!r}; allowed: a file name (str or "
                                 f"os.PathLike)")
        name = os.fspath(path)
        if not isinstance(name, str) or not name.strip():
            raise ParameterError(f"{call}: path={path!r}; allowed: a non-empty file name")
        if (every is None) == (every_steps is None):
            raise ParameterError(f"{call}: give exactly one of every (s) or every_steps")
        value = every if every is not None else every_steps
        label = "every" if every is not None else "every_steps"
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer
                                                     | np.floating):
            raise ParameterError(f"{call}: {label}={value!r} is not a number")
        if every is not None:
            validate(call, {"every": Parameter(low=0.0, low_open=True, unit="s")},
                     {"every": every})
        else:
            validate(call, {"every_steps": Parameter(low=1, kind="float")},
                     {"every_steps": every_steps})
            if not float(every_steps).is_integer():
                raise ParameterError(f"{call}: every_steps={every_steps!r}; allowed: an "
                                     f"integer >= 1")
        if not isinstance(overwrite, bool | np.bool_):
            raise ParameterError(f"{call}: overwrite={overwrite!r}; allowed: True or False")
        chosen = check_output_fields(fields, call)
        for label, flag in (("contacts", contacts), ("solids", solids)):
            if not isinstance(flag, bool | np.bool_):
                raise ParameterError(f"{call}: {label}={flag!r}; allowed: True or False")
        target = os.path.realpath(name)
        w = self._writer
        appending = (w is not None and not w.closed
                     and os.path.realpath(w.path) == target)
        layout = (getattr(self, "_output_fields", ()),
                  getattr(self, "_output_contacts", False),
                  getattr(self, "_output_solids", False))
        if appending and (chosen, bool(contacts), bool(solids)) != layout:
            raise ParameterError(f"{call}: {name!r} is being written with fields="
                                 f"{layout[0]!r}, contacts={layout[1]!r}, solids="
                                 f"{layout[2]!r}; its layout is fixed: call sim.close() "
                                 f"first or choose another path")
        if not appending:
            # (MPI: rank 0 creates the file, maybe before another rank gets here)
            check_output_path(name, bool(overwrite) or not self.backend.root)
            self.close()
            self._output_path = name
            self._output_overwrite = bool(overwrite)
        #: the optional per-particle fields and the contact output of the file
        self._output_fields = chosen
        self._output_contacts = bool(contacts)
        self._output_solids = bool(solids)
        self.operations.frames.set(every, every_steps)
        if appending:
            self.operations.frames.restart_from_here(self)

    def close(self) -> None:
        """Close the output file (and cancel an :meth:`output` whose file a run has not
        created yet); a later run writes a file only after a new :meth:`output` call."""
        if self._writer is not None:
            self._writer.close()
        self._writer = None
        self._output_path = None

    # ----------------------------------------------------------------- checks

    # ----------------------------------------------------------------- checks
    def time_step_report(self) -> TimeStepReport:
        """Rayleigh step and shortest contact duration of the current scene."""
        return scene_report(self)

    def _check_time_step(self) -> None:
        """The time-step check (``dt_check``) of the scene as it is now; ``dt='auto'``
        picks the step."""
        report = self.time_step_report()
        if self._auto_dt and not self._dt > 0:
            self._dt = report.auto()
            report.dt = self._dt
        refuse, warn = report.problems()
        if self.dt_check == "refuse" and refuse:
            raise ParameterError("Simulation(): time step too large:\n  " + "\n  ".join(refuse)
                                 + "\n  (pass dt_check='warn' to run anyway)")
        if self.dt_check != "off":
            # (a law's design speed against the scene's falls: once per checked step)
            speeds = [] if self._dt_checked else design_speed_warnings(self)
            for w in (refuse + warn + speeds):
                warnings.warn(w, stacklevel=4)
        self._dt_checked = True
        return report

    def _pair_tables(self, report: TimeStepReport) -> tuple:
        """The material-pair tables (:func:`dpm.impact.parts.pack_tables`): packed at the
        first run and kept while neither a law nor the materials change, so that bodies
        added later do not recalibrate the contacts of the others."""
        key = (self._contacts_version, len(self.materials))
        if self._tables is None or self._tables[0] != key:
            self._tables = (key, *pack_tables(
                self._contacts, self.materials,
                lambda a, b: PairContext(report.impact_speed, *smallest_pair(self, a, b))))
        return self._tables[1:]

    def _prepare(self) -> None:
        """Validate the scene, plan it (tables, history layout, boundary kinds, step
        module) and hand it to the backend. After a run (bodies added, a law or the skin
        changed) the contact lists keep every contact's history and only the bodies added
        since are checked for initial overlaps."""
        scene_check.validate_scene(self)
        report = self._check_time_step()
        # material-pair tables: one law per distinct composition (dpm.impact.parts); the
        # history floats per contact: the widest the laws use
        laws, pair_model, pair_params, width = self._pair_tables(report)
        if self._skin is None:
            self._skin = 0.4 * float(self.elements.radius.min())
        rmax = float(self.elements.radius.max())
        reach = contact_reach(self._contacts, self.materials, rmax)  # (JKR: |d_c|)
        if reach > 0.0 and self.integrator.implicit:
            raise ParameterError(f"Simulation(integrator={self.integrator.name!r}): a contact "
                                 "law acts at a separation (JKR), which the implicit "
                                 "integrators do not support; choose an explicit one")
        # boundaries: pipe joints, primitives, frames, search grids
        join_pipe_ends(self.boundaries)
        self.walls = BoundaryTable(self.boundaries, lambda m: self._material_index(m, ""),
                                   rmax + self._skin + reach)
        self.walls.load[:, 6] = [bd.work for bd in self.boundaries]  # (the sums go on)
        spheres = population.spheres_only(self)
        if spheres:  # every body one sphere at its centre: element positions are the bodies'
            population.share_sphere_arrays(self)
        periodic = bool(np.any(self.period[3:] > 0))
        self.plan = _plan.ScenePlan(
            laws, pair_model, pair_params, width, self.integrator.kernel_module,
            sorted(set(self.walls.kind.tolist())), periodic,
            any(bd.motion is not None for bd in self.boundaries), spheres, reach)
        scene_check.check_period(self)
        for k, bd in enumerate(self.boundaries):
            self.walls.set_enabled(k, bd.enabled)
        self._set_frames()
        self.backend.attach(self)
        self.backend.rebuild()  # (it wraps periodic positions into the box first)
        scene_check.check_initial_overlaps(self, first_element=self._checked_elements)
        self._checked_elements = len(self.elements)
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
        t = self._t0 + (step - self._step0 + 1 + np.arange(n)) * self._dt
        table = np.empty((n, nb, 18))
        for k, bd in enumerate(self.boundaries):
            table[:, k] = frames(bd.motion, t)
        return table

    # ----------------------------------------------------------------- running
    def run(self, steps: int | None = None, until: float | None = None,
            progress: bool | None = None, **unknown: Any) -> None:
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
        ``max_overlap``, tunnelling speed); then the operations due at this step
        (``sim.operations``, :mod:`dpm.operations`), in order: the cell-order sort, the
        flow event (outlets remove, then inlets insert), an output frame (then
        ``dpm_on_output``), the boundary switches (:meth:`switch_off`), a periodic
        checkpoint, the script's own callbacks (``sim.operations.add(dpm.Callback(f,
        every_steps=N))``). Calls end where an operation is due and are otherwise as long
        as ~0.1 s of work.
        """
        if unknown:
            raise ParameterError(f"sim.run(): unknown parameter(s) {', '.join(unknown)}; "
                                 "allowed: steps, until, progress")
        if (steps is None) == (until is None):
            raise ParameterError("sim.run(): give exactly one of steps or until")
        if steps is not None:
            validate("sim.run()", {"steps": Parameter(low=0, kind="int")}, {"steps": steps})
        else:
            validate("sim.run()", {"until": Parameter(low=self.time, unit="s")},
                     {"until": until})
        def wanted() -> int:
            if steps is not None:
                return int(steps)
            return max(0, math.ceil((until - self.time) / self.dt - 1e-9))

        threads_before = numba.get_num_threads()
        try:
            if not self._prepared:
                if self.inlets and not self._forces_valid and (
                        self.step_count == 0 or len(self.bodies) == 0):
                    population.flow_event(self)  # an inlet may fill an empty scene
                    if len(self.bodies) == 0 and math.isfinite(self.dt):  # (dt="auto": no)
                        skipped = population.wait_for_inlets(self, wanted())
                        if steps is not None:
                            steps = int(steps) - skipped
                        if len(self.bodies) == 0:
                            return  # (the inlets start later than this run ends)
                # the run's thread count before the backend loads its step module: the
                # module's form follows it (CpuBackend.sync_form), and a
                # module loaded under another count would be compiled for nothing
                numba.set_num_threads(self.backend.thread_count(len(self.elements)))
                self._prepare()
            elif not self._dt_checked:  # dt (or dt_check) changed since the last run
                self._check_time_step()
            nsteps = wanted()
            threads = self.backend.thread_count(len(self.elements))
            numba.set_num_threads(threads)
            advice = threading_layer_advice(threads)
            if advice and not _quiet():
                print(f"dpm: {advice}", file=sys.stderr, flush=True)
            try:
                self._run(nsteps, progress)
            except OutputError as exc:  # (disk full: the message says how to go on)
                from .checkpoint import restart_advice

                raise OutputError(f"sim.run(): {exc}{restart_advice(self)}") from exc
        finally:
            numba.set_num_threads(threads_before)


    def _run(self, nsteps: int, progress: bool | None) -> None:
        self.backend.sync_form()
        if not self._forces_valid:
            self.backend.prime()
            if self._integrated_ids == 0:  # the first run: the integrator starts
                self._force_snapshot = None
                self.integrator.start(self)
                self._integrated_ids = self._next_id
                self.energy.start(self)
            else:  # after a run: bodies added since start, the others go on
                population.restore_forces(self)
            self._forces_valid = True
            self._update_boundary_loads()
        if self._scene_box is None:  # (the escape guard's box: at the start of a run)
            self._scene_box = guards.scene_box(self)
        from .progress import Progress

        hooks = self._registry.manager.hook
        per_step_hooks = bool(hooks.dpm_before_step.get_hookimpls()
                              or hooks.dpm_after_step.get_hookimpls())
        # (MPI: a hook on any rank, steps on all; rank 0 writes and reports)
        per_step_hooks = self.backend.agree_any(per_step_hooks)
        root = self.backend.root
        bar = Progress(nsteps, self.dt, self.time, enabled=progress if root else False)
        if self._output_path is not None and self._writer is None:
            from .io.hdf5 import Writer

            if root:
                self._writer = Writer(self._output_path, self,
                                      overwrite=self._output_overwrite)
            else:
                from .io.hdf5 import NullWriter

                self._writer = NullWriter(self._output_path, self)
            self.last_output = self._writer
            self.operations.frames.first(self)
            self._write_frame()
        self.operations.start(self)  # (each schedules itself from here and dt)
        done = 0
        chunk = self._first_chunk()
        chunk = self.backend.agree_chunk(chunk)
        # (the host state is brought up to the backend's before anything between calls
        # reads or changes it, and at the run's end: an MPI backend gathers then only)
        sync = self.backend.sync_host
        try:
            while done < nsteps:
                n = min(nsteps - done, chunk)
                if per_step_hooks:
                    n = 1
                for due in self.operations.due_steps(self):
                    n = min(n, due - self.step_count)
                if per_step_hooks:
                    sync()
                    call_hook(self._registry, "dpm_before_step", sim=self)
                t0 = _time.perf_counter()
                ran = self._advance(n)
                elapsed = _time.perf_counter() - t0
                done += ran
                if per_step_hooks:
                    sync()
                    call_hook(self._registry, "dpm_after_step", sim=self)
                # what is due here, in the operations' order (dpm/operations.py)
                self.operations.run_due(self, sync)
                bar.update(ran, self.time)
                # aim at ~0.1 s of work per call (Python runs only at these events), and
                # at least 100x the checks after each call: at 1e6 spheres a step takes
                # ~60 ms and the checks ~4 ms, which at one or two steps per call had cost
                # a tenth of the run
                if elapsed > 0:
                    aim = self._call_aim()
                    if ran == n:
                        self._call_rate = (elapsed / ran / max(len(self.bodies), 1), ran)
                    chunk = int(min(max(chunk * min(aim / elapsed, 4.0), 1), 100000))
                chunk = self.backend.agree_chunk(chunk)  # (MPI: the same on every rank)
            sync()
        finally:
            bar.close()
            if self._writer is not None:
                self._writer.flush()


    def _call_aim(self) -> float:
        return max(self.backend.call_aim, 100.0 * self._check_cost)

    def _first_chunk(self) -> int:
        """Steps of a run's first kernel call: 10, or, after an earlier run, what its last
        call's seconds per step and body predict for the aim (at most 4x that call's
        steps), so that a script running many short runs does not ramp its calls up from
        10 steps every time (across MPI ranks each call ends in a collective vote)."""
        if self._call_rate is None:
            return 10
        rate, last = self._call_rate
        predicted = self._call_aim() / max(rate * max(len(self.bodies), 1), 1e-300)
        return int(min(max(predicted, 10), 4 * last, 100000))

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
        self._update_boundary_loads()
        if res.status != STATUS_OK:  # (the diagnosis reads the host state)
            self.backend.sync_host()
        if res.status == STATUS_NAN:
            self._fail("a position became NaN")
        if res.status == STATUS_INTEGRATOR:
            self._fail(self.integrator.failure)
        if res.status == STATUS_OVERLAP:
            self._fail(f"an overlap reached {res.worst_overlap:.3g} of the radius "
                       f"(max_overlap={self.max_overlap:g})"
                       f"{diagnosis.locate(self, res.worst_element)}"
                       f"{overlap_hint(self, res.worst_element, res.worst_overlap)}")
        t0 = _time.perf_counter()
        if self.speed_guard:
            diagnosis.check_speeds(self)
        guards.check(self)
        self._check_cost = _time.perf_counter() - t0
        return total

    def _fail(self, what: str) -> None:
        raise diagnosis.unstable(self, what)

    def _failure(self, what: str) -> Exception:
        return diagnosis.unstable(self, what)

    def _update_boundary_loads(self) -> None:
        w = self.walls
        loads = None if w is None else self.backend.boundary_loads()
        for k, bd in enumerate(self.boundaries):
            if w is None:
                bd.record_load(self.time, np.zeros(3), np.zeros(3), bd.velocity,
                               bd.angular_velocity)
                continue
            # (the kernels keep the running sum: one sum whatever the call ends, so a run
            # with checkpoints or frames equals one without to the last bit)
            bd.work = float(loads[k, 6])
            f = loads[k, :3].copy()
            # torque about the frame origin o -> about the torque point c
            o = w.frame[k, :3]
            bd.record_load(self.time, f, loads[k, 3:6] + np.cross(o - bd.torque_point, f),
                           w.frame[k, 12:15].copy(), w.frame[k, 15:18].copy())

    def _write_frame(self) -> None:
        self.backend.sync_host()
        self._writer.write(self)
        self._last_frame_step = self.step_count
        call_hook(self._registry, "dpm_on_output", sim=self, frame=self._writer.frames - 1,
                  path=self._writer.path)

    # ----------------------------------------------------------------- checkpoints
    def checkpoint(self, path: str | os.PathLike) -> Path:
        """Write a checkpoint of the whole simulation now (:mod:`dpm.checkpoint`):
        :func:`dpm.restart` continues from it bit for bit. Written atomically (a
        temporary file beside ``path``, fsync, rename). Returns the path."""
        from . import checkpoint as _ckpt

        if isinstance(path, bool) or not isinstance(path, str | os.PathLike) or not str(path):
            raise ParameterError(f"sim.checkpoint(): path={path!r} must be a file name")
        return _ckpt.write(self, path)

    def checkpoint_every(self, path: str | os.PathLike, every: float | None = None,
                         every_steps: int | None = None, keep: int = 2) -> None:
        """Write checkpoints during the runs every ``every`` seconds of simulated time
        (or ``every_steps`` steps) to numbered files beside ``path`` (``run.ckpt.h5`` ->
        ``run.ckpt.0000012000.h5``, the step number), keeping the last ``keep``.
        ``dpm.restart(path)`` takes the newest. ``path=None`` stops them.

        A checkpoint is plain data (:mod:`dpm.checkpoint`): a scene object it cannot store
        (a lambda, a function defined inside a function, an object of another library) is
        refused here, by where it sits (``sim.boundaries[1].motion.profile``)."""
        from . import checkpoint as _ckpt

        if path is None:
            self.operations.checkpoints = None
            return
        if isinstance(path, bool) or not isinstance(path, str | os.PathLike) or not str(path):
            raise ParameterError(f"sim.checkpoint_every(): path={path!r} must be a file name")
        if (every is None) == (every_steps is None):
            raise ParameterError("sim.checkpoint_every(): give exactly one of every (s) or "
                                 "every_steps")
        spec = {"every": Parameter(default=None, low=0.0, low_open=True, unit="s"),
                "every_steps": Parameter(default=None, low=1, kind="float"),
                "keep": Parameter(default=2, low=1, kind="float")}
        validate("sim.checkpoint_every()", spec,
                 {"every": every, "every_steps": every_steps, "keep": keep})
        for name, value in (("every_steps", every_steps), ("keep", keep)):
            if value is not None and (isinstance(value, bool) or int(value) != value):
                raise ParameterError(f"sim.checkpoint_every(): {name}={value!r} must be an "
                                     "integer")
        base = Path(path)
        if base.is_dir():
            raise ParameterError(f"sim.checkpoint_every(): path={str(path)!r} is a directory")
        from .io.state_tree import encode

        encode(self, "sim.checkpoint_every()")  # (what a checkpoint cannot store: refused now)
        self.operations.checkpoints = _ckpt.Schedule(base, None if every is None else float(every),
                                           None if every_steps is None else int(every_steps),
                                           int(keep), self.step_count,
                                           self.dt if self.dt > 0 else 1.0)

    def __getstate__(self) -> dict[str, Any]:
        """What a checkpoint stores: everything but the plugin registry (found again),
        the open output file (its path and frame count instead) and the progress of a
        run in flight."""
        state = self.__dict__.copy()
        w = state.get("_writer")
        state["_writer"] = None
        state["last_output"] = None
        state["_writer_state"] = None if w is None else {
            "path": str(w.path), "frames": int(w.frames), "removed": int(w.removed)}
        state["_registry"] = None
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._registry = registry()

    def _restored(self, path: Path) -> None:
        """After unpickling from the checkpoint at ``path``: reopen the output, plugins."""
        from .checkpoint import resume_output

        ws = self.__dict__.pop("_writer_state", None)
        resume_output(self, ws)
        ck = self.operations.checkpoints
        if ck is not None and ck.next <= self.step_count:
            ck.next = self.step_count + ck.interval(self.dt)
        call_hook(self._registry, "dpm_on_restart", sim=self,
                  state=self.__dict__.pop("_plugin_state", {}) or {})

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


def _boundary_kinds_doc() -> str:
    """The built-in boundary kinds and their parameters, for ``add_boundary``'s docstring
    (generated from the classes' declared parameters, so it cannot fall behind)."""
    from . import boundaries as b
    from .boundaries.signature import describe

    lines = ["Notes", "-----", "Built-in kinds, with each parameter's unit, range and default",
             "(``help(dpm.boundaries.Tube)`` etc. give the geometry):", ""]
    for kind, cls in (("plane", b.Plane), ("box", b.Box), ("wall", b.Wall), ("tube", b.Tube),
                      ("bend", b.Bend), ("mesh", b.Mesh), ("sieve", b.Sieve),
                      ("orifice_plate", b.OrificePlate)):
        lines.append(f"``{kind}`` (:class:`~dpm.boundaries.{cls.__name__}`)")
        lines += [f"    - ``{name}``: {describe(name, p)}" for name, p in cls.parameters.items()]
        lines.append("")
    return "\n".join(lines)


Simulation.add_boundary.__doc__ = (inspect.cleandoc(Simulation.add_boundary.__doc__ or "")
                                   + "\n\n" + _boundary_kinds_doc())
