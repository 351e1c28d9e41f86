"""GPU measurements of the CUDA backend (#19), every one in one call.

On a machine with an NVIDIA GPU (``pip install 'dpm-granular[cuda]'``)::

    python benchmarks/gpu.py                 # writes benchmarks/results/gpu.json
    python benchmarks/gpu.py --quick         # 1e4 only, no mill: results/gpu_quick.json

``--quick`` on a machine without a GPU runs ``--sim`` instead and writes gpu_quick.json
with ``"gpu_figures": false`` and the reason (no GPU figures in it: a check that the
script and the CUDA backend still run); if even that cannot run, the JSON says why.

- box_settle (``examples/box_settle.py``) at 1e4, 1e5 and 1e6 spheres: particle-steps/s
  of ``device="cuda"`` and of the CPU path (every core) in the same run, the same number
  of steps, and the mean heights (the GPU's within 0.5 % of the CPU's is the criterion;
  at 1e4 the 20,000 steps of the reference scene, whose LIGGGHTS height is known);
- the whole ball mill of the GPGPU thesis (``examples/ball_mill.py``'s full charge; the
  thesis: 253,125 beads, 13.8 s per 1,000 steps, fig. 6.16): s per 1,000 steps;
- DEM-Engine (``import DEME``): recorded as absent when it does not import (its wheel
  scene has not been ported to dpm yet: recorded, not run);
- the first-call cost (kernel compilation) and the transfer/launch split of a call.

``--sim`` runs tiny sizes on numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``) to check
the script without a GPU: it prints its JSON and never writes GPU figures (the simulator's
timings mean nothing). ``--budget`` (s) skips what would start after it.
"""

from __future__ import annotations

import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import harness

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: (lattice, timed steps) per size; 1e4 is the reference scene (20,000 steps)
SIZES = {"1e4": ((20, 20, 25), 20000), "1e5": ((50, 50, 40), 2000),
         "1e6": ((100, 100, 100), 400)}
SIM_SIZES = {"27": ((3, 3, 3), 12)}
#: --quick: 1e4 spheres for 2,000 steps, no ball mill
QUICK_SIZES = {"1e4": ((20, 20, 25), 2000)}
WARMUP = 20


def _no_gpu() -> str | None:
    """Why there is no usable GPU here (probed in a subprocess: numba reads
    ``NUMBA_ENABLE_CUDASIM`` once, at its first ``import numba.cuda``), or None."""
    import subprocess

    probe = ("from numba import cuda\n"
             "print('GPU' if cuda.is_available() else 'no CUDA GPU or driver "
             "(numba.cuda.is_available() is False)')")
    try:
        out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                             timeout=120)
    except (OSError, subprocess.SubprocessError) as exc:
        return f"the GPU probe failed: {exc}"
    lines = (out.stdout.strip() or out.stderr.strip() or "no output").splitlines()
    return None if lines[-1] == "GPU" else lines[-1]


def _backend(device: str):
    if device.startswith("cuda"):
        from dpm.backends.cuda import CudaBackend

        # (box_settle has no flow events, checkpoints or hooks: only the bodies travel);
        # "cuda_host_gate": the rebuild decision read on the host every step
        return CudaBackend(sync_lists=False,
                           host_gate=True if device == "cuda_host_gate" else None)
    from dpm.backends.cpu import CpuBackend

    return CpuBackend(threads=os.cpu_count() if os.cpu_count() else 1)


