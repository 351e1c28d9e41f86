"""Cost per particle from 1e3 to 1e6 spheres, dilute and dense, dpm (1 and 2 threads) and
LIGGGHTS (1 core) in the same run; peak memory per sphere; time to the first step.

Scenes (the box-settle material and walls, Hertz-Mindlin, dt = 1e-5 s):
- dilute: spheres (d = 2 mm) on a lattice of spacing 2.1 mm with random velocities up to
  0.05 m/s and no gravity: almost no contacts, the cost is the list and the integration;
- dense: a simple cubic lattice of spacing 0.999 d under gravity on the floor: six touching
  neighbours per sphere, the cost is the contact laws.

    python benchmarks/scaling.py                # 1e3 .. 1e6
    python benchmarks/scaling.py --quick        # 1e3 .. 1e5, fewer steps (5e6 / N)

Writes benchmarks/results/scaling[_quick].json (``{"rows": [...], "peer": ..., "run": ...}``)
and .png.
"""

from __future__ import annotations

import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness
import numpy as np
from shared_scenes import CASES, RHO, D, scene_arrays

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent


def worker(k: int, case: str, threads: int, steps: int) -> dict:
    import numba

    numba.set_num_threads(threads)
    t_import = time.perf_counter()
    import dpm

    pos, vel, box = scene_arrays(k, case)
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, CASES[case][2]), threads=threads,
                         sphere_orientation=False,  # as LIGGGHTS' nve/sphere
                         overlap_tolerance=0.01)
    glass = dpm.Material("glass", density=RHO, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=box, open="+z")
    sim.add_particles("sphere", material=glass, radius=D / 2, positions=pos, velocities=vel)
    del pos, vel  # the scene holds its own copies (as LIGGGHTS holds what it read)
    t0 = time.perf_counter()
    startup = t0 - t_import  # import dpm, scene arrays and set-up, before any step
    sim.run(steps=5, progress=False)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    n = len(sim.bodies)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return {"code": "dpm", "threads": threads, "case": case, "particles": n, "steps": steps,
            "wall_s": wall, "particle_steps_per_s": n * steps / wall,
            "time_to_first_steps_s": first, "startup_s": startup,
            "peak_rss_bytes": rss, "rss_per_particle": rss / n,
            "contacts": sim.contact_count()}


def liggghts(k: int, case: str, steps: int) -> dict | None:
    exe = shutil.which("liggghts")
    if exe is None:
        return None
    pos, vel, box = scene_arrays(k, case)
    n = len(pos)
    with tempfile.TemporaryDirectory() as tmp:
        with open(Path(tmp) / "in.data", "w") as f:
            f.write(f"scaling\n\n{n} atoms\n1 atom types\n\n0 {box[0]} xlo xhi\n"
                    f"0 {box[1]} ylo yhi\n0 {box[2]} zlo zhi\n\nAtoms\n\n")
            np.savetxt(f, np.column_stack([np.arange(1, n + 1), np.ones(n), np.full(n, D),
                                           np.full(n, RHO), pos]),
                       fmt=["%d", "%d", "%.9g", "%.9g", "%.9g", "%.9g", "%.9g"])
            f.write("\nVelocities\n\n")
            np.savetxt(f, np.column_stack([np.arange(1, n + 1), vel, np.zeros((n, 3))]),
                       fmt=["%d"] + ["%.9g"] * 6)
        script = (HERE / "scenes" / "box_settle" / "box_settle.liggghts").read_text()
        script = script.replace("9.81 vector", f"{abs(CASES[case][2]) or 1e-30} vector")
        (Path(tmp) / "in.liggghts").write_text(script)
        out = subprocess.run(["/usr/bin/time", "-f", "MAXRSS %M", exe, "-in", "in.liggghts",
                              "-var", "DATA", "in.data", "-var", "STEPS", str(steps)],
                             cwd=tmp, capture_output=True, text=True,
                             env={**os.environ, "OMP_NUM_THREADS": "1"})
    text = out.stdout + out.stderr
    m = re.search(r"Loop time of ([0-9.eE+-]+)", text)
    if m is None:
        return {"code": "liggghts", "case": case, "particles": n, "error": text[-2000:]}
    loop = float(m.group(1))
    rss = int(re.search(r"MAXRSS (\d+)", text).group(1)) * 1024
    return {"code": "liggghts", "threads": 1, "case": case, "particles": n, "steps": steps,
            "wall_s": loop, "particle_steps_per_s": n * steps / loop, "peak_rss_bytes": rss,
            "rss_per_particle": rss / n}


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for ax, case in zip(axes, CASES, strict=True):
        for code, threads, style in (("dpm", 1, "o-"), ("dpm", 2, "s-"),
                                     ("liggghts", 1, "k^--")):
            pts = sorted((r["particles"], r["particle_steps_per_s"]) for r in rows
                         if r["case"] == case and r["code"] == code
                         and r.get("threads") == threads and "particle_steps_per_s" in r)
            if pts:
                x, y = zip(*pts, strict=True)
                label = f"{code} {threads} thread{'s' * (threads > 1)}"
                ax.plot(x, y, style, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("spheres")
        ax.set_title(f"{case} box (Hertz-Mindlin)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("particle-steps per second")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    p = harness.parser(__doc__, "1e3 .. 1e5 spheres, fewer steps")
    p.add_argument("--worker", nargs=4, metavar=("K", "CASE", "THREADS", "STEPS"))
    p.add_argument("--sizes", type=int, nargs="+", default=None, help="lattice edge counts")
    p.add_argument("--no-liggghts", action="store_true")
    a = p.parse_args()
    if a.worker:
        k, case, threads, steps = a.worker
        print(json.dumps(worker(int(k), case, int(threads), int(steps))))
        return
    sizes = a.sizes or ([10, 22, 46] if a.quick else [10, 22, 46, 100])
    rows = []
    for k in sizes:
        n = k**3
        steps = max(20, min(2000, int((5e6 if a.quick else 1e8) / n)))
        for case in CASES:
            for threads in (1, 2):
                out = subprocess.run([sys.executable, __file__, "--worker", str(k), case,
                                      str(threads), str(steps)], capture_output=True,
                                     text=True, check=True)
                rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
                print(json.dumps(rows[-1]), flush=True)
            if not a.no_liggghts:
                r = liggghts(k, case, steps)
                if r:
                    rows.append(r)
                    print(json.dumps(r), flush=True)
    path = harness.write("scaling", {"rows": rows, "peer": harness.peer(a.no_liggghts)},
                         a.quick)  # {"rows": rows, "peer": ..., "run": ...}
    harness.png(plot, rows, path=path.with_suffix(".png"))


if __name__ == "__main__":
    main()
