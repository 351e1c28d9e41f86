"""The MPI backend: one sub-domain per rank, ghost layers, migration with contact history.

Design (the DPM thesis, section 2.8.2; LAMMPS/LIGGGHTS' ``comm`` with ``newton off``):

- **The host state is whole on every rank where the run loop reads it.** A call
  scatters the host state into each rank's sub-domain (when it changed) and ends
  without gathering it back (:attr:`host_stale`); :meth:`sync_host` gathers it where the
  run loop needs it (output frames, flow events, hooks, switches, checkpoints, a
  failure's diagnosis, each run's end), so those run as on one process, the same on
  every rank, with ``sim.bodies``, the elements and both contact lists holding the whole
  scene; only rank 0 writes files. Between calls the guards, the tunnelling check and
  the energy book are reductions of the ranks' owned rows (:meth:`guard_hits`,
  :meth:`max_speed`, :meth:`energies`). A gather: each rank sends
  its owned rows (state, the integrator's rows, element references, the contact entries
  it reports, with history) to all as one float64 and one int64 buffer
  (:class:`dpm.parallel.messages.Gather`; the counts by ``Allgather``, the payloads by
  ``Iallgatherv`` into one buffer each, packed and unpacked straight into the host
  arrays by numba kernels, :mod:`dpm.kernels.migrate`).
- **Sub-domains**: orthogonal recursive bisection (:mod:`dpm.parallel.decomposition`)
  over the bodies' modelled cost (elements and touching contacts at a fixed weight, so
  that the cut depends on the state only and a run repeats bit for bit), redone at a
  call's start and at a list rebuild inside a call (:meth:`_recut_in_call`) when the
  ranks' modelled costs differ by more than ``rebalance`` (LIGGGHTS' ``fix balance``
  threshold; 1.1 by default), and always after the population changed.
- **Ownership and ghosts**: a rank owns the bodies whose centre lies in its box and holds
  as ghosts every body of another rank with a listed contact partner among its own
  elements (at a call's start), or within 2 r_max + skin + the body's own extent + the
  scene's largest extent + ``ghost_margin`` of its box: a clustered body is ghosted
  whole. Each rank computes every
  contact of its owned elements (owned-ghost pairs on both ranks, Newton's third law not
  used across ranks), so an owned body's force is complete without sending forces back;
  its lists hold no pair of two ghosts and no boundary entry of a ghost (their owners
  compute those: the ghosts' forces come with the halo).
- **Every step**: the integrator's pre-force part runs for owned bodies (only owners
  integrate); the ranks vote on a NaN, a rebuild and the previous step's overlap limit
  (collective) while each owner sends what the force pass reads of its ghosts
  (position, quaternion, the velocities the forces see: 13 floats a body) to the ranks
  holding them (LAMMPS' forward communication; one message per neighbour, ``Isend`` /
  ``Irecv``; rows packed and unpacked by numba kernels, :mod:`dpm.kernels.halo`); one
  wait for both; the ghosts place their elements; forces and the post-force part run
  for owned bodies. At a rebuild step the migration carries the ghosts' state instead
  (or, where the rows stay, the halo).
  An overlap past ``max_overlap`` stops every rank at the serial step, with step
  s + 1's pre-force part done too (its vote travels with that step's). The steps between
  rebuilds run as one compiled call with the MPI calls in it
  (:func:`dpm.kernels.step.ranked_run`, :mod:`dpm.kernels.mpi_calls`) where this MPI
  allows it (:mod:`dpm.parallel.native`), else from Python with mpi4py.
- **At a list rebuild** (the same step on every rank, since ghosts move as their owners):
  unless the ghost layers held still cover what the new lists need and no body strayed
  farther than ``ghost_margin`` out of its box (:meth:`MpiBackend._ghosts_cover`: then
  the rows stay and the halo runs), bodies whose centre left the box migrate to the
  rank whose box holds it, with their
  full state (orientation, angular velocity, the integrator's rows) and the history of
  every contact they touch; ghost layers are chosen again; each rank rebuilds its lists,
  carrying every contact's history by pair. One message per pair of ranks, one float64
  and one int64 buffer (:class:`dpm.parallel.messages.Migration`: body rows, element
  rows, the migrants' contact entries by body id and element within the body, packed by
  numba kernels): the counts by ``Ialltoall`` while the buffers are packed, then
  ``Ialltoallv`` of both.
- No array travels pickled: besides the buffer calls above, only scalars (a call's
  steps, the ranks' step times, whether the host state changed, the largest overlap and
  its element) travel by mpi4py's lower-case calls.
- Boundary loads and work are summed over ranks (each counts its owned elements only).

- Periodic faces: the kernels take the nearest image of a pair across a periodic face,
  so a ghost is the body itself at its wrapped position, chosen by its nearest image's
  distance from the box; a rank whose box touches both ends of a period needs no copy of
  its own bodies (it is its own periodic neighbour through the nearest image).

Refused with a clear error: implicit integrators (their Newton iterations would need
messages inside the iteration; not yet).
"""

from __future__ import annotations

import numbers
import time
from typing import Any

import numpy as np

from ..backends.base import STATUS_NAN, STATUS_OK, STATUS_OVERLAP, StepResult
from ..backends.cpu import CpuBackend
from ..errors import ParameterError
from ..kernels.domain import owner_and_near
from ..kernels.halo import HALO_WIDTH
from ..kernels.mpi_calls import HALO_TAG
from . import decomposition as dec
from . import launched_ranks
from .local import (
    Entries,
    LocalScene,
    Pool,
    assemble,
    element_rows,
    orient_pairs,
    set_entries,
    take,
)
from .messages import Gather, Migration, Scratch, mpi_counts

#: step functions compiled in turn in this process (:meth:`MpiBackend._compile_in_turn`)
_COMPILED_IN_TURN: dict[int, Any] = {}