def box_settle(lat, steps: int, device: str) -> dict:
    warmup = min(WARMUP, steps // 2)
    ex = harness.example("box_settle")
    csv = ex.initial_packing(*lat)
    t0 = time.perf_counter()
    sim = ex.build(csv)
    sim.backend = _backend(device)
    if device == "cpu":
        import numba

        sim.threads = numba.config.NUMBA_NUM_THREADS
    sim.run(steps=warmup, progress=False)  # compile (or load) and prime
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim.run(steps=steps - warmup, progress=False)
    wall = time.perf_counter() - t0
    n = len(sim.bodies)
    out = {"particles": n, "steps": steps, "timed_steps": steps - warmup, "wall_s": wall,
           "particle_steps_per_s": n * (steps - warmup) / wall,
           "time_to_first_steps_s": first,
           "mean_z_m": float(sim.bodies.position[:, 2].mean()),
           "neighbour_rebuilds": sim.rebuild_count}
    if device.startswith("cuda"):
        out["last_call"] = dict(sim.backend.timing)
        out["host_gate"] = sim.backend.host_gate
    else:
        out["threads"] = sim.threads
    return out


def mill(steps: int, settle: int) -> dict:
    bm = harness.example("ball_mill")
    t0 = time.perf_counter()
    sim = bm.build(0.7, length=bm.L_MILL, periodic=False, ramp=0.0)
    sim.backend = _backend("cuda")
    n = len(sim.bodies)
    sim.run(steps=settle, progress=False)
    t_settle = time.perf_counter() - t0
    contacts = sim.contact_count()
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    return {"beads": n, "settle_steps": settle, "settle_and_build_s": t_settle,
            "steps": steps, "wall_s": wall, "s_per_1000_steps": 1000 * wall / steps,
            "particle_steps_per_s": n * steps / wall,
            "contacts_per_bead": contacts / n,
            "thesis_beads": 253125, "thesis_s_per_1000_steps": 13.795,
            "thesis_particle_steps_per_s": bm.THESIS_PARTICLE_STEPS,
            "ratio_to_thesis_particle_steps": n * steps / wall / bm.THESIS_PARTICLE_STEPS}


def deme() -> dict:
    try:
        import DEME  # noqa: N811 (DEM-Engine's module name)
    except Exception as exc:  # noqa: BLE001 (absent or broken: recorded either way)
        return {"available": False, "error": f"{type(exc).__name__}: {exc}"}
    return {"available": True, "version": getattr(DEME, "__version__", "?"),
            "wheel": "not run: DEM-Engine's wheel scene is not ported to dpm yet"}


def environment(sim_mode: bool) -> dict:
    from numba import cuda

    env = {"simulator": sim_mode, "python": platform.python_version(),
           "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count()}
    try:
        import numba_cuda

        env["numba_cuda"] = getattr(numba_cuda, "__version__", "?")
    except ImportError:
        pass
    if not sim_mode:
        dev = cuda.get_current_device()
        env["gpu"] = dev.name.decode() if isinstance(dev.name, bytes) else str(dev.name)
        env["compute_capability"] = list(dev.compute_capability)
        free, total = cuda.current_context().get_memory_info()
        env["gpu_memory_gib"] = total / 2**30
    return env


def main(argv: list[str] | None = None) -> dict:
    p = harness.parser(__doc__, "1e4 spheres for 2,000 steps, no ball mill "
                                "(writes results/gpu_quick.json)")
    p.add_argument("--sim", action="store_true", help="tiny sizes on the CUDA simulator")
    p.add_argument("--sizes", nargs="*", default=None, help="box_settle sizes (1e4 1e5 1e6)")
    p.add_argument("--mill-steps", type=int, default=1000)
    p.add_argument("--mill-settle", type=int, default=800)
    p.add_argument("--no-mill", action="store_true")
    p.add_argument("--budget", type=float, default=480.0, help="seconds; later parts skip")
    p.add_argument("--out", default=None, help="JSON path (default results/gpu.json)")
    a = p.parse_args(argv)
    why = None  # (--quick without a GPU: why these are no GPU figures)
    if a.quick and not a.sim and os.environ.get("NUMBA_ENABLE_CUDASIM") != "1":
        why = _no_gpu()
        a.sim = why is not None
    if a.quick and (a.sim or os.environ.get("NUMBA_ENABLE_CUDASIM") == "1"):
        why = why or "NUMBA_ENABLE_CUDASIM=1 or --sim"
        try:
            res = _run(a)
        except Exception as exc:  # noqa: BLE001 (--quick: the JSON says why, no crash)
            res = {"issue": 19, "simulator_error": f"{type(exc).__name__}: {exc}"}
        res.update(gpu_figures=False, why=f"no GPU figures: {why}; "
                   + ("the CUDA simulator ran tiny sizes instead, whose timings mean nothing"
                      if "simulator_error" not in res else "the CUDA simulator failed too"))
        path = harness.write("gpu", res, a.quick, default=str)
        print(f"wrote {path} (no GPU figures: {why})")
        return res
    return _run(a)


def _run(a) -> dict:
    if a.sim:
        os.environ["NUMBA_ENABLE_CUDASIM"] = "1"
        if "numba.cuda" in sys.modules:
            raise SystemExit("--sim: numba.cuda was imported before NUMBA_ENABLE_CUDASIM")
    from dpm.backends.cuda import cuda_module, simulator

    cuda_module()  # (a clear error without a GPU and without the simulator)
    sim_mode = simulator()
    start = time.perf_counter()
    res: dict = {"issue": 19, "environment": environment(sim_mode), "box_settle": {}}
    sizes = (SIM_SIZES if sim_mode else QUICK_SIZES if a.quick and not a.sizes
             else {k: SIZES[k] for k in (a.sizes or SIZES)})

    def left() -> bool:
        return time.perf_counter() - start < a.budget

    for name, (lat, steps) in sizes.items():
        if not left():
            res["box_settle"][name] = "skipped: budget"
            continue
        row = {"lattice": list(lat)}
        # at the smallest size also with the rebuild decision read on the host (launch
        # overhead against one small read per step)
        devices = ("cuda", "cpu") + (("cuda_host_gate",) if name == next(iter(sizes)) else ())
        for device in devices:
            row[device] = box_settle(lat, steps, device)
            print(name, device, json.dumps(row[device]), flush=True)
        g, c = row["cuda"], row["cpu"]
        row["speedup"] = g["particle_steps_per_s"] / c["particle_steps_per_s"]
        row["mean_z_rel_diff"] = g["mean_z_m"] / c["mean_z_m"] - 1.0
        row["mean_z_within_0_5_percent"] = abs(row["mean_z_rel_diff"]) <= 0.005
        if "cuda_host_gate" in row:
            row["speedup_host_gate"] = (row["cuda_host_gate"]["particle_steps_per_s"]
                                        / c["particle_steps_per_s"])
        res["box_settle"][name] = row
    if sim_mode or a.no_mill or a.quick:
        res["mill"] = "skipped" + (" on the simulator" if sim_mode else "")
    elif left():
        res["mill"] = mill(a.mill_steps, a.mill_settle)
    else:
        res["mill"] = "skipped: budget"
    res["deme"] = deme()
    res["wall_s"] = time.perf_counter() - start
    text = json.dumps(res, indent=1, default=lambda x: None if isinstance(x, float)
                      and not math.isfinite(x) else str(x))
    print(text)
    if sim_mode:
        if a.out and Path(a.out).resolve() == (harness.SHIPPED / "gpu.json").resolve():
            raise SystemExit("refused: the simulator's figures are not GPU figures")
        if not a.quick:
            print("(the CUDA simulator: no GPU figures written)")
        if a.out:
            Path(a.out).write_text(text)
        return res
    if a.out:
        Path(a.out).parent.mkdir(parents=True, exist_ok=True)
        Path(a.out).write_text(text)
    else:
        harness.write("gpu", json.loads(text), a.quick)
    return res


if __name__ == "__main__":
    main()
