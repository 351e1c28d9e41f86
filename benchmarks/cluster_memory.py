"""Memory per clustered body at scale: dpm against LIGGGHTS' ``fix multisphere``, one run.

benchmarks/clusters_settle.py reports the peak resident memory of its 2,000-body runs, which
the processes' fixed part (the interpreter, numba and LLVM, the compiled step: ~170 MB for
dpm, ~35 MB for LIGGGHTS) swamps. Here the same four-sphere clusters (clusters_settle's
template, material and box) are set up at two or more body counts, and each code's peak
resident memory (ru_maxrss of its process, os.wait4) is measured after ``--steps`` steps
of the fall from the insertion region: the memory per body at each count, and the
marginal memory per body, the slope between the counts, which the fixed part does not
enter.

- dpm: the lattice start of clusters_settle (``own_start``: bounding spheres on a cubic
  lattice filling the insertion region, random orientations, at rest), one thread (the
  two-thread figure adds the pair force rows of clustered bodies: ``--threads 2``).
- LIGGGHTS 3.8: ``fix insert/pack`` of the same count into the same region (its only way
  to place multisphere bodies), then the same steps; one core.

Both lists at the same skin (0.4 mm); the bodies fall apart from rest, so the contact lists
hold the near pairs of the start (about 0.75 element pairs per body), not a settled bed's
(each listed pair costs dpm 4 B of key, 24 B of history and a flag).

    python benchmarks/cluster_memory.py [--bodies 20000 100000 300000] [--steps 200]

Writes benchmarks/results/cluster_memory[_TAG].json.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import clusters_settle as cs  # noqa: E402


def side_for(n: int) -> float:
    """A square floor that keeps the insertion region about as tall as it is wide."""
    return max(0.03, (n * 4 / 3 * math.pi * (cs.R_BOUND + 2e-4) ** 3 / cs.INSERT_FRACTION)
               ** (1 / 3))


def dpm_worker(n: int, steps: int, threads: int) -> dict:
    """In this process: set up n clusters, run ``steps`` steps, report peak memory."""
    import numpy as np

    geo = cs.geometry(n, side_for(n))
    start = cs.own_start(n, geo)
    sim = cs.scene(start, geo)
    del start
    sim.threads = threads
    t = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return {"bodies": len(sim.bodies), "elements": len(sim.elements), "steps": steps,
            "pairs_listed": int(sim.contacts.count), "wall_s": wall, "peak_rss_bytes": rss,
            "mean_z_m": float(np.mean(sim.bodies.position[:, 2]))}


def run_dpm(n: int, steps: int, threads: int) -> dict:
    env = {**os.environ, "DPM_KERNELS": "scene", "DPM_THREADS": str(threads)}
    cmd = [sys.executable, __file__, "--worker", str(n), str(steps), str(threads)]
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_liggghts(n: int, steps: int) -> dict | None:
    exe = shutil.which("liggghts")
    if exe is None:
        return None
    geo = cs.geometry(n, side_for(n))
    reg = geo["region"]
    text = cs.LIGGGHTS_IN.format(
        side=geo["side"], top=geo["top"], skin=cs.SKIN, young=cs.YOUNG, poisson=cs.POISSON,
        restitution=cs.RESTITUTION, friction=cs.FRICTION, dt=cs.DT, density=cs.DENSITY,
        spheres=" ".join(f"{x:.6g} {y:.6g} {z:.6g} {cs.R:.6g}" for x, y, z in cs.TEMPLATE),
        r0=reg[0], r1=reg[1], r2=reg[2], r3=reg[3], r4=reg[4], r5=reg[5], seed=cs.SEEDS[0],
        n=n, every=steps, settle=steps - 1, window=1)
    # no dumps of every sphere: only the memory and the count matter here
    text = "\n".join(ln for ln in text.splitlines()
                     if not ln.startswith(("dump", "undump", "write_dump")))
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "in.clusters").write_text(text)
        out, wall, rss_kb = cs._wait([exe, "-in", "in.clusters", "-echo", "none", "-log",
                                      "none"], tmp, {**os.environ, "OMP_NUM_THREADS": "1"})
    atoms = [int(ln.split()[1]) for ln in out.splitlines()
             if len(ln.split()) == 4 and ln.split()[0].isdigit()]
    return {"bodies": atoms[-1] // 4 if atoms else None, "spheres": atoms[-1] if atoms else None,
            "steps": steps, "wall_s": wall, "peak_rss_bytes": rss_kb * 1024}


def slope(rows: list[dict]) -> float | None:
    """Marginal bytes per body between the smallest and the largest count."""
    ok = [r for r in rows if r and r.get("bodies")]
    if len(ok) < 2:
        return None
    a, b = ok[0], ok[-1]
    return (b["peak_rss_bytes"] - a["peak_rss_bytes"]) / (b["bodies"] - a["bodies"])


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--bodies", type=int, nargs="+", default=[20000, 100000, 300000])
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--no-liggghts", action="store_true")
    p.add_argument("--tag", default="")
    p.add_argument("--worker", nargs=3, type=int, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.worker:
        print(json.dumps(dpm_worker(*a.worker)))
        return {}
    run_dpm(min(a.bodies), 20, a.threads)  # compiles or loads the scene's module
    dpm_rows, lig_rows = [], []
    for n in sorted(a.bodies):
        dpm_rows.append(run_dpm(n, a.steps, a.threads))
        lig_rows.append(None if a.no_liggghts else run_liggghts(n, a.steps))
        for name, r in (("dpm", dpm_rows[-1]), ("LIGGGHTS", lig_rows[-1])):
            if r and r.get("bodies"):
                print(f"{name} {r['bodies']} bodies: peak {r['peak_rss_bytes'] / 2**20:.0f} MiB, "
                      f"{r['peak_rss_bytes'] / r['bodies']:.0f} B per body "
                      f"({r['wall_s']:.0f} s)", flush=True)
    res = {"template": "four spheres r = 1 mm (clusters_settle.py)", "steps": a.steps,
           "threads": a.threads, "dpm": dpm_rows, "liggghts": lig_rows,
           "marginal_bytes_per_body": {"dpm": slope(dpm_rows), "liggghts": slope(lig_rows)}}
    m = res["marginal_bytes_per_body"]
    print("marginal bytes per body: dpm "
          + (f"{m['dpm']:.0f}" if m["dpm"] else "-") + ", LIGGGHTS "
          + (f"{m['liggghts']:.0f}" if m["liggghts"] else "-"))
    name = "cluster_memory" + (f"_{a.tag}" if a.tag else "") + ".json"
    (HERE / "results" / name).write_text(json.dumps(res, indent=1) + "\n")
    return res


if __name__ == "__main__":
    main()
