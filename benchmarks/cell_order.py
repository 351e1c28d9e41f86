"""What renumbering the bodies in cell order buys (``CpuBackend(sort_every=...)``).

The box_settle scene (10,000 spheres) in three orders, each run in the same process after
a warm-up, timed over the settling run: the lattice order of its CSV (already close to
cell order: neighbours are near in memory), the same packing shuffled (as an inlet or a
long mixing run leaves it), and the shuffled packing renumbered in cell order at every
``--sort-every`` rebuilds (decided every ``SORT_CHECK_STEPS`` steps). ``--rounds N`` runs
the three in turn N times and gives the median of each round's ratio to the lattice order
(one round's ratios move by ~5 % on a shared 2-core machine). Writes
results/cell_order[_TAG].json.

    python benchmarks/cell_order.py                  # 10,000 spheres, 6,000 steps
    python benchmarks/cell_order.py --quick          # 1,000 spheres, 2,000 steps
    python benchmarks/cell_order.py --lattice 15 15 15 --rounds 5 --tag small_3375
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np
from box_settle import _example  # noqa: I001  (run from benchmarks/)

from dpm.backends import CpuBackend

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent


def run(csv: Path, steps: int, order: str, sort_every: int, threads: int) -> dict:
    ex = _example()
    sim = ex.build(csv)
    sim.backend = CpuBackend(threads=threads, sort_every=sort_every)
    if order != "lattice":
        sim.permute(np.random.default_rng(0).permutation(len(sim.bodies)))
    sim.run(steps=200, progress=False)  # compile, first rebuilds
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    return {"order": order, "sort_every": sort_every, "threads": threads, "wall_s": wall,
            "bodies": len(sim.bodies),
            "particle_steps_per_s": len(sim.bodies) * steps / wall,
            "mean_height_m": float(sim.bodies.position[:, 2].mean()),
            "rebuilds": sim.rebuild_count}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--steps", type=int, default=None)
    p.add_argument("--sort-every", type=int, default=20)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--lattice", type=int, nargs=3, metavar=("NX", "NY", "NZ"), default=None)
    p.add_argument("--tag", default="")
    p.add_argument("--rounds", type=int, default=1, help="the three runs in turn, N times")
    a = p.parse_args()
    ex = _example()
    csv = ex.initial_packing(*(a.lattice or ((10, 10, 10) if a.quick else (20, 20, 25))))
    steps = a.steps or (2000 if a.quick else 6000)
    cases = [("lattice", 0), ("shuffled", 0), ("shuffled", a.sort_every)]
    rounds = [[run(csv, steps, order, every, a.threads) for order, every in cases]
              for _ in range(a.rounds)]  # (the three in turn: a load change hits all)
    rows = []
    for k in range(len(cases)):
        r = dict(rounds[len(rounds) // 2][k])
        r["ratio_to_lattice"] = statistics.median(
            rr[k]["particle_steps_per_s"] / rr[0]["particle_steps_per_s"] for rr in rounds)
        r["ratios_by_round"] = [rr[k]["particle_steps_per_s"] / rr[0]["particle_steps_per_s"]
                                for rr in rounds]
        r["particle_steps_per_s"] = statistics.median(
            rr[k]["particle_steps_per_s"] for rr in rounds)
        rows.append(r)
    for r in rows:
        print(f"{r['order']:9s} sort_every={r['sort_every']:3d}: "
              f"{r['particle_steps_per_s']:.3g} particle-steps/s "
              f"({r['ratio_to_lattice']:.3f} of the lattice order, median of the rounds' "
              f"ratios), mean height "
              f"{r['mean_height_m'] * 1e3:.4f} mm, {r['rebuilds']} rebuilds")
    out = HERE / "results" / ("cell_order" + (f"_{a.tag}" if a.tag else "") + ".json")
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps({"steps": steps, "spheres": rows[0]["bodies"],
                               "rounds": a.rounds,
                               "runs": rows}, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
