"""The CPU backend: numba kernels over the host arrays, threads by ``prange``.

Results are bit for bit the same for any number of threads and for either force form
(``kernels/step.py``). Its fast form runs many steps in one compiled call
(:func:`run_steps`); the parts of a step (:meth:`CpuBackend.pre_force` ...
:meth:`CpuBackend.post_force`) give the same bits one at a time.
"""

from __future__ import annotations

import os
from typing import Any

import numba
import numpy as np

from .. import warm
from ..errors import ParameterError
from .base import (
    STATUS_OK,
    STATUS_OVERFLOW,
    STATUS_OVERLAP,
    STATUS_WALL_OVERFLOW,
    BackendBase,
    StepResult,
)
from .records import (
    BodyArrays,
    BoundaryArrays,
    ElementArrays,
    PairList,
    SceneConstants,
    WallList,
)

#: scenes with fewer elements run on one thread unless ``threads`` is given
SMALL_SCENE = 4000
#: list rebuilds between renumberings of the bodies in cell order, by default, for scenes
#: of at least ``SORT_FROM`` elements: bodies inserted or mixed out of order (an inlet,
#: a LIGGGHTS start, a drum) put a body's partners far apart in memory, which cost a
#: settled bed of 2,000 clusters 1.34x on two threads against 1.91x in cell order
SORT_EVERY = 20
#: the smallest scene renumbered by default (below it the scene sits in the caches; a
#: shuffled box of 3,375 spheres ran 0.94 of its lattice order, and renumbered 0.95)
SORT_FROM = SMALL_SCENE
#: the renumbering is decided every ``SORT_CHECK_STEPS`` steps of a run, a kernel call
#: ending there (:meth:`CpuBackend.sort_due`): a decision at whatever step a time-sized
#: call happened to end would make the order of the sums, and so a run's round-off,
#: depend on the machine's speed
SORT_CHECK_STEPS = 1000
#: the force forms (``force_pass``)
FORCE_PASSES = ("auto", "fused", "two_pass")


def default_threads() -> int:
    """``$DPM_THREADS`` (an integer or ``all``), else 1."""
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


_LAYER_WARNED: list[bool] = []


def threading_layer_advice(threads: int) -> str | None:
    """A warning (once per process) when a run on several threads finds numba on another
    threading layer than OpenMP although OpenMP is there and ``$NUMBA_THREADING_LAYER``
    does not ask for it: numba chose its layer at the process's first parallel launch,
    before ``import dpm`` put OpenMP first. On a 2-core machine a parallel launch on two
    threads costs 169 us on TBB against 4.2 us on OpenMP, and a settled bed of 2,000
    clusters gains 1.46x from two threads on TBB against 1.67x on OpenMP. None when
    there is nothing to say."""
    if threads <= 1 or _LAYER_WARNED or "NUMBA_THREADING_LAYER" in os.environ:
        return None
    try:
        layer = numba.threading_layer()
    except ValueError:  # (no parallel launch yet: the layer will be OpenMP's)
        return None
    if layer == "omp":
        return None
    try:
        from numba.np.ufunc import omppool  # noqa: F401
    except ImportError:  # (no OpenMP here: the layer numba took is the best there is)
        return None
    _LAYER_WARNED.append(True)
    return (f"numba runs its parallel loops on its {layer!r} threading layer, chosen by a "
            "parallel launch before `import dpm`; OpenMP's launches can be far cheaper "
            "(169 us against 4 us on two threads of one 2-core machine). Import "
            "dpm first, or set NUMBA_THREADING_LAYER=omp (or to the layer you want, which "
            "also silences this).")


