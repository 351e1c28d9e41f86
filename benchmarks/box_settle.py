"""Box-settle benchmark: particle-steps per second of dpm and LIGGGHTS on the same scene.

Runs the reference scene (benchmarks/scenes/box_settle, 10,000 spheres, 20,000 steps by
default) with dpm, and with LIGGGHTS in the same run when the ``liggghts`` binary is on
PATH (``apt-get install -y liggghts``). Writes benchmarks/results/box_settle.json (both
figures, their ratio and the mean heights) and box_settle.png.

    python benchmarks/box_settle.py              # full scene
    python benchmarks/box_settle.py --quick      # 1,000 spheres, 2,000 steps
    python benchmarks/box_settle.py --lattice 10 10 10 --steps 20000 --tag box_settle_1e3
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import harness
import numba

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scenes" / "box_settle"


def run_dpm(lat, steps, threads=1, warmup=20):
    ex = harness.example("box_settle")
    csv = ex.initial_packing(*lat)
    t0 = time.perf_counter()
    sim = ex.build(csv)
    sim.threads = threads
    sim.run(steps=warmup, progress=False)  # compile (or load from cache) and prime
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim.run(steps=steps - warmup, progress=False)
    wall = time.perf_counter() - t0
    n = len(sim.bodies)
    return {"particles": n, "steps": steps, "timed_steps": steps - warmup, "wall_s": wall,
            "particle_steps_per_s": n * (steps - warmup) / wall,
            "time_to_first_steps_s": first, "threads": threads,
            "mean_z_m": float(sim.bodies.position[:, 2].mean()),
            "neighbour_rebuilds": sim.rebuild_count}


def run_liggghts(lat, steps):
    exe = harness.liggghts()
    if exe is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["python3", str(SCENE / "gen_init.py"), *map(str, lat)], cwd=tmp,
                       check=True, capture_output=True)
        n = lat[0] * lat[1] * lat[2]
        shutil.copy(SCENE / "box_settle.liggghts", tmp)
        t0 = time.perf_counter()
        out = subprocess.run([exe, "-in", "box_settle.liggghts", "-var", "DATA",
                              f"box_settle_{lat[0]}x{lat[1]}x{lat[2]}.data", "-var", "STEPS",
                              str(steps)], cwd=tmp,
                             check=True, capture_output=True, text=True,
                             env={**os.environ, "OMP_NUM_THREADS": "1"}).stdout
        whole = time.perf_counter() - t0
    loop = float(re.search(r"Loop time of ([0-9.eE+-]+)", out).group(1))
    rows = [ln.split() for ln in out.splitlines() if re.match(rf"\s+{steps}\s+{n}\s", ln)]
    return {"particles": n, "steps": steps, "loop_s": loop, "whole_run_s": whole,
            "particle_steps_per_s": n * steps / loop,
            "mean_z_m": float(rows[-1][3]) if rows else None}


def plot(result, path):
    import matplotlib.pyplot as plt

    names, vals, colors = ["dpm 1 thread"], [result["dpm"]["particle_steps_per_s"]], ["tab:blue"]
    if result["dpm_2_threads"]:
        names.append("dpm 2 threads")
        vals.append(result["dpm_2_threads"]["particle_steps_per_s"])
        colors.append("tab:cyan")
    if result["liggghts"]:
        names.append("LIGGGHTS 1 core")
        vals.append(result["liggghts"]["particle_steps_per_s"])
        colors.append("tab:gray")
    fig, ax = plt.subplots(figsize=(6, 3.4))
    bars = ax.bar(names, vals, color=colors)
    ax.bar_label(bars, labels=[f"{v:.3g}" for v in vals])
    ax.set_ylabel("particle-steps per second")
    n, s = result["dpm"]["particles"], result["dpm"]["steps"]
    ratios = ""
    if result["ratio"]:
        ratios = f"\ndpm/LIGGGHTS: {result['ratio']:.2f} (1 thread)"
        if result["ratio_2_threads"]:
            ratios += f", {result['ratio_2_threads']:.2f} (2 threads)"
    ax.set_title(f"box_settle, {n} spheres, {s} steps{ratios}")
    ax.margins(y=0.15)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    p = harness.parser(__doc__, "1,000 spheres, 2,000 steps")
    p.add_argument("--lattice", type=int, nargs=3, default=None)
    p.add_argument("--steps", type=int, default=None)
    p.add_argument("--no-liggghts", action="store_true")
    p.add_argument("--tag", default=None,
                   help="results/<tag>.json and .png (default box_settle, box_settle_quick)")
    a = p.parse_args()
    lat = a.lattice or ((10, 10, 10) if a.quick else (20, 20, 25))
    steps = a.steps or (2000 if a.quick else 20000)
    d = run_dpm(lat, steps, threads=1)
    d2 = run_dpm(lat, steps, threads=2) if numba.config.NUMBA_NUM_THREADS >= 2 else None
    lg = None if a.no_liggghts else run_liggghts(lat, steps)
    lps = lg["particle_steps_per_s"] if lg else None
    result = {"scene": "box_settle", "lattice": lat, "dpm": d, "dpm_2_threads": d2,
              "peer": harness.peer(a.no_liggghts), "liggghts": lg,
              "ratio": harness.ratio(d["particle_steps_per_s"], lps),
              "ratio_2_threads": harness.ratio(d2["particle_steps_per_s"], lps) if d2 else None,
              "mean_z_rel_diff": (d["mean_z_m"] / lg["mean_z_m"] - 1)
              if lg and lg["mean_z_m"] else None}
    path = harness.write("box_settle", result, a.quick, a.tag, indent=2)
    harness.png(plot, result, path=path.with_suffix(".png"))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
