"""Which step module a run uses, what it says while one compiles, and compiling ahead.

A scene's own step module (:func:`dpm.plan.step_module`) is the fastest code but compiles
for 1-4 minutes (a 2-core machine) the first time a combination of laws, integrator and
boundary kinds is met (announced with this machine's last compile time, reported every
15 s while it compiles, and timed: :func:`compiling`). The universal module of the
integrator (:mod:`dpm.universal_step`) runs every scene of built-in parts with the same
results bit for bit, a little slower. With
``kernels="auto"`` (the default of :class:`dpm.backends.cpu.CpuBackend`):

1. the scene's own module when it has been compiled before (a marker beside the
   generated file, written once its kernels are in numba's cache);
2. else the universal module, when it is compiled (``dpm compile`` compiles them), and
   the scene's own module is compiled in a background process for the next run
   (``$DPM_BACKGROUND_COMPILE=0`` turns that off);
3. else the scene's own module, compiled now, with a message on standard error that
   says so and how to avoid it next time.

``$DPM_KERNELS`` (``auto``, ``scene``, ``universal``) overrides the default.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

from .errors import ParameterError

#: the choices of CpuBackend(kernels=...)
KERNEL_CHOICES = ("auto", "scene", "universal")
#: the step functions a run calls (their compiled signatures are what a background
#: compile of the scene's module compiles for)
DRIVERS = ("run_steps", "finish_step", "rebuild", "pre_force", "needs_rebuild",
           "compute_forces", "post_force", "update_element_positions", "pair_overlaps",
           "entry_overlaps")


def kernels_choice(value: str | None) -> str:
    """``value``, else ``$DPM_KERNELS``, else "auto" (checked)."""
    name = "kernels"
    if value is None:
        value, name = os.environ.get("DPM_KERNELS", "auto"), "DPM_KERNELS"
    if value not in KERNEL_CHOICES:
        raise ParameterError(f"{name}={value!r}; allowed: {', '.join(KERNEL_CHOICES)}")
    return value


def _marker(module: ModuleType) -> Path:
    return Path(module.__file__).with_suffix(".ready")


def _stamp() -> str:
    import numba

    return f"numba {numba.__version__} python {sys.version_info[:2]}"


def is_ready(module: ModuleType) -> bool:
    """Whether ``module``'s kernels were compiled into numba's cache (by this numba and
    Python) before."""
    try:
        return _marker(module).read_text() == _stamp()
    except OSError:
        return False


def mark_ready(module: ModuleType) -> None:
    """Record that ``module``'s kernels are in numba's cache."""
    path = _marker(module)
    if not is_ready(module):
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        try:
            tmp.write_text(_stamp())
            os.replace(tmp, path)
        except OSError:
            pass


def background_allowed() -> bool:
    return os.environ.get("DPM_BACKGROUND_COMPILE", "1") not in ("0", "", "no", "false")


def choose(plan: Any, fused: bool, kernels: str, one_thread: bool = False
           ) -> tuple[ModuleType, bool]:
    """(step module, whether it is the universal one) for a run of ``plan`` (on one
    thread: the scene's own module in its one-thread form, :func:`dpm.plan.one_thread_form`;
    the universal module has one form)."""
    from . import universal_step

    covered = universal_step.covers(plan.laws) and _builtin_kinds(plan.kinds)
    if kernels == "universal":
        if not covered:
            raise ParameterError("kernels='universal': this scene uses a plugin's contact "
                                 "law or boundary kind; allowed: 'scene' or 'auto'")
        uni = universal_step.universal_module(plan.integrator_module)
        return _load_module(uni, "the universal"), True
    own = plan.module(fused, one_thread)
    if kernels == "scene" or is_ready(own) or not covered:
        return _load_module(own, "this scene's"), False
    uni = universal_step.universal_module(plan.integrator_module)
    if is_ready(uni):
        later = (" its own, faster ones compile in the background for the next run."
                 if background_allowed() else "")
        _announce(uni, "this scene runs on the universal step kernels (compiled ahead);"
                  + later)
        return uni, True
    return _load_module(own, "this scene's"), False


def _builtin_kinds(kinds: list[int]) -> bool:
    from .boundaries.primitives import BUILTIN_CODES

    return all(k in BUILTIN_CODES for k in kinds)


_ANNOUNCED: set[str] = set()


def _load_module(module: ModuleType, what: str) -> ModuleType:
    """``module``, saying (once) that it compiles at the first step if it was not
    compiled before, with this machine's last compile time of that kind as the
    estimate; :func:`compiling` then reports while it compiles."""
    if not is_ready(module):
        kind = "universal" if what == "the universal" else "scene"
        _KIND[module.__name__] = (kind, what)
        _announce(module, f"compiling {what} step kernels (first run of this combination of "
                  f"contact laws, integrator and boundaries; {_estimate(kind)}, then "
                  "cached). `dpm compile` once makes new scenes of built-in parts start "
                  "in seconds.")
    return module


#: seconds between the lines that say a compile is still going
TICK_S = 15.0
#: what :func:`_load_module` announced: module name -> (kind, words)
_KIND: dict[str, tuple[str, str]] = {}
#: when each announced compile began (the first call of its module)
_BEGAN: dict[str, float] = {}


def _times_file() -> Path:
    from . import plan as _plan

    return _plan.cache_dir() / "compile_times.json"


def _recorded(kind: str) -> list[float]:
    import json

    try:
        return [float(t) for t in json.loads(_times_file().read_text()).get(kind, [])]
    except (OSError, ValueError, TypeError, AttributeError):
        return []


def _record(kind: str, seconds: float) -> None:
    """Keep the last 5 compile times of ``kind`` on this machine (the next estimate)."""
    import json

    path = _times_file()
    try:
        data = json.loads(path.read_text())
        if not isinstance(data, dict):
            data = {}
    except (OSError, ValueError):
        data = {}
    data[kind] = ([float(t) for t in data.get(kind, []) if isinstance(t, int | float)]
                  + [round(seconds, 1)])[-5:]
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(json.dumps(data))
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)


def _estimate(kind: str) -> str:
    """An honest estimate: this machine's recent compile times of the kind, else the
    range measured on 2-core machines."""
    times = sorted(_recorded(kind))
    if times:
        lo, hi = times[0], times[-1]
        span = f"{lo:.0f} s" if hi - lo < 5 else f"{lo:.0f}-{hi:.0f} s"
        return f"{span} the last time{'s' if len(times) > 1 else ''} on this machine"
    return ("1-4 minutes on a 2-core machine" if kind == "scene"
            else "3-5 minutes on a 2-core machine")


@contextlib.contextmanager
def compiling(module: ModuleType | None) -> Iterator[None]:
    """Around the calls of a step module until its first call has compiled it: every
    :data:`TICK_S` seconds a line says how long it has been compiling (against this
    machine's last time); once the module is ready (:func:`mark_ready`), one line says how
    long it took, and the time is kept for the next estimate. Silent for a module that
    was compiled before, and inside :func:`quiet`."""
    import threading

    name = getattr(module, "__name__", None)
    if name not in _KIND or _quiet():
        yield
        return
    kind, what = _KIND[name]
    began = _BEGAN.setdefault(name, time.perf_counter())
    last = _recorded(kind)
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(TICK_S):
            so_far = time.perf_counter() - began
            ref = f" (last time here: {max(last):.0f} s)" if last else ""
            print(f"dpm: still compiling {what} step kernels: {so_far:.0f} s{ref}",
                  file=sys.stderr, flush=True)

    ticker = threading.Thread(target=tick, name="dpm-compile-ticker", daemon=True)
    ticker.start()
    try:
        yield
    finally:
        stop.set()
        ticker.join()
        if is_ready(module):
            took = time.perf_counter() - began
            del _KIND[name]
            _BEGAN.pop(name, None)
            _record(kind, took)
            print(f"dpm: compiled {what} step kernels in {took:.0f} s (cached: the next run "
                  "of this combination starts in seconds)", file=sys.stderr, flush=True)


def _announce(module: ModuleType, text: str) -> None:
    """``text`` on standard error, once per module and process (not inside
    :func:`quiet`)."""
    if module.__name__ not in _ANNOUNCED and not _quiet():
        _ANNOUNCED.add(module.__name__)
        print(f"dpm: {text}", file=sys.stderr, flush=True)


#: how many :func:`quiet` blocks are open in this process
_QUIET_DEPTH = 0


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Hold back the compile messages and the threading-layer advice of the runs inside
    the block (``dpm compile``'s own throwaway scenes); nothing outside it changes."""
    global _QUIET_DEPTH
    _QUIET_DEPTH += 1
    try:
        yield
    finally:
        _QUIET_DEPTH -= 1


def _quiet() -> bool:
    return _QUIET_DEPTH > 0


# ------------------------------------------------------------------ background compile
def signatures(module: ModuleType) -> dict[str, list]:
    """The compiled signatures of the step functions of ``module``."""
    out = {}
    for name in DRIVERS:
        fn = getattr(module, name, None)
        sigs = list(getattr(fn, "signatures", []) or [])
        if sigs:
            out[name] = sigs
    return out


def compile_in_background(plan: Any, fused: bool, sigs: dict[str, list],
                          one_thread: bool = False) -> Path | None:
    """Start a detached process that compiles the scene's own step module (in its
    one-thread form if ``one_thread``) for the signatures ``sigs`` (what the universal
    module was called with) and marks it ready; None when the plan cannot be handed over
    (a law defined in a script)."""
    from . import plan as _plan

    job = (plan.laws, plan.integrator_module, plan.kinds, plan.periodic, fused, sigs,
           one_thread)
    try:
        data = pickle.dumps(job)
    except Exception:  # noqa: BLE001  (classes of a script's __main__: nothing to hand over)
        return None
    d = _plan.cache_dir()
    d.mkdir(parents=True, exist_ok=True)
    # one compile per module at a time: a script that makes many scenes of one kind (a
    # parameter sweep, a benchmark) would otherwise start one compile of the same module
    # for each scene while the first is still running
    busy = Path(plan.module(fused, one_thread).__file__).with_suffix(".compiling")
    if not _claim(busy):
        return None
    path = d / f"compile-{os.getpid()}-{time.time_ns()}.job"
    path.write_bytes(data)
    log = path.with_suffix(".log").open("w")
    # at the lowest priority (nice 19): a run on two or more threads beside it would
    # otherwise lose a core to it, and threads that wait at each parallel loop's barrier
    # for a descheduled one made such a run 10-50x slower while the compile lasted
    child = subprocess.Popen([sys.executable, "-c", "import os, sys; os.nice(19); "
                              "import dpm.warm; sys.exit(dpm.warm.main(sys.argv[1:]))",
                              str(path), str(busy)], stdout=log, stderr=log,
                             stdin=subprocess.DEVNULL, start_new_session=True,
                             env=dict(os.environ, DPM_BACKGROUND_COMPILE="0",
                                      DPM_THREADS="1"))
    log.close()
    busy.write_text(str(child.pid))
    return path


def _claim(busy: Path) -> bool:
    """Create ``busy`` (the marker of a compile in progress) unless a living process holds
    it; False when one does. A marker whose process is gone (killed) is taken over."""
    for _ in range(2):
        try:
            os.close(os.open(busy, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            return True
        except FileExistsError:
            try:
                pid = int(busy.read_text() or "0")
            except (OSError, ValueError):
                pid = 0
            if pid == 0 and time.time() - _mtime(busy) < 60.0:
                return False  # (just claimed: the pid follows)
            if pid and _alive(pid):
                return False
            busy.unlink(missing_ok=True)
        except OSError:
            return False
    return False


def _mtime(path: Path) -> float:
    try:
        return path.stat().st_mtime
    except OSError:
        return 0.0


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def compile_job(path: Path) -> ModuleType:
    """Compile the scene module a job file names (see :func:`compile_in_background`)."""
    from . import plan as _plan

    laws, integrator, kinds, periodic, fused, sigs, *form = pickle.loads(
        Path(path).read_bytes())
    module = _plan.step_module(laws, integrator, kinds, periodic, fused,
                               one_thread=bool(form and form[0]))
    if not is_ready(module):
        for name, sig_list in sigs.items():
            for sig in sig_list:
                getattr(module, name).compile(sig)
        mark_ready(module)
    return module


# ------------------------------------------------------------------ dpm compile
def integrator_modules() -> dict[str, str]:
    """The explicit built-in integrators by name, and their kernel modules (the implicit
    ones run their forces through velocity Verlet's module)."""
    from .plugins import registry

    reg = registry()
    out = {}
    for name in reg.names("integrator"):
        cls = reg.lookup("integrator", name)
        mod = getattr(cls, "kernel_module", "")
        if (cls.__module__.startswith("dpm.") and mod.startswith("dpm.kernels.")
                and not getattr(cls, "implicit", False)):
            out.setdefault(mod, name)
    return {name: mod for mod, name in out.items()}


def compile_universal(integrator: str) -> float:
    """Compile the universal step module of ``integrator`` (by name) into numba's cache:
    a throwaway scene of spheres and a two-sphere cluster in a box with a tube, two
    materials with different laws, run through every step function a run calls.
    Returns the seconds it took."""
    import numpy as np

    from . import Material, Simulation
    from .backends.cpu import CpuBackend

    t0 = time.perf_counter()
    sim = Simulation(dt=1e-6, gravity=(0, 0, -9.81), integrator=integrator,
                     device=CpuBackend(threads=1, kernels="universal"), dt_check="off")
    a = Material("a", density=2500.0, young=1e7, poisson=0.3)
    b = Material("b", density=7800.0, young=2e7, poisson=0.3)
    sim.contact(a, a, model="hertz_mindlin", restitution=0.5, friction=0.5,
                rolling_friction=0.01, rolling_model="epsd")
    sim.contact(a, b, model="linear_spring_dashpot", stiffness=1e3, restitution=0.5,
                friction=0.4)
    sim.add_boundary("box", material=b, lower=(0, 0, 0), upper=(0.01, 0.01, 0.01))
    xyz = np.array([[0.003, 0.003, 0.002], [0.006, 0.006, 0.002]])
    sim.add_particles("sphere", material=a, positions=xyz, radius=1e-3)
    sim.run(steps=3, progress=False)
    be = sim.backend
    be.pre_force(sim.dt)
    be.needs_rebuild()
    be.forces(sim.dt)
    be.post_force(sim.dt)
    be.module.finish_step(sim.dt, *be.records(), be.diag)
    mark_ready(be.module)
    return time.perf_counter() - t0


def _compile_one(integrator: str) -> tuple[str, float]:
    with quiet():
        return integrator, compile_universal(integrator)


def compile_builtins(integrators: list[str] | None = None, jobs: int = 1,
                     say=print) -> dict[str, float]:
    """``dpm compile``: the universal step modules of ``integrators`` (default: every
    built-in explicit one), ``jobs`` at a time in worker processes. Returns seconds per
    integrator."""
    known = integrator_modules()
    names = list(known) if not integrators else list(integrators)
    for n in names:
        if n not in known:
            raise ParameterError(f"dpm compile: integrator {n!r}; allowed: "
                                 f"{', '.join(sorted(known))}")
    out: dict[str, float] = {}
    if jobs <= 1:
        for n in names:
            out[n] = _compile_one(n)[1]
            say(f"  {n}: {out[n]:.1f} s")
        return out
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
        for fut in as_completed([pool.submit(_compile_one, n) for n in names]):
            n, sec = fut.result()
            out[n] = sec
            say(f"  {n}: {sec:.1f} s")
    return out


def main(argv: list[str] | None = None) -> int:
    """The background compile: ``python -c "...dpm.warm.main(...)" JOB``; its log (beside
    the job file) is removed when it succeeds, kept when it fails."""
    argv = sys.argv[1:] if argv is None else argv
    path = Path(argv[0])
    t0 = time.perf_counter()
    try:
        module = compile_job(path)
    finally:
        path.unlink(missing_ok=True)
        if len(argv) > 1:
            Path(argv[1]).unlink(missing_ok=True)  # (the compile-in-progress marker)
    print(f"compiled {module.__name__} in {time.perf_counter() - t0:.1f} s", flush=True)
    path.with_suffix(".log").unlink(missing_ok=True)
    return 0