class CpuBackend(BackendBase):
    """numba kernels on the host.

    Parameters
    ----------
    threads : int, optional
        Threads of the step kernels (default: ``$DPM_THREADS``, else 1; scenes under
        ``SMALL_SCENE`` elements one thread unless given).
    force_pass : {"auto", "fused", "two_pass"}
        The force form: "auto" takes the fused pass when every body is a single sphere
        and two passes otherwise; "two_pass" always sums through force rows (for
        comparisons and profiles: the sums are the same bit for bit). May be changed
        between runs.
    sort_every : int, optional
        Renumber the bodies in the order of the contact-search cells they lie in once
        ``sort_every`` list rebuilds have passed (0: never), so that neighbours sit close
        in memory (:meth:`sort_by_cell`), decided every ``SORT_CHECK_STEPS`` (1,000)
        steps, so that every run of a scene renumbers at the same steps. Default: 20
        rebuilds (``SORT_EVERY``) in scenes of at least ``SORT_FROM`` (4,000) elements,
        never in smaller ones. Rows of
        ``sim.bodies`` then change order (ids do not: find a body by its id); the sums
        of a body's forces may change by rounding.
    kernels : {"auto", "scene", "universal"}, optional
        Which step module runs the scene (:mod:`dpm.warm`): "scene", its own (compiled
        at its first run, then cached); "universal", the integrator's module for every
        scene of built-in parts (compiled once, by ``dpm compile``; same results bit for
        bit, slower); "auto" (default, or ``$DPM_KERNELS``): its own when compiled
        before, else the universal one when compiled (and its own compiled in the
        background for the next run), else its own.
    """

    name = "cpu"
    #: whether this backend can run the universal step module (the MPI and CUDA backends
    #: call functions of the scene's own)
    universal_ok = True
    #: whether a run on one thread takes the step module's one-thread form
    #: (:func:`dpm.plan.one_thread_form`)
    one_thread_ok = True

    def __init__(self, threads: int | None = None, force_pass: str = "auto",
                 sort_every: int | None = None, kernels: str | None = None) -> None:
        if force_pass not in FORCE_PASSES:
            raise ParameterError(f"CpuBackend(): force_pass={force_pass!r}; allowed: "
                                 f"{', '.join(FORCE_PASSES)}")
        if not (sort_every is None or (isinstance(sort_every, int)
                                       and not isinstance(sort_every, bool)
                                       and sort_every >= 0)):
            raise ParameterError(f"CpuBackend(): sort_every={sort_every!r} must be None "
                                 f"(every {SORT_EVERY} rebuilds from {SORT_FROM} "
                                 "elements, else never) or an integer >= 0 (0: never)")
        self.threads = threads
        self.force_pass = force_pass
        self.kernel_choice = warm.kernels_choice(kernels)
        #: the step module is the universal one (its pair table: ``_universal_params``)
        self.universal = False
        self._universal_params: np.ndarray | None = None
        self._form: tuple[bool, bool] | None = None
        self._compiled = False
        #: renumber the bodies in cell order after this many list rebuilds (0: never)
        self.sort_every = sort_every
        self._rebuilds_since_sort = 0
        self.sim: Any = None
        self.module = None
        #: kernel diagnostics (see kernels/step.py): status, steps, rebuilds, pairs
        #: needed, largest overlap / radius, its element, touching contacts
        self.diag = np.zeros(8)
        self.aux = np.zeros((0, 0))
        self._rows_stale = False

    def __getstate__(self) -> dict[str, Any]:
        """A checkpoint keeps the state (the integrator's rows, diagnostics); the step
        module is loaded again at the next run."""
        state = self.__dict__.copy()
        state["module"] = None
        state["_universal_params"] = None
        state["_form"] = None
        return state

    # ------------------------------------------------------------------ set-up
    def thread_count(self, n_elements: int) -> int:
        """Threads for a run of a scene of ``n_elements`` elements."""
        if self.threads is not None:
            return int(self.threads)
        if n_elements < SMALL_SCENE:
            return 1
        return default_threads()

    def attach(self, sim: Any) -> None:
        self.sim = sim
        plan, b, e = sim.plan, sim.bodies, sim.elements
        self.module = None
        self.sync_form()
        n_el = len(e)
        c, wc = sim.contacts, sim.wall_contacts
        c.set_history_width(plan.history_width)
        wc.set_history_width(plan.history_width)
        if len(c.start) != n_el + 1 or (c.count == 0 and wc.count == 0):
            c.reset(n_el, 4 * n_el)  # grows on demand
            wc.reset(n_el, n_el // 4 + 16)
        # (re-attached after a run: the lists, their history and the integrator's rows of
        # the bodies already there are kept; rows of bodies added since start at zero)
        self._scratch()
        cols = sim.integrator.aux_columns
        if self.aux.shape[1:] == (cols,) and len(self.aux) <= len(b):
            self.aux = np.ascontiguousarray(np.concatenate(
                [self.aux, np.zeros((len(b) - len(self.aux), cols))]))
        else:
            self.aux = np.zeros((len(b), cols))
        if not plan.spheres_only:
            self.update_elements()

    def _scratch(self) -> None:
        b, e = self.sim.bodies, self.sim.elements
        self.e_worst = np.zeros(len(e))
        self.e_count = np.zeros(len(e), np.int32)
        self.vf = np.zeros((len(b), 3))  # velocities the forces see (set by the integrator)
        self.wf = np.zeros((len(b), 3))

    def sync_form(self) -> None:
        """Load the step module of the force pass the scene needs: the fused pass when
        every body is a single sphere, else the two-pass sum (``FUSED``, a constant of the
        generated module, so that a scene compiles one form only); on one thread its
        one-thread form (no parallel-loop launches: :func:`dpm.plan.one_thread_form`).
        Called at a run's start, once the run's thread count is set."""
        plan = self.sim.plan
        fused = (plan.spheres_only if self.force_pass == "auto"
                 else self.force_pass == "fused" and plan.spheres_only)
        want = (fused, self.one_thread_ok and numba.get_num_threads() == 1)
        if self.module is None or self._form != want:
            self._form = want
            self._compiled = False
            if self.universal_ok:
                self.module, self.universal = warm.choose(plan, want[0], self.kernel_choice,
                                                          one_thread=want[1])
            else:
                self.module, self.universal = plan.module(*want), False
            self._universal_params = None
            if self.universal:
                from ..universal_step import universal_tables

                self._universal_params = universal_tables(plan.laws, plan.pair_model,
                                                          plan.pair_params)

    def _after_call(self) -> None:
        """After the first call of a step module: it is in numba's cache now (marked
        ready); a universal one hands the scene's own module to a background compile."""
        if self._compiled or self.module is None:
            return
        self._compiled = True
        warm.mark_ready(self.module)
        if self.universal and self.kernel_choice == "auto" and warm.background_allowed():
            warm.compile_in_background(self.sim.plan, self._form[0],
                                       warm.signatures(self.module), self._form[1])

    def fused_chunks(self) -> int:
        """The number of chunks (one per thread) if the step sums forces as it computes
        them (kernels/step.py ``fused_pass``); 0 for the two-pass form. The sums are bit
        for bit the same; the fused pass leaves the rows of most pairs stale, so those are
        zeroed when the two-pass form takes over again."""
        fused = numba.get_num_threads() if self.module.FUSED else 0
        c = self.sim.contacts
        c.use_rows(fused != 1)  # rows: the two-pass sum, and pairs across chunks
        if not fused and self._rows_stale:
            c.force[:] = 0.0
        self._rows_stale = bool(fused)
        return fused

    def records(self) -> tuple:
        """The kernel records of the current state: (constants, bodies, elements, pair
        list, boundary list, boundary table); named tuples of the arrays, no copies."""
        sim = self.sim
        b, e, c, wc, w, plan = (sim.bodies, sim.elements, sim.contacts, sim.wall_contacts,
                                sim.walls, sim.plan)
        ctl = SceneConstants(sim.gravity, float(sim.skin), sim.max_overlap,
                             not plan.spheres_only, self.fused_chunks(),
                             plan.spheres_only and not sim.sphere_orientation,
                             plan.pair_model,
                             plan.pair_params if self._universal_params is None
                             else self._universal_params, sim.period,
                             len(b) - b.ghosts, float(getattr(plan, "reach", 0.0)))
        bodies = BodyArrays(b.position, b.velocity, b.orientation, b.angular_velocity,
                            b.force, b.torque, b.mass, b.invmass, b.invinertia, self.vf,
                            self.wf, self.aux, b.element_start)
        elems = ElementArrays(e.owner, e.offset, e.radius, e.material, e.position,
                              e.reference, self.e_worst, self.e_count)
        pairs = PairList(c.start, c.key, c.history, c.active, c.force, c.t_start, c.t_pair)
        walls = WallList(wc.start, wc.key, wc.history, wc.active, wc.force, wc.tag)
        bnd = BoundaryArrays(w.kind, w.par, w.owner, w.material, w.ids, w.frame, w.frame_ref,
                             w.extent, w.load, w.grid_int, w.grid_flt, w.cell_start,
                             w.cell_items, w.prim_cells)
        return ctl, bodies, elems, pairs, walls, bnd

    def update_elements(self) -> None:
        """Element world positions from their bodies."""
        b, e = self.sim.bodies, self.sim.elements
        if len(b):
            self.module.update_element_positions(b.position, b.orientation, b.element_start,
                                                 e.offset, e.position)

    def _grow(self, status: int, needed: int) -> None:
        sim = self.sim
        (sim.contacts if status == STATUS_OVERFLOW else sim.wall_contacts).grow(needed)

    # ------------------------------------------------------------------ the step's parts
    def rebuild(self) -> None:
        """Rebuild both lists (growing them as needed), history carried over by pair."""
        d = self.diag
        while True:
            d[0] = STATUS_OK
            self.module.rebuild(*self.records(), d)
            if d[0] in (STATUS_OVERFLOW, STATUS_WALL_OVERFLOW):
                self._grow(int(d[0]), int(d[3]))
            else:
                break
        self.sim.rebuild_count += int(d[2])
        d[2] = 0
        c, wc = self.sim.contacts, self.sim.wall_contacts
        c.force[:c.count] = 0.0  # rows of the new lists: the contact pass fills touching ones
        wc.force[:wc.count] = 0.0

    def pre_force(self, dt: float) -> None:
        ctl, bodies, elems, *_ = self.records()
        self.module.pre_force(dt, ctl, bodies, elems)

    def needs_rebuild(self) -> int:
        ctl, _, elems, _, _, bnd = self.records()
        return int(self.module.needs_rebuild(ctl, elems, bnd))

    def forces(self, dt: float, integrate: bool = False) -> None:
        """Gravity and contact forces (and the post-force part too if ``integrate``)."""
        ctl, bodies, elems, pairs, walls, bnd = self.records()
        self.module.compute_forces(dt, integrate, ctl, bodies, elems, pairs, walls, bnd,
                                   self.diag)

    def post_force(self, dt: float) -> None:
        ctl, bodies, *_ = self.records()
        self.module.post_force(dt, ctl, bodies)

    def prime(self) -> None:
        """Forces of the current state, leaving the contact history and the touching
        flags as they were (dt = 0: the contact pass would otherwise re-project tangential
        springs and mark contacts as begun, so that the steps after a prime differ from
        those of an uninterrupted run)."""
        with warm.compiling(self.module):  # (the first forces compile the module)
            self._prime()

    def _prime(self) -> None:
        sim = self.sim
        b = sim.bodies
        self.vf[:] = b.velocity
        self.wf[:] = b.angular_velocity
        kept = []
        for lst in (sim.contacts, sim.wall_contacts):
            n = lst.count
            idx = np.flatnonzero(lst.active[:n])
            kept.append((lst, n, idx, lst.history[idx].copy(), lst.active[:n].copy()))
        self.forces(0.0, False)
        for lst, n, idx, hist, act in kept:
            lst.history[:n][lst.active[:n] != 0] = 0.0
            lst.history[idx] = hist
            lst.active[:n] = act

    def advance(self, n: int, dt: float, frames: np.ndarray) -> StepResult:
        """``n`` steps in one compiled call (fewer when a status stops it); a full list
        stops the loop after the pre-force part of a step, the lists grow and the step is
        finished, so results do not depend on where a run is split into calls."""
        d = self.diag
        if not self._compiled:  # (the first call compiles: said while it does)
            with warm.compiling(self.module):
                self.module.run_steps(n, dt, *self.records(), d, frames)
                self._after_call()
        else:
            self.module.run_steps(n, dt, *self.records(), d, frames)
        ran = int(d[1])
        while d[0] in (STATUS_OVERFLOW, STATUS_WALL_OVERFLOW):
            self._grow(int(d[0]), int(d[3]))
            d[0] = STATUS_OK
            self.module.finish_step(dt, *self.records(), d)
            if d[0] in (STATUS_OK, STATUS_OVERLAP):
                ran += 1
        d[1] = ran
        self._after_call()
        out = self._result(ran)
        self._rebuilds_since_sort += out.rebuilds
        return out

    def sorts(self) -> bool:
        """Whether this run renumbers its bodies by default (:meth:`sort_interval`):
        :class:`dpm.Simulation` then ends a kernel call every ``SORT_CHECK_STEPS`` steps
        and calls :meth:`sort_due` there."""
        return self.sort_interval(len(self.sim.elements)) > 0

    def sort_due(self) -> None:
        """At a multiple of ``SORT_CHECK_STEPS`` steps: renumber in cell order if
        ``sort_interval`` rebuilds have passed since the last renumbering. Both the
        steps and the rebuild counts are the run's own, not the calls', so the
        renumberings, and with them the round-off, are the same in every run of a
        scene, on any number of threads."""
        every = self.sort_interval(len(self.sim.elements))
        if every and self._rebuilds_since_sort >= every:
            self.sort_by_cell()

    def sort_interval(self, n_elements: int) -> int:
        """List rebuilds between renumberings in cell order for a scene of
        ``n_elements`` elements (0: never): ``sort_every`` if given, else ``SORT_EVERY``
        from ``SORT_FROM`` elements (as LIGGGHTS' ``atom_modify sort``, on by default)
        and never below, where the whole scene sits in the caches."""
        if self.sort_every is not None:
            return int(self.sort_every)
        return SORT_EVERY if n_elements >= SORT_FROM else 0

    def sort_by_cell(self) -> None:
        """Renumber the bodies in the order of the cell (half the contact-search cell,
        (2 r_max + skin) / 2, z fastest) that holds their centre
        (:meth:`dpm.Simulation.permute`: every contact keeps its history). Half cells:
        on the shuffled box_settle packing they recovered 0.93 of the lattice order's
        speed, whole search cells 0.86."""
        sim = self.sim
        b = sim.bodies
        self._rebuilds_since_sort = 0
        if len(b) < 2:
            return
        width = 0.5 * (2.0 * float(sim.elements.radius.max()) + float(sim.skin))
        lo = b.position.min(axis=0)
        cell = ((b.position - lo) / width).astype(np.int64)
        dims = cell.max(axis=0) + 1
        key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
        order = np.argsort(key, kind="stable")
        if np.any(order != np.arange(len(order))):
            sim.permute(order)

    def _result(self, ran: int) -> StepResult:
        d = self.diag
        out = StepResult(ran, int(d[0]), int(d[2]), float(d[4]), int(d[5]))
        d[2] = 0
        return out

    # ------------------------------------------------------------------ reductions
    def max_speed(self) -> tuple[int, float]:
        """(index, speed) of the fastest body; speed NaN if a velocity is NaN."""
        from ..diagnosis import fastest_body

        return fastest_body(self.sim.bodies.velocity)

    def max_overlap(self) -> tuple[float, int]:
        """Largest overlap / radius since the last reset and its element."""
        return float(self.diag[4]), int(self.diag[5])

    def nan_count(self) -> int:
        b = self.sim.bodies
        return int(np.count_nonzero(~np.isfinite(b.position))
                   + np.count_nonzero(~np.isfinite(b.velocity)))

    def boundary_loads(self) -> np.ndarray:
        """(boundaries, 6): force [0:3] and torque about the frame origin [3:6]."""
        return self.sim.walls.load

    def contact_count(self) -> int:
        """Touching contacts (pairs and boundary entries) of the last force evaluation."""
        return int(self.diag[6])

    # ------------------------------------------------------------------ population
    def keep_bodies(self, keep_b: np.ndarray) -> None:
        """Bodies are being removed (``keep_b`` False): drop their rows of the
        integrator state (the contact lists are compacted by the caller). Rows of bodies
        added since the last attach have no state yet."""
        self.aux = np.ascontiguousarray(self.aux[keep_b[:len(self.aux)]])

    def permute_bodies(self, order: np.ndarray) -> None:
        """The bodies were reordered (:meth:`dpm.Simulation.permute`): the per-body state
        this backend keeps follows (the integrator's auxiliary rows)."""
        self.aux = np.ascontiguousarray(self.aux[order])
        self._scratch()

    def population_changed(self) -> None:
        """After bodies were inserted or removed during a run: resize the per-element
        arrays (keeping the contact lists and their history), rebuild, recompute forces."""
        sim = self.sim
        b, e = sim.bodies, sim.elements
        n_el = len(e)
        self.sync_form()
        if not sim.plan.spheres_only:
            self.update_elements()
        sim.contacts.resize_rows(n_el)
        sim.wall_contacts.resize_rows(n_el)
        self._scratch()
        if len(self.aux) < len(b):
            extra = np.zeros((len(b) - len(self.aux), self.aux.shape[1]))
            self.aux = np.ascontiguousarray(np.concatenate([self.aux, extra]))
        e.reference = np.full((n_el, 3), np.inf)
        self.rebuild()
        self.prime()

    # ------------------------------------------------------------------ checks
    def pair_overlaps(self) -> np.ndarray:
        """Overlap / smaller radius of each listed pair (negative: apart)."""
        e, c = self.sim.elements, self.sim.contacts
        return self.module.pair_overlaps(e.position, e.radius, c.start, c.key, self.sim.period)

    def entry_overlaps(self) -> np.ndarray:
        """Overlap / radius of each element-boundary entry (0 where not touching)."""
        e, wc, w = self.sim.elements, self.sim.wall_contacts, self.sim.walls
        return self.module.entry_overlaps(e.position, e.radius, wc.start, wc.key, w.kind,
                                          w.par, w.owner, w.frame)

    # ------------------------------------------------------------------ state transfer
    #: whether ``sim.bodies`` (and the contact lists) are older than the backend's state
    #: (an MPI backend between a run's calls); the CPU backend's host arrays are its state
    host_stale = False

    def sync_host(self) -> None:
        """Bring the host's state up to the backend's before anything reads or changes
        it (the run loop calls it at events and at a run's end; collective across MPI
        ranks). The CPU backend's host arrays are its state: nothing to do."""

    def energies(self, gravity: np.ndarray) -> tuple[float, float]:
        """(kinetic, mechanical) energy [J] of the bodies (:func:`dpm.guards.energies`)."""
        from ..guards import energies

        return energies(self.sim.bodies, gravity)

    def guard_hits(self, nonfinite: bool, box: np.ndarray | None) -> bool:
        """Whether the run-time guards would find anything (a non-finite state value, a
        centre outside ``box``) without reading the host: a backend whose host is stale
        answers from its own state; here the host is the state, so look there (True)."""
        return True

    def force_rows_current(self) -> bool:
        """The two-pass form keeps every pair's force row of the last evaluation (the
        fused pass only those of pairs across chunks)."""
        module = self.module
        return module is not None and not getattr(module, "FUSED", True)

    def force_velocities(self) -> tuple[np.ndarray, np.ndarray] | None:
        vf, wf = self.__dict__.get("vf"), self.__dict__.get("wf")
        return None if vf is None or wf is None else (vf, wf)