class MpiBackend(CpuBackend):
    """Domain decomposition over MPI ranks: one sub-domain per rank, ghosts, migration with
    contact history (the module docstring says how). On one rank it is the CPU backend.
    ``threads`` are each rank's threads (MPI x threads); ``rebalance`` the imbalance
    (largest over mean modelled cost of the ranks) above which the domain is cut again;
    ``loop="compiled"`` refuses to run where the steps between list rebuilds cannot run
    as one compiled call with the MPI calls in it ("auto", the default: compiled where
    this MPI allows it, else from Python)."""

    universal_ok = False  # (its kernels call functions of the scene's own module)

    name = "mpi"

    def __init__(self, threads: int | None = None, force_pass: str = "auto",
                 rebalance: float = 1.1, boxes: Any = None,
                 comm: Any = None, loop: str = "auto",
                 ghost_margin: float | None = None) -> None:
        super().__init__(threads=threads, force_pass=force_pass)
        if loop not in ("auto", "compiled"):
            raise ParameterError(f"MpiBackend(): loop={loop!r}; allowed: auto (compiled "
                                 "where this MPI allows it, else from Python), compiled "
                                 "(an error where it does not)")
        #: how the steps between list rebuilds run: "compiled" (one compiled call with
        #: the MPI calls in it, :func:`dpm.kernels.step.ranked_run`; an error where this
        #: MPI does not allow it), "auto" (compiled where
        #: :func:`dpm.parallel.native.handles` allows it, else two compiled calls per
        #: step with the messages by mpi4py); ``loop_used`` says which ran
        self.loop = loop
        self.loop_used = ""
        if boxes is not None:
            boxes = np.asarray(boxes, float)
            if boxes.ndim != 3 or boxes.shape[1:] != (2, 3) or np.any(
                    boxes[:, 0] >= boxes[:, 1]):
                raise ParameterError(f"MpiBackend(): boxes of shape {boxes.shape}; allowed: "
                                     "(ranks, 2, 3), lower corner below upper corner")
        #: fixed sub-domains (one box per rank, together tiling space) instead of the
        #: bisection: for tests and for scenes whose cut the user knows better
        self.fixed_boxes = boxes
        if not (isinstance(rebalance, int | float) and rebalance >= 1.0):
            raise ParameterError(f"MpiBackend(): rebalance={rebalance!r}; allowed: a "
                                 "number >= 1 (largest over mean step time)")
        self.rebalance = float(rebalance)
        if ghost_margin is not None and (
                isinstance(ghost_margin, bool) or not isinstance(ghost_margin, numbers.Real)
                or not np.isfinite(ghost_margin) or ghost_margin < 0.0):
            raise ParameterError(f"MpiBackend(): ghost_margin={ghost_margin!r}; allowed: "
                                 "None (the scene's skin) or a length >= 0 [m]")
        #: extra thickness [m] of the ghost layers chosen at a migration, beyond what the
        #: next lists need (None: the scene's skin). A list rebuild at which the layers
        #: held still cover what the new lists need, and no body lies farther than this
        #: outside its rank's box, keeps every body where it is and runs the halo instead
        #: of a migration (:meth:`_ghosts_cover`): a settled bed migrates rarely
        self.ghost_margin = None if ghost_margin is None else float(ghost_margin)
        #: the largest body extent in the scene (:meth:`_body_extent`), set at a scatter
        self._ext_max = 0.0
        self._comm = comm
        self._reset_local()
        #: figures of the last call on this rank: steps, seconds stepping (all of it), in
        #: the step kernels (``work_s``), in the step's one wait for the other ranks: the
        #: vote (NaN, rebuild, the last step's overlap) with the halo exchange
        #: (``halo_s``; it holds this rank's wait for the slowest one's forces too), in
        #: the overlap vote of a call's last step (``wait_s``), migrating
        #: at rebuilds (the list rebuild included), the call's end (the loads' sum) with
        #: any whole-state gather after it (``gather_s``; ``gathers`` counts those),
        #: scattering at the start; owned bodies and ghosts; halo bytes sent per step
        self.timing: dict[str, float] = {}
        #: the same figures summed over the calls (``reset_totals()`` starts again)
        self.totals: dict[str, float] = {}
        #: list rebuilds at which the ghost layers held still covered what the new lists
        #: need and no body had strayed past ``ghost_margin`` out of its box (on every
        #: rank): no migration ran, the halo did
        self.skipped_migrations = 0
        #: bodies that changed rank at the migrations so far, counted by their old owners
        #: (a settled bed of 100,800 spheres on 2 ranks moves a few to a few tens of its
        #: ~50,000 a rank at each: the migration's rebuild of the whole local scene is
        #: O(n) for them)
        self.migrants = 0

    def _reset_local(self) -> None:
        self.local: LocalScene | None = None
        self.inner: CpuBackend | None = None
        self.boxes: np.ndarray | None = None
        self._host_copy: tuple | None = None
        self._hp: dict = {}
        self._sent: np.ndarray | None = None
        self._gather_scratch: Scratch | None = None
        #: the host state (``sim.bodies``, the contact lists) is older than the ranks':
        #: the calls since the last :meth:`sync_host` left it where it was
        self._stale = False

    def __getstate__(self) -> dict[str, Any]:
        state = super().__getstate__()
        for k in ("_comm", "local", "inner", "boxes", "_host_copy", "_gather_scratch",
                  "_sent"):
            state[k] = None
        state["_hp"] = {}
        state["_stale"] = False
        return state

    # ------------------------------------------------------------------ communicator
    @property
    def comm(self) -> Any:
        if self._comm is None:
            from mpi4py import MPI

            self._comm = MPI.COMM_WORLD
        return self._comm

    @property
    def ranks(self) -> int:
        if self._comm is None and launched_ranks() == 1:
            return 1  # (not under an MPI launcher: mpi4py is not imported)
        return int(self.comm.Get_size())

    @property
    def rank(self) -> int:
        if self._comm is None and launched_ranks() == 1:
            return 0
        return int(self.comm.Get_rank())

    @property
    def root(self) -> bool:
        """Whether this rank writes the files (rank 0)."""
        return self.rank == 0

    #: a body's modelled cost per step, in elements, by which the domain is cut: 1 per
    #: element, ``TOUCHING_WEIGHT`` per touching contact of its elements (a pair counts
    #: for both its bodies, a boundary contact twice for its one body).
    #: A step measured (Hertz-Mindlin, one thread) ~40 ns per element, ~45 ns more per
    #: touching pair, and a listed pair that does not touch at the noise (|cost| < 1.5
    #: ns): not counted. (Weighing each listed contact as an element and touching ones
    #: nothing more left the lighter rank of a settling bed at 10,000 spheres waiting
    #: 0.69 s in the halo against 0.19 s.)
    TOUCHING_WEIGHT = 0.5

    #: calls aim at ``CALL_AIM`` seconds of work and at least ``GATHER_SHARE``-fold the
    #: last call's gather (where one followed it: an event, a run's end) and scatter, at
    #: most ``CALL_AIM_MAX`` (events, output frames and the end of a run still end a call
    #: where they fall)
    CALL_AIM = 1.0
    GATHER_SHARE = 50.0
    CALL_AIM_MAX = 30.0

    @property
    def call_aim(self) -> float:
        """Seconds of work the run loop aims each kernel call at: with one rank as one
        process; with several, long enough that a whole-state gather after the call (an
        event's or the run's end) costs at most ~2 % (at 1e6 spheres it takes ~1 s a call)."""
        if self.ranks == 1:
            return 0.1
        t = self.timing.get("gather_s", 0.0) + self.timing.get("scatter_s", 0.0)
        return min(max(self.CALL_AIM, self.GATHER_SHARE * t), self.CALL_AIM_MAX)

    def agree_chunk(self, n: int) -> int:
        """The steps of the next call, the same on every rank (the smallest asked)."""
        if self.ranks == 1:
            return n
        from mpi4py import MPI

        return int(self.comm.allreduce(int(n), op=MPI.MIN))

    # ------------------------------------------------------------------ host changes
    def attach(self, sim: Any) -> None:
        self.sync_host()
        if self.ranks > 1:
            if sim.integrator.implicit:
                raise ParameterError(f"Simulation(device='mpi'): the implicit "
                                     f"{sim.integrator.name} integrator is not supported "
                                     "across ranks; choose an explicit one")
        super().attach(sim)
        self._reset_local()

    def rebuild(self) -> None:
        self.sync_host()
        super().rebuild()
        self._host_copy = None

    def population_changed(self) -> None:
        self.sync_host()
        super().population_changed()
        self._reset_local()

    def prime(self) -> None:
        self.sync_host()
        super().prime()
        self._host_copy = None

    def keep_bodies(self, keep_b: np.ndarray) -> None:
        self.sync_host()
        super().keep_bodies(keep_b)
        self._reset_local()

    def permute_bodies(self, order: np.ndarray) -> None:
        self.sync_host()
        super().permute_bodies(order)
        self._reset_local()

    def _host_unchanged(self) -> bool:
        """Whether the host state is still what the last call gathered (a script may
        have changed it between runs)."""
        if self._host_copy is None or self.local is None:
            return False
        b = self.sim.bodies
        return all(np.array_equal(a, c) for a, c in zip(
            (b.position, b.velocity, b.angular_velocity, b.orientation, b.mass),
            self._host_copy, strict=True))

    # ------------------------------------------------------------------ the steps
    def force_rows_current(self) -> bool:
        """The contact output evaluates the pairs again (the force rows of the last
        evaluation are the CPU backend's own, one process)."""
        return False

    def sorts(self) -> bool:
        """Across ranks no renumbering in cell order (each migration lays a rank's rows
        out anew); on one rank as :class:`CpuBackend`."""
        return self.ranks == 1 and super().sorts()

    def advance(self, n: int, dt: float, frames: np.ndarray) -> StepResult:
        if self.ranks == 1:
            return super().advance(n, dt, frames)
        from mpi4py import MPI

        comm = self.comm
        n = int(comm.allreduce(int(n), op=MPI.MIN))
        # a new cut when the host state changed (on any rank), or the ranks' shares of
        # the modelled cost (the same on every rank: the host state is) drifted apart by
        # more than ``rebalance``
        # (a stale host was left as it was: nothing between the calls changed it, since
        # whatever changes the host gathers it first, :meth:`sync_host`)
        same = comm.allreduce(int(self._stale or self._host_unchanged()), op=MPI.MIN)
        t_scatter = time.perf_counter()
        # (by the measure the cut evens: the step times differ where the model is off,
        # and a cut by cost alone would not change; the cost is the host's, so a stale
        # host leaves it to the re-cut check at the next list rebuild,
        # :meth:`_recut_in_call`)
        recut = (self.fixed_boxes is None and self.boxes is not None and not self._stale
                 and self._cost_imbalance() > self.rebalance)
        if recut:
            self.sync_host()  # (the cut is made from the whole host state)
        if not same or recut:
            if same:  # a re-cut
                self.boxes = None
            self._scatter()
        t_scatter = time.perf_counter() - t_scatter
        inner, loc = self.inner, self.local
        sim = self.sim  # (constants a script may change between runs)
        if self.rank != 0 and sim.walls is not None and sim.walls.load.size:
            # the boundaries' running work sum goes on on rank 0 only: the sum over the
            # ranks at the call's end (:meth:`_sum_loads`) adds every rank's share once
            sim.walls.load[:, 6] = 0.0
        loc.gravity, loc.max_overlap = sim.gravity, sim.max_overlap
        loc.sphere_orientation = sim.sphere_orientation
        module = self.module
        inner.module = module
        flags = np.zeros(3, np.int64)
        out = np.zeros(3, np.int64)
        status = STATUS_OK
        rebuilds = 0
        skipped_before = self.skipped_migrations
        migrants_before = self.migrants
        worst_all = 0.0
        t_halo = t_mig = t_recut = t_wait = t_relist = 0.0
        recuts = 0
        work = 0.0  # this rank's seconds in the step kernels since a re-cut check
        t_work = 0.0  # (and in the whole call)
        clock = time.perf_counter
        t_start = clock()
        inner.diag[4] = 0.0
        inner.diag[5] = -1
        # this rank's last step passed the overlap limit (not yet voted on: the vote
        # travels with the next step's, so that ranks wait for each other once a step)
        late = 0
        rec = None
        h = self._native_handles()
        if h is not None:
            acc = np.zeros(3)
            flags6 = np.zeros(6, np.int64)
            statuses = np.zeros(0, np.uint8)
        s = 0
        since = 0  # (the step of the last re-cut check)
        while s < n:
            if rec is None:  # (the records hold the arrays: new ones after a rebuild)
                rec = inner.records()
                ctl, bodies, elems, pairs, wl, bnd = rec
                # (the step functions this call may run, their first compile in turn; a
                # rebuild's records are of the same types)
                self._compile_in_turn(module.rebuild, (*rec, inner.diag))
                if h is None:
                    self._compile_in_turn(module.ranked_pre_force,
                                          (dt, ctl, bodies, elems, bnd, frames, s))
                    self._compile_in_turn(module.ranked_forces,
                                          (dt, ctl, bodies, elems, pairs, wl, bnd, inner.diag))
            if h is not None:  # compiled steps until a rebuild, the end, or a failure
                hp = self._hp
                k = len(hp["requests"])
                if len(statuses) < k * h[4]:
                    statuses = np.zeros(k * int(h[4]), np.uint8)
                acc[:] = 0.0
                args = (s, n, dt, ctl, bodies, elems, pairs, wl, bnd, frames, inner.diag,
                        float(loc.max_overlap), hp["first"], not loc.plan.spheres_only,
                        hp["send_rows"], hp["send_rank"], hp["send_off"], hp["sbuf"],
                        hp["recv_rank"], hp["recv_off"], hp["rbuf"], hp["requests"],
                        statuses, h, flags6, acc)
                flags6[2] = late
                self._compile_in_turn(module.ranked_run, args)
                s, why = module.ranked_run(*args)
                late = int(flags6[2])
                work += float(acc[0])
                t_halo += float(acc[1])
                worst_all = max(worst_all, float(acc[2]))
                if why == module.RUN_DONE:
                    break
                if why == module.RUN_NAN:
                    status = STATUS_NAN
                    break
                if why == module.RUN_OVERLAP:
                    status = STATUS_OVERLAP
                    break
                if why == module.RUN_MPI_ERROR:
                    raise RuntimeError(f"MpiBackend: an MPI call failed in the compiled "
                                       f"step loop at step {s} on rank {self.rank}")
                rebuild = True  # (RUN_REBUILD: step s's pre-force part done, agreed)
            else:
                t0 = clock()
                need = int(module.ranked_pre_force(dt, ctl, bodies, elems, bnd, frames, s))
                work += clock() - t0
                flags[0] = need < 0
                flags[1] = need > 0
                flags[2] = late  # (the last step's overlap, voted with this step's answers)
                t0 = clock()
                comm.Allreduce(flags, out, op=MPI.MAX)
                t_halo += clock() - t0
                late = 0
                if out[2]:
                    status = STATUS_OVERLAP
                    break
                if out[0]:
                    status = STATUS_NAN
                    break
                rebuild = bool(out[1])
            if rebuild:
                t_work += work
                t0 = clock()
                cut = self._recut_in_call(s - since)
                recuts += int(cut)
                t_recut += clock() - t0
                work, since = 0.0, s
                t0 = clock()
                self._migrate(moved=cut)
                t1 = clock()
                inner.rebuild()  # (history of the carried entries merged by pair)
                rebuilds += 1
                t_relist += clock() - t1
                t_mig += clock() - t0
                rec = inner.records()
                ctl, bodies, elems, pairs, wl, bnd = rec
            else:  # (after a migration the ghosts came with it)
                t0 = clock()
                self._halo(bodies, elems)
                t_halo += clock() - t0
            t0 = clock()
            worst = module.ranked_forces(dt, ctl, bodies, elems, pairs, wl, bnd, inner.diag)
            work += clock() - t0
            s += 1
            worst_all = max(worst_all, worst)
            # (voted with the next step's answers: one wait a step for the other ranks)
            late = int(worst > loc.max_overlap)
        if status == STATUS_OK:  # the last step's overlap (every rank got here)
            t0 = clock()
            if int(comm.allreduce(late, op=MPI.MAX)):
                status = STATUS_OVERLAP
            t_wait += clock() - t0
        ran = s
        t_steps = time.perf_counter() - t_start
        t_work += work
        # the call's end: the boundary loads summed over the ranks; the whole state stays
        # on the ranks until the host needs it (:meth:`sync_host`: an output frame, a
        # flow event, a hook, the run's end)
        t0 = time.perf_counter()
        self._sum_loads()
        self._stale = True
        self.timing = {"steps": ran, "steps_s": t_steps, "halo_s": t_halo,
                       "migrate_s": t_mig, "gather_s": time.perf_counter() - t0,
                       "scatter_s": t_scatter, "owned": loc.n_owned,
                       "ghosts": int(loc.bodies.ghosts),
                       "halo_bytes_per_step": float(self._hp["sbuf"].nbytes)}
        self.timing["calls"] = 1
        self.timing["rebuilds"] = rebuilds
        self.timing["migrations_skipped"] = self.skipped_migrations - skipped_before
        self.timing["migrants"] = self.migrants - migrants_before
        self.timing["recuts"] = recuts
        self.timing["recut_s"] = t_recut
        self.timing["relist_s"] = t_relist  # (of migrate_s: the lists' rebuild)
        self.timing["work_s"] = t_work
        self.timing["wait_s"] = t_wait
        for k in ("calls", "steps", "rebuilds", "migrations_skipped", "migrants", "recuts",
                  "steps_s",
                  "work_s", "halo_s",
                  "wait_s", "migrate_s", "relist_s", "recut_s", "gather_s", "scatter_s"):
            self.totals[k] = self.totals.get(k, 0.0) + self.timing[k]
        best = comm.allreduce((float(inner.diag[4]), self.rank), op=MPI.MAXLOC)
        d = self.diag
        d[4] = max(d[4], best[0])
        # (the host element of the largest overlap: mapped by the rank that has it)
        d[5] = comm.bcast(self._host_element(int(inner.diag[5])) if self.rank == best[1]
                          else -1, root=best[1])
        d[1] = ran
        return StepResult(ran, status, rebuilds, float(best[0]), int(d[5]))

    def _compile_in_turn(self, fn: Any, args: tuple) -> None:
        """Compile step function ``fn`` for the types of ``args`` on rank 0 first, into
        numba's cache, then on the other ranks, which load it from there: a scene kind's
        first run on R ranks compiles each function once, not R times at once (R
        compilers sharing the cores, every one writing the cache). Collective: called
        where every rank calls ``fn`` next; at most once per function and process."""
        key = id(fn)
        if key in _COMPILED_IN_TURN:
            return
        _COMPILED_IN_TURN[key] = fn  # (held: the id stays this function's)
        import numba

        sig = tuple(numba.typeof(a) for a in args)
        failed = None
        if self.rank == 0:
            try:
                fn.compile(sig)
            except Exception as exc:  # (the others fail alike; none waits forever)
                failed = exc
        self.comm.Barrier()
        if failed is not None:
            raise failed
        if self.rank != 0:
            fn.compile(sig)

    def _native_handles(self) -> np.ndarray | None:
        """The MPI handles for :func:`dpm.kernels.step.ranked_run`, or None: the Python
        loop (:func:`dpm.parallel.native.handles`; ``loop``)."""
        from . import native

        h, why = native.handles(self.comm)
        if h is None and self.loop == "compiled":
            raise ParameterError(f"MpiBackend(loop='compiled'): this MPI cannot be called "
                                 f"from compiled code here: {why}; allowed: loop='auto'")
        self.loop_used = "python" if h is None else "compiled"
        return h

    # ------------------------------------------------------------------ scatter
    def _layer(self) -> float:
        sim = self.sim
        reach = float(getattr(getattr(sim, "plan", None), "reach", 0.0))  # (JKR's |d_c|)
        return 2.0 * float(sim.elements.radius.max()) + float(sim.skin) + reach

    def _body_extent(self, estart: np.ndarray, offset: np.ndarray,
                     radius: np.ndarray) -> np.ndarray:
        """Largest distance of a body's element surfaces from its centre, less the
        scene's r_max (0 for a sphere of radius r_max)."""
        if len(offset) == 0:
            return np.zeros(len(estart) - 1)
        r_max = float(self.sim.elements.radius.max())
        reach = np.linalg.norm(offset, axis=1) + radius - r_max
        return np.maximum.reduceat(reach, estart[:-1].clip(max=len(reach) - 1)) \
            if len(estart) > 1 else np.zeros(0)

    def _reach(self, estart: np.ndarray, offset: np.ndarray, radius: np.ndarray
               ) -> np.ndarray:
        """How near another rank's box a body's centre must lie for that rank's next
        lists to need it as a ghost: 2 r_max + skin (+ an interaction range beyond
        touching) + its own extent + the largest extent in the scene (an element of the
        other rank's body may reach out of that box by as much)."""
        return self._layer() + self._body_extent(estart, offset, radius) + self._ext_max

    def _margin(self) -> float:
        """The ghost layers' extra thickness chosen at a migration (``ghost_margin``)."""
        return float(self.sim.skin) if self.ghost_margin is None else self.ghost_margin

    def _period(self) -> np.ndarray:
        per = self.sim.period
        return np.zeros(6) if per is None else np.asarray(per, np.float64)

    def _cut(self, pool_pos: np.ndarray, weight: np.ndarray) -> None:
        """A new cut unless the current one is kept (after a host change, while the ranks'
        step times stay within ``rebalance``)."""
        if self.fixed_boxes is not None:
            if len(self.fixed_boxes) != self.ranks:
                raise ParameterError(f"MpiBackend(): {len(self.fixed_boxes)} boxes for "
                                     f"{self.ranks} ranks; give one box per rank")
            self.boxes = self.fixed_boxes
        elif self.boxes is None:
            self.boxes = dec.bisect(pool_pos, weight, self.ranks, self._layer())

    def _cost(self) -> tuple[np.ndarray, Entries]:
        """Each body's modelled cost (``TOUCHING_WEIGHT``) and the host's pair entries."""
        sim = self.sim
        b, e = sim.bodies, sim.elements
        pairs = Entries.of(sim.contacts, copy=False)  # (no history read)
        nb = len(b)
        weight = np.diff(b.element_start).astype(float)
        act = (pairs.act != 0).astype(float)
        tw = self.TOUCHING_WEIGHT
        weight += tw * (np.bincount(e.owner[pairs.i], act, minlength=nb)
                        + np.bincount(e.owner[pairs.j], act, minlength=nb))
        wc = sim.wall_contacts
        rows = np.repeat(np.arange(len(wc.start) - 1), np.diff(wc.start))
        weight += 2.0 * tw * np.bincount(
            e.owner[rows], (wc.active[:wc.count] != 0).astype(float), minlength=nb)
        return weight, pairs

    def _cost_imbalance(self) -> float:
        """Largest over mean of the ranks' modelled cost under the current cut."""
        weight, _ = self._cost()
        owner = dec.owner_of(self.sim.bodies.position, self.boxes)
        return dec.imbalance(np.bincount(owner, weights=weight, minlength=self.ranks))

    def _scatter(self) -> None:
        """Cut the domain (if due) and take this rank's rows from the whole host state."""
        sim = self.sim
        b, e = sim.bodies, sim.elements
        c, wc = sim.contacts, sim.wall_contacts
        nb = len(b)
        weight, pairs = self._cost()
        eb_i, eb_j = e.owner[pairs.i], e.owner[pairs.j]
        self._cut(b.position, weight)
        # ghosts of rank k: every body within the ghost layer of k's box (with the
        # margin), and every body with a listed partner owned by k
        ext = self._body_extent(b.element_start, e.offset, e.radius)
        self._ext_max = max(float(ext.max()), 0.0) if len(ext) else 0.0
        reach = self._layer() + ext + self._ext_max + self._margin()
        owner, ghost_on = owner_and_near(b.position, self.boxes, sim.period, reach)
        cross = owner[eb_i] != owner[eb_j]
        ghost_on[owner[eb_i[cross]], eb_j[cross]] = True
        ghost_on[owner[eb_j[cross]], eb_i[cross]] = True
        ghost_on[owner, np.arange(nb)] = False
        pool = Pool.of(b, e, self.aux, self.vf, self.wf, c, wc)
        self._place(pool, owner, ghost_on, b.id)
        self._host_copy = tuple(np.array(a) for a in (
            b.position, b.velocity, b.angular_velocity, b.orientation, b.mass))

    def _place(self, pool: Pool, owner: np.ndarray, ghost_on: np.ndarray,
               ids: np.ndarray) -> None:
        """Assemble this rank's scene from ``pool``: owned rows (``owner`` == this rank)
        in id order, then ghosts grouped by owner rank, each group in id order; and the
        halo plan (which owned rows go to which rank, which ghost rows come from which)."""
        me, P = self.rank, self.ranks
        by_id = np.argsort(ids, kind="stable")
        mine = by_id[owner[by_id] == me]
        groups = []
        ranges = {}
        first = len(mine)
        for s in range(P):
            if s == me:
                continue
            g = by_id[(owner[by_id] == s) & ghost_on[me, by_id]]
            if len(g):
                ranges[s] = (first, len(g))
                first += len(g)
                groups.append(g)
        ghosts = np.concatenate(groups) if groups else np.zeros(0, np.int64)
        if self.local is None:
            self.local = LocalScene(self.sim)
            self.inner = CpuBackend(threads=self.threads, force_pass=self.force_pass)
            self.inner.module = self.module
        loc = self.local
        loc.plan, loc.walls = self.sim.plan, self.sim.walls
        aux, vf, wf = assemble(loc, pool, mine, ghosts)
        if loc.plan.spheres_only:
            from ..population import share_sphere_arrays

            share_sphere_arrays(loc)
        inner = self.inner
        inner.sim = loc
        inner.aux = aux
        inner._scratch()
        inner.vf[:] = vf
        inner.wf[:] = wf
        # the halo plan: owned rows (local index, id order) sent to each rank
        sends = {}
        for k in range(P):
            if k != me:
                rows = np.flatnonzero(ghost_on[k, mine])
                if len(rows):
                    sends[k] = rows.astype(np.int64)
        self._halo_plan(sends, ranges, len(mine))

    def _halo_plan(self, sends: dict, ranges: dict, n_own: int) -> None:
        """The halo's messages as flat arrays (what :func:`dpm.kernels.step.ranked_run`
        takes): owned rows to send, rank by rank (``send_off`` delimits them), one buffer
        row each; ghost rows ``n_own ..`` received rank by rank (``recv_off``) into one
        buffer whose rows are the ghost rows in order."""
        z = np.zeros(0, np.int64)
        s_rank = np.array(sorted(sends), np.int64)
        s_rows = np.concatenate([sends[k] for k in s_rank]) if len(s_rank) else z
        s_off = np.concatenate([[0], np.cumsum([len(sends[k]) for k in s_rank])])
        r_rank = np.array(sorted(ranges), np.int64)
        firsts = [ranges[k][0] for k in r_rank]
        if firsts != sorted(firsts) or (firsts and firsts[0] != n_own):
            raise RuntimeError("MpiBackend: ghost groups are not in rank order")
        r_off = np.concatenate([[0], np.cumsum([ranges[k][1] for k in r_rank])])
        # which owned rows each rank holds as ghosts (what :meth:`_ghosts_cover` checks)
        sent = np.zeros((self.ranks, n_own), np.bool_)
        for k, rows in sends.items():
            sent[k, rows] = True
        self._sent = sent
        self._hp = {"send_rows": s_rows.astype(np.int64), "send_rank": s_rank,
                    "send_off": s_off.astype(np.int64),
                    "sbuf": np.empty((len(s_rows), HALO_WIDTH)),
                    "recv_rank": r_rank, "recv_off": r_off.astype(np.int64),
                    "rbuf": np.empty((int(r_off[-1]), HALO_WIDTH)),
                    # (one more: the compiled loop's vote waits with the messages)
                    "requests": np.zeros(len(s_rank) + len(r_rank) + 1, np.intp),
                    "first": n_own}

    # ------------------------------------------------------------------ halo
    def _halo(self, bodies: Any = None, elems: Any = None) -> None:
        """Owners send what the force pass reads of their ghosts (after the pre-force
        part: position, quaternion, the velocities the forces see) to the ranks that hold
        them; ghosts take it and place their elements. ``bodies``, ``elems``: the
        current records (taken here if not given)."""
        from mpi4py import MPI

        loc, inner = self.local, self.inner
        if bodies is None:
            _, bodies, elems, *_ = inner.records()
        hp = self._hp
        sbuf, rbuf = hp["sbuf"], hp["rbuf"]
        # (the scene's step module's halo functions: cached with it)
        pack, unpack = self.module.ranked_halo_pack, self.module.ranked_halo_unpack
        place = not loc.plan.spheres_only
        self._compile_in_turn(pack, (hp["send_rows"], bodies, sbuf))
        self._compile_in_turn(unpack, (hp["first"], rbuf, bodies, elems, place))
        pack(hp["send_rows"], bodies, sbuf)
        reqs = []
        off = hp["recv_off"]
        for m, s in enumerate(hp["recv_rank"]):
            reqs.append(self.comm.Irecv([rbuf[off[m]:off[m + 1]], MPI.DOUBLE],
                                        source=int(s), tag=HALO_TAG))
        off = hp["send_off"]
        for k, d in enumerate(hp["send_rank"]):
            reqs.append(self.comm.Isend([sbuf[off[k]:off[k + 1]], MPI.DOUBLE],
                                        dest=int(d), tag=HALO_TAG))
        MPI.Request.Waitall(reqs)
        unpack(hp["first"], rbuf, bodies, elems, place)

    # ------------------------------------------------------------------ re-cut in a call
    def _owned_parts(self) -> tuple[np.ndarray, np.ndarray]:
        """This rank's owned bodies' elements and touching contact sides (a boundary
        contact counts twice), from its own lists: the two parts of the modelled cost
        (:meth:`_cost` counts them on the host)."""
        loc = self.local
        b, e, c = loc.bodies, loc.elements, loc.contacts
        n_own, ne = loc.n_owned, len(e.owner)
        act = (c.active[:c.count] != 0).astype(float)
        row = np.repeat(np.arange(ne), np.diff(c.start[:ne + 1]))
        per_elem = np.zeros(ne)  # (bincount of nothing is an int array)
        per_elem += np.bincount(row, act, minlength=ne)[:ne]
        per_elem += np.bincount(c.key[:c.count], act, minlength=ne)[:ne]
        w = loc.wall_contacts
        per_elem += 2.0 * np.bincount(np.repeat(np.arange(ne), np.diff(w.start[:ne + 1])),
                                      (w.active[:w.count] != 0).astype(float),
                                      minlength=ne)[:ne]
        touching = np.bincount(e.owner, weights=per_elem, minlength=len(b))[:n_own]
        elements = np.diff(b.element_start[:n_own + 1]).astype(float)
        return elements, touching

    def _owned_cost(self) -> np.ndarray:
        """This rank's owned bodies' modelled cost from its own lists."""
        elements, touching = self._owned_parts()
        return elements + self.TOUCHING_WEIGHT * touching

    def _recut_in_call(self, steps: int) -> bool:
        """At a list rebuild inside a call (collective): cut the domain again when the
        ranks' modelled costs differ by more than ``rebalance``, so that a long call keeps
        its ranks busy while the bodies move (a hopper emptying, a bed sliding). Two floats
        per rank decide; a re-cut gathers each rank's owned centres and costs (four floats
        per body, not the whole state) and bisects them on every rank alike; the migration
        that follows moves the bodies to their new owners. Returns whether it cut."""
        if self.fixed_boxes is not None or steps == 0:
            return False
        from mpi4py import MPI

        comm, P = self.comm, self.ranks
        elements, touching = self._owned_parts()
        n_own = self.local.n_owned
        tw = self.TOUCHING_WEIGHT
        weight = elements + tw * touching
        mine = np.array([elements.sum() + tw * touching.sum(), n_own])
        every = np.empty((P, 2))
        comm.Allgather([mine, MPI.DOUBLE], [every, MPI.DOUBLE])
        due = dec.imbalance(every[:, 0]) > self.rebalance
        if not due:
            return False
        rows = np.empty((n_own, 4))
        rows[:, :3] = self.local.bodies.position[:n_own]
        rows[:, 3] = weight
        sizes = 4 * every[:, 1].astype(np.int64)
        allrows = np.empty((int(sizes.sum()) // 4, 4))
        comm.Allgatherv([rows, MPI.DOUBLE],
                        [allrows, mpi_counts(sizes, "re-cut"), MPI.DOUBLE])
        self.boxes = dec.bisect(allrows[:, :3], allrows[:, 3], P, self._layer())
        return True

    # ------------------------------------------------------------------ migration
    def _migrate(self, moved: bool = False) -> None:
        """At a list rebuild: owned bodies whose centre left the box go to their new
        owner with the history of the contacts they touch; the ghost layers are chosen
        again (the old owner sends a migrant's ghost copies on its new owner's behalf).
        Unless the boxes ``moved`` (a re-cut), a rebuild at which the ghost layers held
        still cover what the new lists need keeps every row where it is
        (:meth:`_ghosts_cover`)."""
        loc, inner = self.local, self.inner
        me, P = self.rank, self.ranks
        b, e = loc.bodies, loc.elements
        n_own = loc.n_owned
        pos = b.position[:n_own]
        est = b.element_start
        reach = self._reach(est[:n_own + 1], e.offset[:est[n_own]], e.radius[:est[n_own]])
        if not moved and self._ghosts_cover(pos, reach):
            # (every body stays with its owner and every ghost layer held still covers
            # what the new lists need, on every rank: the ghosts take their owners'
            # state as at any step, the rows stay)
            self._halo()
            self.skipped_migrations += 1
            return
        new_owner, near = owner_and_near(pos, self.boxes, self.sim.period,
                                         reach + self._margin())
        self.migrants += int(np.count_nonzero(new_owner != me))
        # touching entries only: the lists are rebuilt right after, and an entry that does
        # not touch has no history to carry (it was cleared when the pair parted)
        pool = Pool.of(b, e, inner.aux, inner.vf, inner.wf, loc.contacts, loc.wall_contacts,
                       active_only=True)
        # to each rank: the bodies it will own or hold as ghosts; with those it will own,
        # the touching entries (pairs and boundary entries) of their elements
        act_p, act_w = pool.pairs.act != 0, pool.walls.act != 0
        eo = e.owner
        ship = [None] * P
        for k in range(P):
            if k == me:
                continue
            rows = np.flatnonzero((new_owner == k) | near[k])
            if not len(rows):
                continue
            mig = rows[new_owner[rows] == k]
            if len(mig):
                is_mig = np.zeros(len(b), bool)
                is_mig[mig] = True
                sel_p = np.flatnonzero(act_p & (is_mig[eo[pool.pairs.i]]
                                                | is_mig[eo[pool.pairs.j]]))
                sel_w = np.flatnonzero(act_w & is_mig[eo[pool.walls.i]])
            else:
                sel_p = sel_w = np.zeros(0, np.int64)
            ship[k] = (rows, sel_p, sel_w)
        recv = self._exchange_migrants(pool, eo, new_owner, near, ship)
        ids = b.id
        # the pool: this rank's rows, then the rows received that it does not hold; a row
        # it holds (a ghost) takes the received state (its owner's, after the pre-force
        # part: ghosts are not integrated here, and no halo ran this step)
        top = max([int(ids.max()) if len(ids) else 0]
                  + [int(m["bodies"]["id"].max()) for m in recv if m is not None]) + 1
        have = np.zeros(top, bool)
        have[ids] = True
        local_row = np.full(top, -1, np.int64)
        local_row[ids] = np.arange(len(ids))
        extra = []
        for msg in recv:
            if msg is None:
                continue
            fresh = ~have[msg["bodies"]["id"]]
            held = np.flatnonzero(~fresh)
            if len(held):
                self._take_state(pool, local_row[msg["bodies"]["id"][held]], msg, held)
            if np.any(fresh):
                rows = np.flatnonzero(fresh)
                part = {"bodies": {k: take(v, rows) for k, v in msg["bodies"].items()},
                        "elements": None, "aux": take(msg["aux"], rows),
                        "vf": take(msg["vf"], rows), "wf": take(msg["wf"], rows)}
                est_m = np.concatenate([[0], np.cumsum(msg["counts"])])
                er, counts = element_rows(est_m, rows)
                part["counts"] = counts
                part["elements"] = {k: take(v, er) for k, v in msg["elements"].items()}
                extra.append(part)
                have[part["bodies"]["id"]] = True
        pool.extend(extra)
        pids = pool.ids()
        n_pool = len(pids)
        row_of = np.full(top, -1, np.int64)
        row_of[pids] = np.arange(n_pool)
        owner = np.full(n_pool, -1, np.int64)
        ghost_on = np.zeros((P, n_pool), bool)
        owner[:n_own] = new_owner
        ghost_on[:, :n_own] = near
        migrants = []
        shipped_p, shipped_w = [], []
        for msg in recv:
            if msg is None:
                continue
            r = row_of[msg["bodies"]["id"]]
            owner[r] = msg["owner"]
            ghost_on[:, r] |= msg["near"]
            mine_now = r[msg["owner"] == me]
            if len(mine_now):  # (the sender shipped their contacts)
                migrants.append(mine_now)
                shipped_p.append(msg["pairs"])
                shipped_w.append(msg["walls"])
        # pool element index of (body id, element within the body)
        pest = pool.estart

        def elem(idv, subv):
            rows = np.where(idv < top, row_of[np.minimum(idv, top - 1)], -1)
            ok = rows >= 0
            return np.where(ok, pest[np.maximum(rows, 0)] + subv, -1), ok

        if migrants:
            is_mig = np.zeros(n_pool, bool)
            is_mig[np.concatenate(migrants)] = True
            pown = np.repeat(np.arange(n_pool), np.diff(pest))
            pp = pool.pairs
            pool.pairs = pp.where(~(is_mig[pown[pp.i]] | is_mig[pown[pp.j]]))
            pw = pool.walls
            pool.walls = pw.where(~is_mig[pown[pw.i]])
            width = pp.hist.shape[1]
            new_p, new_w = [], []
            for ia, sa, ib, sb, hist, act in shipped_p:
                ea, oka = elem(ia, sa)
                eb, okb = elem(ib, sb)
                ok = oka & okb
                new_p.append(Entries(ea[ok], eb[ok], hist[ok], act[ok]))
            for ia, sa, key, hist, act in shipped_w:
                ea, ok = elem(ia, sa)
                new_w.append(Entries(ea[ok], key[ok].astype(np.int64), hist[ok], act[ok]))
            # shipped entries first: the owner's history wins over a ghost copy's
            pool.pairs = Entries.cat(new_p + [pool.pairs], width)
            pool.walls = Entries.cat(new_w + [pool.walls], width)
        # rows no rank needs here any more drop out (old ghosts not chosen again)
        self._place(pool, owner, ghost_on, pids)

    def _ghosts_cover(self, pos: np.ndarray, reach: np.ndarray) -> bool:
        """Whether a list rebuild can keep every body where it is (collective): on every
        rank, no owned body lies farther than the margin (``ghost_margin``) outside the
        rank's box, and every owned body within ``reach`` of another rank's box, widened
        by how far that rank's own bodies lie outside it, is in that rank's ghost layer
        already. Then the new lists find every pair they need among the rows held: a pair
        of bodies a (here) and b (owned by rank r, at most ``strays[r]`` outside r's box)
        within 2 r_max + skin + both extents has a within ``reach[a] + strays[r]`` of r's
        box (2 r_max + skin + an interaction range beyond touching, as JKR's, + both
        extents: :meth:`_reach`). The layers were chosen with the margin, so a bed that
        barely moves keeps them for many rebuilds."""
        from mpi4py import MPI

        from ..kernels.domain import stray_distance, uncovered_ghosts

        sent = getattr(self, "_sent", None)
        me, P = self.rank, self.ranks
        per = self._period()
        boxes = np.ascontiguousarray(self.boxes, np.float64)
        # (without periodic images: a box open to infinity along a periodic axis holds an
        # image of every centre, and ownership is by the plain position, so a body that
        # wrapped to the far end must count as strayed and migrate; the plain distance is
        # never below the nearest image's, so the covering argument holds with it)
        mine = np.array([stray_distance(pos, boxes[me], np.zeros(6)) if len(pos) else 0.0])
        strays = np.empty(P)
        self.comm.Allgather([mine, MPI.DOUBLE], [strays, MPI.DOUBLE])
        ok = (sent is not None and sent.shape == (P, len(pos))
              and bool(np.all(strays <= self._margin())))
        if ok and len(pos):
            ok = uncovered_ghosts(np.ascontiguousarray(pos), boxes, per,
                                  np.ascontiguousarray(reach, np.float64), strays, me,
                                  sent) == 0
        return bool(self.comm.allreduce(int(ok), op=MPI.MIN))

    @staticmethod
    def _take_state(pool: Pool, rows: np.ndarray, msg: dict, src: np.ndarray) -> None:
        """Pool body ``rows`` (with their elements) take the dynamic state of message rows
        ``src`` (the same bodies)."""
        for k in ("position", "velocity", "orientation", "angular_velocity", "force",
                  "torque"):
            pool.bodies[k][rows] = take(msg["bodies"][k], src)
        for name in ("aux", "vf", "wf"):
            getattr(pool, name)[rows] = take(msg[name], src)
        er, _ = element_rows(pool.estart, rows)
        est_m = np.concatenate([[0], np.cumsum(msg["counts"])])
        mr, _ = element_rows(est_m, src)
        for k in ("position", "reference"):
            pool.elements[k][er] = take(msg["elements"][k], mr)

    def _exchange_migrants(self, pool: Pool, e_owner: np.ndarray, owner: np.ndarray,
                           near: np.ndarray, ship: list) -> list:
        """Send each rank its migration message (:class:`dpm.parallel.messages.Migration`:
        the counts by ``Ialltoall``, packed meanwhile, then floats and ints by
        ``Ialltoallv``) and return the received ones, unpacked (None: none)."""
        from mpi4py import MPI

        comm = self.comm
        mig = Migration(pool, self.ranks)
        counts = mig.counts(pool, ship)
        rcounts = np.empty_like(counts)
        req = comm.Ialltoall([counts, MPI.INT64_T], [rcounts, MPI.INT64_T])
        fbuf, ibuf = mig.pack(pool, e_owner, owner, near, ship, counts)
        req.Wait()
        fs, is_ = mig.sizes(counts)
        rfs, ris = mig.sizes(rcounts)
        rf, ri = np.empty(int(rfs.sum())), np.empty(int(ris.sum()), np.int64)
        MPI.Request.Waitall([
            comm.Ialltoallv([fbuf, mpi_counts(fs, "migration"), MPI.DOUBLE],
                            [rf, mpi_counts(rfs, "migration"), MPI.DOUBLE]),
            comm.Ialltoallv([ibuf, mpi_counts(is_, "migration"), MPI.INT64_T],
                            [ri, mpi_counts(ris, "migration"), MPI.INT64_T])])
        return mig.unpack(rcounts, rf, ri)

    # ------------------------------------------------------------------ gather
    def _gather(self) -> None:
        """Every rank's owned rows (state, integrator rows, element references, contact
        entries whose first element it owns) into the whole host state on every rank."""
        sim = self.sim
        loc, inner = self.local, self.inner
        b, e = loc.bodies, loc.elements
        no = loc.n_owned
        est = b.element_start
        ne_own = int(est[no])
        hb, he = sim.bodies, sim.elements
        id_row = self._id_rows(hb.id)
        grow_l = id_row[b.id]                              # host row of each local body
        sub = np.arange(len(e.owner)) - est[e.owner]
        gel = hb.element_start[grow_l[e.owner]] + sub      # host element of each element
        from mpi4py import MPI

        comm = self.comm
        lc, lw = loc.contacts, loc.wall_contacts
        if self._gather_scratch is None:
            self._gather_scratch = Scratch()
        msg = Gather(inner.aux.shape[1], not sim.plan.spheres_only, lc.history.shape[1],
                     lw.history.shape[1], self._gather_scratch)
        counts = np.array([no, ne_own, msg.reported(lc, gel, ne_own, True),
                           msg.reported(lw, gel, ne_own, False)], np.int64)
        allc = np.empty((self.ranks, 4), np.int64)
        comm.Allgather([counts, MPI.INT64_T], [allc, MPI.INT64_T])
        fs, is_ = msg.sizes(allc)
        fbuf, ibuf = msg.buffers(allc)
        fc, ic = mpi_counts(fs, "gather"), mpi_counts(is_, "gather")
        me = self.rank
        f0, i0 = fc[1][me], ic[1][me]
        # (this rank's message straight into its place in the received buffers)
        msg.pack({"position": b.position, "velocity": b.velocity,
                  "orientation": b.orientation, "angular_velocity": b.angular_velocity,
                  "force": b.force, "torque": b.torque, "aux": inner.aux, "vf": inner.vf,
                  "wf": inner.wf}, grow_l[:no],
                 {"reference": e.reference, "position": e.position}, gel[:ne_own], lc, lw,
                 gel, counts, fbuf[f0:f0 + fc[0][me]], ibuf[i0:i0 + ic[0][me]])
        MPI.Request.Waitall([comm.Iallgatherv(MPI.IN_PLACE, [fbuf, fc, MPI.DOUBLE]),
                             comm.Iallgatherv(MPI.IN_PLACE, [ibuf, ic, MPI.INT64_T])])
        host = {"position": hb.position, "velocity": hb.velocity,
                "orientation": hb.orientation, "angular_velocity": hb.angular_velocity,
                "force": hb.force, "torque": hb.torque, "aux": self.aux, "vf": self.vf,
                "wf": self.wf}
        pairs, walls = msg.unpack(allc, fbuf, ibuf, host,
                                  {"reference": he.reference, "position": he.position})
        width = sim.contacts.history.shape[1]
        if not len(pairs.i):  # (as an empty concatenation)
            pairs = Entries.empty(width)
        if not len(walls.i):
            walls = Entries.empty(width)
        pairs = orient_pairs(pairs, he.material, sim.plan)
        set_entries(sim.contacts, len(he), pairs)
        set_entries(sim.wall_contacts, len(he), walls)
        self.diag[6] = int(np.count_nonzero(sim.contacts.active[:sim.contacts.count])
                           + np.count_nonzero(sim.wall_contacts.active[
                               :sim.wall_contacts.count]))
        self._host_copy = tuple(np.array(a) for a in (
            hb.position, hb.velocity, hb.angular_velocity, hb.orientation, hb.mass))

    def _sum_loads(self) -> None:
        """The boundary loads (force, torque, work) of every rank's owned elements summed
        into each rank's (shared with the host's ``sim.walls.load``)."""
        from mpi4py import MPI

        load = self.sim.walls.load
        if load.size:
            total = np.empty_like(load)
            self.comm.Allreduce(np.ascontiguousarray(load), total, op=MPI.SUM)
            load[:] = total

    def _host_element(self, w: int) -> int:
        """The host element of this rank's element ``w`` (-1: none). The host's layout
        (ids, element starts) is current even while its state is stale."""
        e, b = self.local.elements, self.local.bodies
        if not 0 <= w < len(e.owner):
            return -1
        k = int(e.owner[w])
        hb = self.sim.bodies
        row = np.flatnonzero(hb.id == b.id[k])
        if not len(row):
            return -1
        return int(hb.element_start[row[0]] + w - b.element_start[k])

    # ------------------------------------------------------------------ the host state
    @property
    def host_stale(self) -> bool:
        """Whether ``sim.bodies`` and the contact lists are older than the ranks' state
        (the calls since the last :meth:`sync_host`)."""
        return self._stale

    def sync_host(self) -> None:
        """Gather the ranks' state into the host containers if calls ran since the last
        gather (collective: the run loop calls it on every rank at the same points,
        before anything reads or changes the host state, and at a run's end). A call
        ends without it, so a run without output, flow events or hooks between its
        calls gathers once, at its end (HOOMD-blue's snapshot taken on demand, the same
        idea)."""
        if not self._stale:
            return
        t0 = time.perf_counter()
        self._stale = False
        self._gather()
        took = time.perf_counter() - t0
        for figures in (self.timing, self.totals):
            figures["gather_s"] = figures.get("gather_s", 0.0) + took
            figures["gathers"] = figures.get("gathers", 0) + 1

    def max_speed(self) -> tuple[int, float]:
        """(host row, speed) of the fastest body; over the ranks' owned bodies while the
        host is stale (a non-finite velocity anywhere gives inf)."""
        if not self._stale:
            return super().max_speed()
        from mpi4py import MPI

        from ..diagnosis import fastest_body

        loc = self.local
        no = loc.n_owned
        k, speed = fastest_body(loc.bodies.velocity[:no]) if no else (0, 0.0)
        speed = float(speed) if np.isfinite(speed) else np.inf
        best, who = self.comm.allreduce((speed, self.rank), op=MPI.MAXLOC)
        ident = self.comm.bcast(int(loc.bodies.id[k]) if no else -1, root=who)
        row = np.flatnonzero(self.sim.bodies.id == ident)
        return (int(row[0]) if len(row) else 0), best

    def guard_hits(self, nonfinite: bool, box: np.ndarray | None) -> bool:
        """Whether the run-time guards (:func:`dpm.guards.check`) would find anything on
        the ranks' owned bodies: a non-finite state value (``nonfinite``), a centre
        outside ``box`` (None: not asked). Collective; read from the ranks' state, so a
        stale host need not be gathered to learn that all is well."""
        from mpi4py import MPI

        from ..guards import STATE_ARRAYS

        b, no = self.local.bodies, self.local.n_owned
        hit = False
        if nonfinite:
            hit = not all(np.isfinite(getattr(b, name)[:no]).all() for name in STATE_ARRAYS)
        if box is not None and not hit:
            p = b.position[:no]
            hit = bool(np.any((p < box[0]) | (p > box[1])))
        return bool(self.comm.allreduce(int(hit), op=MPI.MAX))

    def energies(self, gravity: np.ndarray) -> tuple[float, float]:
        """(kinetic, mechanical) energy [J]: while the host is stale, of each rank's owned
        rows summed over the ranks (collective; the sum's order is not serial's, so the
        last bits may differ)."""
        if not self._stale:
            return super().energies(gravity)
        from mpi4py import MPI

        from ..guards import energies

        mine = energies(self.local.bodies, gravity, slice(0, self.local.n_owned))
        total = np.empty(2)
        self.comm.Allreduce(np.array(mine, float), total, op=MPI.SUM)
        return float(total[0]), float(total[1])

    def agree_any(self, flag: bool) -> bool:
        """Whether ``flag`` holds on any rank (collective): a decision that leads to a
        collective call (a per-step hook's gather) is taken alike on every rank."""
        if self.ranks == 1:
            return bool(flag)
        from mpi4py import MPI

        return bool(self.comm.allreduce(int(bool(flag)), op=MPI.MAX))

    def to_host(self) -> None:
        """The whole state into the host containers (:meth:`sync_host`)."""
        self.sync_host()

    def nan_count(self) -> int:
        self.sync_host()
        return super().nan_count()

    def _id_rows(self, ids: np.ndarray) -> np.ndarray:
        out = np.full(int(ids.max()) + 1 if len(ids) else 1, -1, np.int64)
        out[ids] = np.arange(len(ids))
        return out

    # ------------------------------------------------------------------ reductions
    def contact_count(self) -> int:
        self.sync_host()
        return int(self.diag[6])


__all__ = ["MpiBackend"]
