"""The rotating drum's step time on 1 and 2 threads, in a minute (an A/B of two trees).

benchmarks/drum_peer.py's drum (``--kind tube``: the analytic tube, or ``mesh``: the STL,
3,959 beads, its first start) turns for ``--settle`` steps on 2 threads, then runs
``--blocks`` blocks of ``--block`` steps on 1 and 2 threads in turn (``sim.threads``; a
run's results are the same bit for bit for any thread count, so both counts time the same
kind of steps under the same load); the median microseconds per step of each count, their
ratio (the two-thread gain) and the list rebuilds. drum_peer.py takes 24 minutes with
LIGGGHTS; this is for before/after figures on dpm alone.

With two source trees every round runs one process per tree, in turn::

    python benchmarks/drum_steps.py --trees /tmp/before . --rounds 3

Writes benchmarks/results/drum_steps[_TAG].json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def worker(kind: str, settle: int, blocks: int, block: int) -> dict:
    sys.path.insert(0, str(HERE))
    import drum_peer as dp

    import dpm

    cfg = dp.config("full")
    with tempfile.TemporaryDirectory() as tmp:
        stl = Path(tmp) / "drum.stl"
        dp.write_stl(stl, dp.drum_triangles(cfg["length"]))
        sim = dp.scene(kind, dp.start(cfg["length"], 1), cfg["length"], stl)
        sim.threads = 2
        sim.run(steps=settle, progress=False)
        times: dict[int, list[float]] = {1: [], 2: []}
        rebuilds = sim.rebuild_count
        for k in range(2 * blocks):
            th = 1 + k % 2
            sim.threads = th
            t = time.perf_counter()
            sim.run(steps=block, progress=False)
            times[th].append((time.perf_counter() - t) / block * 1e6)
    m1, m2 = statistics.median(times[1]), statistics.median(times[2])
    return {"dpm": str(Path(dpm.__file__).parent), "beads": len(sim.bodies),
            "us_per_step": {"1": m1, "2": m2}, "two_thread_gain": m1 / m2,
            "blocks_us": {str(k): v for k, v in times.items()},
            "rebuilds_per_1000_steps": 1000 * (sim.rebuild_count - rebuilds)
            / (2 * blocks * block)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--kind", choices=("tube", "mesh"), default="tube")
    p.add_argument("--settle", type=int, default=15000)
    p.add_argument("--blocks", type=int, default=4)
    p.add_argument("--block", type=int, default=2500)
    p.add_argument("--trees", nargs=2, type=Path, metavar=("A", "B"))
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--tag", default="")
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    args = [a.kind, a.settle, a.blocks, a.block]
    if a.worker:
        print(json.dumps(worker(*args)))
        return
    trees = a.trees or [HERE.parent]
    rounds = []
    for r in range(a.rounds if a.trees else 1):
        row = []
        for tree in trees:
            env = dict(os.environ, PYTHONPATH=str(tree.resolve()), DPM_KERNELS="scene")
            cmd = [sys.executable, __file__, "--worker", "--kind", a.kind, "--settle",
                   str(a.settle), "--blocks", str(a.blocks), "--block", str(a.block)]
            done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True)
            res = json.loads(done.stdout.strip().splitlines()[-1])
            row.append(res)
            print(f"round {r + 1} {tree}: 1 thread {res['us_per_step']['1']:.0f} us, "
                  f"2 threads {res['us_per_step']['2']:.0f} us per step (gain "
                  f"{res['two_thread_gain']:.2f}), {res['rebuilds_per_1000_steps']:.0f} "
                  "rebuilds per 1000 steps", flush=True)
        rounds.append(row)
    out: dict = {"kind": a.kind, "settle": a.settle, "blocks": a.blocks, "block": a.block,
                 "trees": [str(t) for t in trees], "rounds": rounds}
    if a.trees:
        out["ratio_a_over_b"] = {th: statistics.median(
            r[0]["us_per_step"][th] / r[1]["us_per_step"][th] for r in rounds)
            for th in ("1", "2")}
        print(f"A/B time per step: 1 thread {out['ratio_a_over_b']['1']:.3f}, "
              f"2 threads {out['ratio_a_over_b']['2']:.3f}")
    name = "drum_steps" + (f"_{a.tag}" if a.tag else "") + ".json"
    (HERE / "results" / name).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
