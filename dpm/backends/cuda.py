"""The CUDA backend: the state resident on an NVIDIA GPU, the step as kernel launches.

``dpm.Simulation(..., device="cuda")`` is the only change a script needs. Install with
``pip install 'dpm-granular[cuda]'`` (numba-cuda and the CUDA 12 libraries; a driver must be
present); without a GPU the kernels run on numba's CUDA simulator
(``NUMBA_ENABLE_CUDASIM=1``, slow: for tests).

Design (as :mod:`dpm.parallel.backend` for MPI):

- **Between kernel calls the host state is whole.** ``sim.bodies``, the elements, both
  contact lists (with their history) and the boundary table hold the scene, so the run
  loop's events (flow events, output, checkpoints, hooks, guards, diagnosis) run on the
  host as on the CPU backend, with the CPU kernels (prime, list rebuilds after a change of
  the population). A call uploads the state when the host changed it (or the host
  methods of this backend ran) and downloads it at its end; with ``sync_lists=False``
  the contact lists stay on the device between calls (for long runs of a scene without
  flow events, checkpoints or hooks that read contacts: only the bodies' state travels).
- **A step is a fixed sequence of launches** (:mod:`dpm.kernels.cuda_step`): frames of
  moving boundaries, the integrator's pre-force part per body, the rebuild decision (one
  thread), the rebuild kernels (each returns at once unless the decision asked for a
  rebuild: no host synchronisation to decide), the contact pass per element, the force
  sums and the post-force part per body, the loads and reductions, the step's end. The
  host reads the 16-float state once every ``poll`` steps (and at the call's end) for
  its status: a full list, a NaN position, an overlap beyond ``max_overlap``. After a
  status the remaining launches of the window return at once; a full list is grown and
  the step finished as on the CPU (``finish_step``), so results do not depend on where a
  run is split.
- **The same bits as the CPU's two-pass form** on the simulator: the kernels call the
  scene's own per-contact functions, the lists are the CPU lists entry for entry, and
  each body's sum adds the same rows in the same order. On a GPU, fused multiply-adds and
  the device's libm change the last bits (the contract's tolerances cover this).

Refused with a clear error: implicit integrators (their Newton iterations run on the
host) and contact laws that act at a separation (JKR). Float64 throughout.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..errors import ParameterError
from .base import STATUS_OK, STATUS_OVERFLOW, STATUS_WALL_OVERFLOW, StepResult
from .cpu import CpuBackend

INSTALL = "pip install 'dpm-granular[cuda]'"
_KERNELS: dict[tuple[str, bool], Any] = {}


def cuda_module() -> Any:
    """``numba.cuda``, checked: a clear error when numba-cuda, a driver or a GPU is
    missing (the simulator, ``NUMBA_ENABLE_CUDASIM=1``, needs neither)."""
    try:
        from numba import cuda
    except ImportError as exc:  # pragma: no cover (numba-cuda is in the test extra)
        raise ParameterError(
            "Simulation(device='cuda'): numba-cuda is not installed "
            f"({exc}); install it with {INSTALL}") from None
    if simulator():
        return cuda
    reason = ""
    try:
        ok = cuda.is_available()
    except Exception as exc:  # noqa: BLE001 (any driver error is reported as such)
        ok, reason = False, str(exc)
    if not ok:
        try:
            cuda.gpus  # noqa: B018 (raises the driver's own reason)
            cuda.detect()
        except Exception as exc:  # noqa: BLE001
            reason = reason or " ".join(str(exc).split())
        raise ParameterError(
            "Simulation(device='cuda'): no usable NVIDIA GPU"
            + (f" ({reason})" if reason else "")
            + f". It needs an NVIDIA driver and GPU and the CUDA libraries ({INSTALL}); "
            "without a GPU, NUMBA_ENABLE_CUDASIM=1 runs the kernels on numba's CUDA "
            "simulator (slow: for tests), or use device='cpu'")
    return cuda


def simulator() -> bool:
    """Whether numba's CUDA simulator is on (``NUMBA_ENABLE_CUDASIM=1``, read by numba at
    import)."""
    try:
        from numba.cuda import config
    except ImportError:  # pragma: no cover
        return os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"
    return bool(config.ENABLE_CUDASIM)


class _Launch:
    """A kernel with its launch configuration, applied at each call (the simulator's
    ``kernel[grid, block]`` configures the kernel object itself, not a copy)."""

    __slots__ = ("kernel", "grid", "block")

    def __init__(self, kernel: Any, grid: int, block: int) -> None:
        self.kernel, self.grid, self.block = kernel, grid, block

    def __call__(self, *args: Any) -> None:
        self.kernel[self.grid, self.block](*args)


def _pow2(n: int) -> int:
    m = 64
    while m < n:
        m *= 2
    return m


class CudaBackend(CpuBackend):
    """State and step on an NVIDIA GPU (numba-cuda), host events on the CPU.

    Parameters
    ----------
    threads : int, optional
        Threads of the host-side CPU kernels (prime, rebuilds after population changes).
    sync_lists : bool
        Download the contact lists (and their history) at the end of every call (default)
        so that any host event may read or change them; False keeps them on the device
        between calls and downloads only the bodies' state (scenes without flow events,
        checkpoints or hooks that touch contacts; :meth:`to_host` brings them back).
    poll : int
        Steps between reads of the device status (one 128-byte copy each); a status
        stops the steps launched after it from doing anything.
    host_gate : bool, optional
        Read the rebuild decision on the host every step and launch the rebuild kernels
        only when it asks for them (one 128-byte read per step instead of ~27 empty
        launches; default: on the simulator only). Same results either way.
    """

    universal_ok = False  # (its kernels call functions of the scene's own module)
    one_thread_ok = False  # (one module for its host parts and device functions)

    name = "cuda"
    #: seconds of steps the run loop aims at per call (the host state travels once per
    #: call: longer calls than the CPU's 0.1 s)
    call_aim = 0.5

    def __init__(self, threads: int | None = None, sync_lists: bool = True,
                 poll: int = 64, host_gate: bool | None = None) -> None:
        if not (isinstance(poll, int) and poll >= 1):
            raise ParameterError(f"CudaBackend(): poll={poll!r} must be an integer >= 1")
        self._setup(cuda_module(), threads, sync_lists, poll)
        if host_gate is not None:
            self.host_gate = bool(host_gate)

    def _setup(self, cuda: Any, threads: int | None, sync_lists: bool, poll: int) -> None:
        self.cuda = cuda
        super().__init__(threads=threads, force_pass="two_pass")
        self.sync_lists = bool(sync_lists)
        self.poll = poll
        self.simulator = simulator()
        self._dev: dict[str, Any] | None = None
        self._snapshot: tuple | None = None
        self._lists_on_device = False
        self._grown: dict[str, int] = {}
        #: read the rebuild decision on the host and launch the rebuild kernels only when
        #: it asks for them (the simulator, where every launched thread costs a Python
        #: thread; on a GPU the rebuild kernels return at once instead: no host sync)
        self.host_gate = self.simulator
        #: the simulator: compile the device functions for the CPU (``DPM_CUDASIM_COMPILED=1``)
        #: instead of running them as Python (the default: no compile, for small scenes)
        self.sim_compiled = os.environ.get("DPM_CUDASIM_COMPILED") == "1"
        #: threads per block (the simulator: fewer idle threads for small scenes)
        self.block = 32 if self.simulator else 128
        #: launches, transfers and times of the last call
        self.timing: dict[str, float] = {}

    def __getstate__(self) -> dict[str, Any]:
        if self._lists_on_device:  # (a checkpoint holds the whole state)
            self._pull_lists()
        state = super().__getstate__()
        state.update(cuda=None, _dev=None, _snapshot=None, _lists_on_device=False,
                     _args=None, _frame_kernel=None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.cuda = cuda_module()

    # ------------------------------------------------------------------ host changes
    def attach(self, sim: Any) -> None:
        if sim.integrator.implicit:
            raise ParameterError(f"Simulation(device='cuda'): the implicit "
                                 f"{sim.integrator.name} integrator is not supported on "
                                 "the GPU (its Newton iterations run on the host); choose "
                                 "an explicit one")
        if float(getattr(sim.plan, "reach", 0.0)) > 0.0:
            raise ParameterError("Simulation(device='cuda'): a contact law acts at a "
                                 "separation (JKR), which the GPU step does not support yet; "
                                 "run it on the CPU")
        if not self.sync_lists and (sim.inlets or sim.outlets):
            raise ParameterError("CudaBackend(sync_lists=False): the scene has inlets or "
                                 "outlets, whose events change the contact lists on the "
                                 "host; use sync_lists=True (the default)")
        self._pull_lists()
        super().attach(sim)
        self._dev = None

    def _pull_lists(self) -> None:
        """Lists kept on the device (``sync_lists=False``) back to the host before a host
        method reads them."""
        if self._lists_on_device and self._dev is not None:
            self._download(lists=True)
        self._lists_on_device = False

    def rebuild(self) -> None:
        self._pull_lists()
        super().rebuild()
        self._dev = None

    def prime(self) -> None:
        self._pull_lists()
        super().prime()
        self._dev = None

    def population_changed(self) -> None:
        super().population_changed()
        self._dev = None

    def keep_bodies(self, keep_b: np.ndarray) -> None:
        super().keep_bodies(keep_b)
        self._dev = None

    def permute_bodies(self, order: np.ndarray) -> None:
        super().permute_bodies(order)
        self._dev = None

    def _host_unchanged(self) -> bool:
        """Whether the host state is what the last call left (a script or hook may
        have changed the bodies between calls, a boundary switch the search grids)."""
        if self._dev is None or self._snapshot is None:
            return False
        b, w = self.sim.bodies, self.sim.walls
        now = (b.position, b.velocity, b.angular_velocity, b.orientation, b.mass, w.kind,
               w.par, w.grid_int)
        return all(a.shape == c.shape and np.array_equal(a, c)
                   for a, c in zip(now, self._snapshot, strict=True))

    def _take_snapshot(self) -> None:
        b, w = self.sim.bodies, self.sim.walls
        self._snapshot = tuple(a.copy() for a in (
            b.position, b.velocity, b.angular_velocity, b.orientation, b.mass, w.kind, w.par,
            w.grid_int))

    # ------------------------------------------------------------------ transfers
    def kernels(self) -> Any:
        """The device kernels of the scene's step module (compiled at first launch)."""
        python = self.simulator and not self.sim_compiled
        key = (self.module.__name__, self.simulator, python)
        if key not in _KERNELS:
            from ..kernels.cuda_step import make_kernels

            _KERNELS[key] = make_kernels(self.module, self.simulator, python)
        return _KERNELS[key]

    def _upload(self) -> None:
        """The whole state to the device, with the scratch arrays of the rebuild."""
        cuda = self.cuda
        ctl, bodies, elems, pairs, walls, bnd = self.records()
        sim = self.sim
        dev: dict[str, Any] = {}

        def put(name: str, a: np.ndarray) -> None:
            dev[name] = cuda.to_device(np.ascontiguousarray(a))

        for f in bodies._fields:
            put("b_" + f, getattr(bodies, f))
        for f in elems._fields:
            if f == "pos" and elems.pos is bodies.pos or (
                    f == "pos" and np.shares_memory(elems.pos, bodies.pos)):
                dev["e_pos"] = dev["b_pos"]  # (single spheres: the bodies' positions)
                continue
            put("e_" + f, getattr(elems, f))
        c, wc = sim.contacts, sim.wall_contacts
        for f in pairs._fields:
            put("nl_" + f, getattr(pairs, f))
        if len(pairs.t_pair) < c.capacity:  # (the two-pass form always has them)
            put("nl_t_pair", np.zeros(c.capacity, pairs.key.dtype))
        for f in walls._fields:
            put("wl_" + f, getattr(walls, f))
        for f in bnd._fields:
            put("w_" + f, getattr(bnd, f))
        put("gravity", np.asarray(ctl.gravity, float))
        put("period", np.asarray(ctl.period, float))
        put("pair_model", ctl.pair_model)
        put("pair_params", ctl.pair_params)
        n = len(sim.elements)
        self._scratch_lists(dev, c.capacity, wc.capacity, n)
        m = _pow2(2 * max(n, 1))
        dev["mask"] = m - 1
        dev["cells"] = cuda.device_array((n, 3), np.int64)
        dev["bucket"] = cuda.device_array(n, np.int64)
        dev["bucket_count"] = cuda.device_array(m, np.int64)
        dev["bucket_start"] = cuda.device_array(m + 1, np.int64)
        dev["cursor"] = cuda.device_array(max(m, n) + 1, np.int64)
        dev["order"] = cuda.device_array(max(n, 1), np.int32)
        dev["counts"] = cuda.device_array(max(n, 1), np.int64)
        dev["sums"] = cuda.device_array(max(m, n + 1) // 256 + 2, np.int64)
        dev["state"] = cuda.to_device(np.zeros(16))
        dev["speed"] = cuda.to_device(np.zeros(2))
        self._dev = dev
        self._lists_on_device = False
        self._take_snapshot()

    def _scratch_lists(self, dev: dict, cap: int, wcap: int, n: int) -> None:
        cuda = self.cuda
        h = dev["nl_hist"].shape[1]
        wh = dev["wl_hist"].shape[1]
        dev["new_start"] = cuda.device_array(n + 1, np.int64)
        dev["new_key"] = cuda.device_array(cap, dev["nl_key"].dtype)
        dev["new_hist"] = cuda.device_array((cap, h))
        dev["new_active"] = cuda.device_array(cap, np.uint8)
        dev["new_wstart"] = cuda.device_array(n + 1, np.int64)
        dev["new_w"] = cuda.device_array(wcap, dev["wl_key"].dtype)
        dev["new_whist"] = cuda.device_array((wcap, wh))
        dev["new_wactive"] = cuda.device_array(wcap, np.uint8)

    def _download(self, lists: bool) -> None:
        """The device state to the host arrays (in place)."""
        dev = self._dev
        ctl, bodies, elems, pairs, walls, bnd = self.records()
        for f in ("pos", "vel", "quat", "angvel", "force", "torque", "vf", "wf", "aux"):
            dev["b_" + f].copy_to_host(getattr(bodies, f))
        if dev["e_pos"] is not dev["b_pos"]:
            dev["e_pos"].copy_to_host(elems.pos)
        for f in ("ref", "worst", "count"):
            dev["e_" + f].copy_to_host(getattr(elems, f))
        for f in ("frame", "frame_ref", "load"):
            dev["w_" + f].copy_to_host(getattr(bnd, f))
        if lists:
            c, wc = self.sim.contacts, self.sim.wall_contacts
            names = {"hist": "history"}
            for lst, pre, fields in ((c, "nl_", ("key", "hist", "active", "force", "t_pair")),
                                     (wc, "wl_", ("key", "hist", "active", "force", "tag"))):
                cap = dev[pre + "key"].shape[0]
                if lst.capacity < cap:  # (the device list grew: the host's follows)
                    lst.grow(self._grown.get(pre, cap))
                dev[pre + "start"].copy_to_host(lst.start)
                if pre == "nl_":
                    dev["nl_t_start"].copy_to_host(lst.t_start)
                count = lst.count
                for f in fields:
                    host = getattr(lst, names.get(f, f))
                    if count and len(host):
                        dev[pre + f][:count].copy_to_host(host[:count])

    def to_host(self) -> None:
        """The device state (bodies, elements, lists, loads) to the host arrays."""
        if self._dev is not None:
            self._download(lists=True)
            self._lists_on_device = False
            self._take_snapshot()

    def from_host(self) -> None:
        """The host state to the device (at the next call)."""
        self._pull_lists()
        self._dev = None

    def _grow_device(self, status: int, needed: int) -> None:
        """A device list grows (keeping its entries); the host list follows at the next
        download."""
        cuda, dev = self.cuda, self._dev
        pre = "nl_" if status == STATUS_OVERFLOW else "wl_"
        count = int(dev[pre + "start"][-1:].copy_to_host()[0])
        cap = int(needed * 1.25) + 16  # (the host list's growth: the same capacity)
        self._grown[pre] = needed
        fields = ("key", "hist", "active", "force") + (("t_pair",) if pre == "nl_" else
                                                       ("tag",))
        for f in fields:
            old = dev[pre + f]
            new = cuda.device_array((cap,) + old.shape[1:], old.dtype)
            if count:  # (force rows past the list are cleared when a rebuild fills them)
                new[:count].copy_to_device(old[:count])
            dev[pre + f] = new
        n = len(self.sim.elements)
        self._scratch_lists(dev, dev["nl_key"].shape[0], dev["wl_key"].shape[0], n)
        self._args = None

    # ------------------------------------------------------------------ the steps
    def _launch_plan(self, dt: float) -> None:
        """Configured kernels and their arguments for the calls of this advance."""
        k, dev, sim = self.kernels(), self._dev, self.sim
        b, e = sim.bodies, sim.elements
        nb, ne = len(b), len(e)
        blk = self.block

        def grid(n: int) -> int:
            return max(1, (n + blk - 1) // blk)

        def cfg(kernel: Any, n: int) -> Any:
            return _Launch(kernel, grid(n), blk)

        one = 1
        cap = dev["nl_key"].shape[0]
        wcap = dev["wl_key"].shape[0]
        m = dev["mask"] + 1
        st = dev["state"]
        skin = float(sim.skin)
        rmax = float(e.radius.max()) if ne else 0.0
        h = 2.0 * rmax + skin
        period = np.asarray(sim.period, float)
        ncell = np.array([max(1, int(period[3 + d] / h)) if period[3 + d] > 0 else 0
                          for d in range(3)], np.int64)
        dev["ncell"] = self.cuda.to_device(ncell)
        dev["period"] = self.cuda.to_device(period)
        dev["gravity"] = self.cuda.to_device(np.asarray(sim.gravity, float))
        plan = sim.plan
        spin_only = int(plan.spheres_only and not sim.sphere_orientation)
        periodic = int(bool(np.any(period[3:] > 0)))
        update_elements = int(not plan.spheres_only)
        n_owned = nb - int(b.ghosts)
        nsb = 256

        def scan(vals: str, n: int, out: str, gate: int, slot: int, capacity: int,
                 status: int) -> list:
            nblocks = max(1, (n + nsb - 1) // nsb)
            return [(_Launch(k.k_scan_block, nblocks, nsb),
                     (st, gate, dev[vals], n, dev[out], dev["sums"])),
                    (_Launch(k.k_scan_sums, 1, 1 if self.simulator else nsb),
                     (st, gate, dev["sums"], nblocks, dev[out], n, slot, capacity, status)),
                    (cfg(k.k_scan_add, n), (st, gate, dev[out], n, dev["sums"]))]

        from ..kernels import cuda_step as cs

        pre = [(cfg(k.k_pre_force, nb),
                (st, nb, dt, spin_only, periodic, update_elements, n_owned, dev["period"],
                 dev["b_pos"], dev["b_vel"], dev["b_quat"], dev["b_angvel"], dev["b_force"],
                 dev["b_torque"], dev["b_invmass"], dev["b_invinertia"], dev["b_vf"],
                 dev["b_wf"], dev["b_aux"], dev["b_estart"], dev["e_offset"], dev["e_pos"],
                 dev["e_ref"], dev["e_worst"]))]
        decide = [(_Launch(k.k_decide, 1, 1), (st, skin, dev["w_frame"], dev["w_frame_ref"],
                                       dev["w_extent"]))]
        search = (dev["e_pos"], dev["e_radius"], dev["e_owner"], skin, dev["period"], h,
                  dev["ncell"], dev["cells"], m - 1, dev["bucket_start"], dev["order"])
        wsearch = (dev["e_pos"], dev["e_radius"], skin, dev["w_frame"], dev["w_kind"],
                   dev["w_par"], dev["w_grid_int"], dev["w_grid_flt"], dev["w_cell_start"],
                   dev["w_cell_items"], dev["w_prim_cells"])
        rebuild = [
            (cfg(k.k_zero, m), (st, one, dev["bucket_count"], m)),
            (cfg(k.k_cells, ne), (st, ne, dev["e_pos"], dev["period"], h, dev["ncell"], m - 1,
                                  dev["cells"], dev["bucket"], dev["bucket_count"])),
            *scan("bucket_count", m, "bucket_start", one, -1, -1, 0),
            (cfg(k.k_copy, m), (st, one, dev["bucket_start"], dev["cursor"], m)),
            (cfg(k.k_scatter, ne), (st, ne, dev["bucket"], dev["cursor"], dev["order"])),
            (cfg(k.k_pair_count, ne), (st, ne, *search, dev["counts"], dev["new_key"])),
            *scan("counts", ne, "new_start", one, cs.S_PAIRS, cap, STATUS_OVERFLOW),
            (cfg(k.k_pair_fill, ne), (st, ne, *search, dev["new_start"], dev["new_key"])),
            (cfg(k.k_merge, ne), (st, ne, dev["nl_start"], dev["nl_key"], dev["nl_hist"],
                                  dev["nl_active"], dev["new_start"], dev["new_key"],
                                  dev["new_hist"], dev["new_active"])),
            (cfg(k.k_copy_back, max(cap, ne + 1)),
             (st, cs.S_PAIRS, dev["new_start"], dev["new_key"], dev["new_hist"],
              dev["new_active"], dev["nl_start"], dev["nl_key"], dev["nl_hist"],
              dev["nl_active"], dev["nl_force"])),
            (cfg(k.k_zero, ne), (st, one, dev["counts"], ne)),
            (cfg(k.k_transpose_count, cap), (st, dev["nl_start"], dev["nl_key"],
                                             dev["counts"])),
            *scan("counts", ne, "nl_t_start", one, -1, -1, 0),
            (cfg(k.k_copy, ne), (st, one, dev["nl_t_start"], dev["cursor"], ne)),
            (cfg(k.k_transpose_fill, cap), (st, dev["nl_start"], dev["nl_key"],
                                            dev["cursor"], dev["nl_t_pair"])),
            (cfg(k.k_sort_rows, ne), (st, ne, dev["nl_t_start"], dev["nl_t_pair"])),
            (cfg(k.k_wall_count, ne), (st, ne, *wsearch, dev["counts"], dev["new_w"])),
            *scan("counts", ne, "new_wstart", one, cs.S_WALLS, wcap, STATUS_WALL_OVERFLOW),
            (cfg(k.k_wall_fill, ne), (st, ne, *wsearch, dev["new_wstart"], dev["new_w"])),
            (cfg(k.k_merge, ne), (st, ne, dev["wl_start"], dev["wl_key"], dev["wl_hist"],
                                  dev["wl_active"], dev["new_wstart"], dev["new_w"],
                                  dev["new_whist"], dev["new_wactive"])),
            (cfg(k.k_copy_back, max(wcap, ne + 1)),
             (st, cs.S_WALLS, dev["new_wstart"], dev["new_w"], dev["new_whist"],
              dev["new_wactive"], dev["wl_start"], dev["wl_key"], dev["wl_hist"],
              dev["wl_active"], dev["wl_force"])),
            (cfg(k.k_rebuilt, max(ne, dev["w_frame"].shape[0])),
             (st, ne, dev["e_pos"], dev["e_ref"], dev["w_frame"], dev["w_frame_ref"])),
            (_Launch(k.k_rebuild_done, 1, 1), (st,)),
        ]
        forces = [
            (cfg(k.k_contacts, ne),
             (st, ne, dt, dev["b_pos"], dev["b_vf"], dev["b_wf"], dev["b_mass"],
              dev["b_invmass"], dev["e_owner"], dev["e_radius"], dev["e_mat"], dev["e_pos"],
              dev["e_worst"], dev["e_count"], dev["nl_start"], dev["nl_key"], dev["nl_hist"],
              dev["nl_active"], dev["nl_force"], dev["wl_start"], dev["wl_key"],
              dev["wl_hist"], dev["wl_active"], dev["wl_force"], dev["wl_tag"],
              dev["pair_model"], dev["pair_params"], dev["period"], dev["w_kind"],
              dev["w_par"], dev["w_owner"], dev["w_material"], dev["w_ids"],
              dev["w_frame"])),
            (cfg(k.k_sums, nb),
             (st, nb, dt, one, n_owned, dev["gravity"], dev["b_pos"], dev["b_vel"],
              dev["b_quat"], dev["b_angvel"], dev["b_force"], dev["b_torque"], dev["b_mass"],
              dev["b_invmass"], dev["b_invinertia"], dev["b_aux"], dev["b_estart"],
              dev["nl_start"], dev["nl_force"], dev["nl_t_start"], dev["nl_t_pair"],
              dev["wl_start"], dev["wl_force"], dev["e_count"])),
            (cfg(k.k_zero_loads, 6 * dev["w_load"].shape[0]), (st, dev["w_load"])),
            (cfg(k.k_loads, max(wcap, ne)),
             (st, n_owned, dev["b_estart"], dev["wl_start"], dev["wl_key"], dev["wl_active"],
              dev["wl_force"], dev["w_owner"], dev["w_load"], dev["e_worst"])),
            (_Launch(k.k_step_end, 1, 1), (st, float(sim.max_overlap), dt, dev["w_load"],
                                  dev["w_frame"])),
        ]
        self._args = (pre, decide, rebuild, forces)
        nf = dev["w_frame"].shape[0] * dev["w_frame"].shape[1]
        self._frame_kernel = cfg(k.k_set_frame, nf)

    def _step(self, s: int, frames: Any, finish_only: bool = False) -> None:
        pre, decide, rebuild, forces = self._args
        if not finish_only:
            if frames is not None:
                self._frame_kernel(self._dev["state"], self._dev["w_frame"], frames,
                                   min(s, frames.shape[0] - 1))
            for kern, args in pre:
                kern(*args)
        for kern, args in decide:
            kern(*args)
        if not self.host_gate or self._read_state()[7] != 0.0:
            for kern, args in rebuild:
                kern(*args)
        for kern, args in forces:
            kern(*args)

    def _read_state(self) -> np.ndarray:
        return self._dev["state"].copy_to_host()

    def _write_state(self, st: np.ndarray) -> None:
        self._dev["state"].copy_to_device(st)

    def force_rows_current(self) -> bool:
        """The contact output evaluates the pairs again (the force rows of the last
        evaluation are the CPU backend's own, one process)."""
        return False

    def sorts(self) -> bool:
        """No renumbering on the device (its lists sort their own rows)."""
        return False

    def advance(self, n: int, dt: float, frames: np.ndarray) -> StepResult:
        """``n`` steps on the device (fewer when a status stops them); the host state is
        downloaded at the end (the lists too unless ``sync_lists`` is False)."""
        import time

        t0 = time.perf_counter()
        uploaded = False
        if self._dev is None or not self._host_unchanged():
            self._pull_lists()
            self._upload()
            uploaded = True
        self._launch_plan(dt)
        d = self.diag
        from ..kernels import cuda_step as cs

        st = np.zeros(cs.N_STATE)
        st[cs.S_WORST] = d[4]
        st[cs.S_WORST_E] = d[5]
        st[cs.S_STEP_WORST_E] = 1e300
        st[cs.S_ACTIVE] = d[6]
        self._write_state(st)
        table = self.cuda.to_device(frames) if len(frames) else None
        s = 0
        status = STATUS_OK
        launched = 0
        while s < n:
            m = min(self.poll, n - s)
            for t in range(s, s + m):
                self._step(t, table)
            launched += m
            st = self._read_state()
            done = int(st[cs.S_STEPS])
            status = int(st[cs.S_STATUS])
            while status in (STATUS_OVERFLOW, STATUS_WALL_OVERFLOW):
                self._grow_device(status, int(st[cs.S_NEEDED]))
                self._launch_plan(dt)
                st[cs.S_STATUS] = STATUS_OK
                self._write_state(st)
                self._step(done, table, finish_only=True)
                st = self._read_state()
                status = int(st[cs.S_STATUS])
                done = int(st[cs.S_STEPS])
            # (the steps launched after a full list did nothing: the loop goes on from
            # the first step not done)
            s = done
            if status != STATUS_OK:
                break
        t_steps = time.perf_counter() - t0
        self._download(lists=self.sync_lists)
        self._lists_on_device = not self.sync_lists
        self._take_snapshot()
        d[2] = st[cs.S_REBUILDS]
        d[4] = st[cs.S_WORST]
        d[5] = st[cs.S_WORST_E]
        d[6] = st[cs.S_ACTIVE]
        d[0] = status
        d[1] = s
        self.timing = {"steps": s, "launch_steps": launched, "uploaded": float(uploaded),
                       "steps_s": t_steps, "call_s": time.perf_counter() - t0}
        return self._result(s)

    # ------------------------------------------------------------------ checks
    @classmethod
    def compile_check(cls, sim: Any, cc: tuple[int, int] = (9, 0)) -> dict[str, int]:
        """Compile every kernel of ``sim``'s scene (run at least once on the CPU, so that
        it is planned) for compute capability ``cc``, without a GPU (:meth:`compile_ptx`);
        ``sim`` keeps its backend."""
        from numba import cuda

        be = cls.__new__(cls)
        be._setup(cuda, None, True, 64)
        be.simulator = False
        be.host_gate, be.block = False, 128
        be.attach(sim)
        return be.compile_ptx(cc)

    def compile_ptx(self, cc: tuple[int, int] = (9, 0)) -> dict[str, int]:
        """Compile every kernel of the attached scene for a GPU of compute capability
        ``cc`` without running it (no GPU needed: numba-cuda's NVVM only; not on the
        simulator); returns the PTX size per kernel. The argument types are those of the
        launches :meth:`advance` makes."""
        from numba import typeof

        from ..kernels import cuda_step as cs

        if self.simulator:
            raise ParameterError("CudaBackend.compile_ptx(): not on the CUDA simulator")

        class _Host:  # numpy stand-ins for the device arrays: the same numba types
            @staticmethod
            def to_device(a: np.ndarray) -> np.ndarray:
                return np.array(a)

            @staticmethod
            def device_array(shape: Any, dtype: Any = float) -> np.ndarray:
                return np.zeros(shape, dtype)

        cuda, self.cuda = self.cuda, _Host()
        try:
            self._upload()
            self._launch_plan(1e-6)
            pre, decide, rebuild, forces = self._args
            plan = [*pre, *decide, *rebuild, *forces]
            plan.append((self._frame_kernel, (self._dev["state"], self._dev["w_frame"],
                                              np.zeros((1, *self._dev["w_frame"].shape)), 0)))
        finally:
            self.cuda = cuda
            self._dev = None
        sizes: dict[str, int] = {}
        from numba.cuda import dispatcher

        class _Device:  # (device functions ask the driver for it; without one: ``cc``)
            compute_capability = cc

        current = dispatcher.get_current_device
        dispatcher.get_current_device = lambda: _Device
        try:
            for launch, args in plan:
                fn = launch.kernel.py_func
                sig = tuple(typeof(a) for a in args)
                ptx, _ = cuda.compile_ptx(fn, sig, cc=cc)
                sizes[fn.__name__] = max(sizes.get(fn.__name__, 0), len(ptx))
        finally:
            dispatcher.get_current_device = current
        assert set(sizes) == set(cs.KERNELS), set(cs.KERNELS) - set(sizes)
        return sizes

    # ------------------------------------------------------------------ reductions
    def max_speed(self) -> tuple[int, float]:
        """(index, speed) of the fastest body (host arrays: downloaded after each call)."""
        return super().max_speed()

