"""Two threads on a scene with no listed pair: a dilute gas of spheres in a box.

The fused force pass of sphere scenes cuts the elements into one contiguous chunk per
thread (``chunk_bounds`` in ``dpm/kernels/step.py``). Cut by listed pairs alone, a
scene with none (spheres farther apart than their skin: a stream, a dilute inlet jet,
this gas) put every element in the last chunk, so one thread did all the work. This
times the gas on one thread and on two, in one process (``sim.threads``, the same bits),
blocks in turn, and writes ``results/<tag>.json`` with the median microseconds per step
and the two-thread gain.

    python benchmarks/thread_chunks.py                  # 20,000 spheres
    PYTHONPATH=/tmp/before python benchmarks/thread_chunks.py --tag thread_chunks_before
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

import dpm

HERE = Path(__file__).resolve().parent


def gas(n: int) -> dpm.Simulation:
    """``n`` spheres (r = 1 mm) on a cubic lattice of spacing 4 mm (twice the diameter:
    no pair within the 0.4 mm skin), random velocities up to 0.05 m/s, no gravity, in a
    box of walls."""
    k = int(np.ceil(n ** (1 / 3)))
    side = 4e-3 * k
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, 0), threads=1, skin=4e-4,
                         sphere_orientation=False)
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(side, side, side))
    g = (np.arange(k) + 0.5) * 4e-3
    pos = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T[:n]
    rng = np.random.default_rng(2)
    sim.add_particles("sphere", material=glass, radius=1e-3, positions=pos,
                      velocities=rng.uniform(-0.05, 0.05, pos.shape))
    return sim


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spheres", type=int, default=20000)
    ap.add_argument("--steps", type=int, default=2000, help="steps per timed block")
    ap.add_argument("--blocks", type=int, default=5, help="timed blocks per thread count")
    ap.add_argument("--tag", default="thread_chunks")
    a = ap.parse_args()
    sim = gas(a.spheres)
    us: dict[int, list[float]] = {1: [], 2: []}
    for th in (1, 2):  # (warm-up: each form's first run loads its kernels)
        sim.threads = th
        sim.run(steps=20, progress=False)
    for k in range(2 * a.blocks):
        th = 1 + k % 2
        sim.threads = th
        t0 = time.perf_counter()
        sim.run(steps=a.steps, progress=False)
        us[th].append((time.perf_counter() - t0) / a.steps * 1e6)
    med = {th: statistics.median(v) for th, v in us.items()}
    out = {"spheres": len(sim.bodies), "listed_pairs": int(sim.contacts.count),
           "steps_per_block": a.steps, "us_per_step": us, "median_us_per_step": med,
           "two_thread_gain": med[1] / med[2]}
    print(f"{out['spheres']} spheres, {out['listed_pairs']} listed pairs: "
          f"{med[1]:.0f} us per step on 1 thread, {med[2]:.0f} on 2: gain "
          f"{out['two_thread_gain']:.2f}")
    (HERE / "results").mkdir(exist_ok=True)
    (HERE / "results" / f"{a.tag}.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
