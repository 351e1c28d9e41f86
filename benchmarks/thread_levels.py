"""The settled clusters bed on one and two threads, block after block, to see how steady
the two-thread step is on this machine.

The bed of ``clusters_settle.py`` (2,000 four-sphere clusters from its own lattice
start, settled on two threads) runs ``--rounds`` rounds of ``--steps`` steps on one thread
(the one-thread form, as a user's run takes it) then on two, each block timed whole
(``sim.run``, its list rebuilds included). ``--processes`` fresh processes do the same in
turn (the machine's state is per process and per minute, not per run). Writes
``results/<tag>.json`` (every block's microseconds per step and when it ran) and a PNG
of the blocks against time.

    python benchmarks/thread_levels.py --processes 3 --rounds 6
    python benchmarks/thread_levels.py --no-sort --tag thread_levels_no_sort
    OMP_WAIT_POLICY=active python benchmarks/thread_levels.py --tag thread_levels_omp_active
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE))


def blocks(rounds: int, steps: int, sort: bool = True) -> dict:
    """One process: settle the bed, then the rounds (1 thread, 2 threads); ``sort``
    False: no cell-order renumbering after the settling."""
    import clusters_settle as cs

    geo = cs.geometry(2000, side=0.035)
    sim = cs.scene(cs.own_start(2000, geo), geo)
    sim.threads = 2
    sim.run(steps=geo["settle_steps"], progress=False)
    if not sort:
        sim.backend.sort_every = 0
    out = []
    for _ in range(rounds):
        for k in (1, 2):
            sim.threads = k
            sim.run(steps=20, progress=False)  # (the form for k threads loaded)
            t = time.perf_counter()
            sim.run(steps=steps, progress=False)
            out.append({"threads": k, "us_per_step": (time.perf_counter() - t) / steps * 1e6,
                        "at_s": time.time()})
    return {"blocks": out, "bodies": len(sim.bodies), "elements": len(sim.elements)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--processes", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--no-sort", action="store_true",
                    help="no cell-order renumbering in the timed blocks")
    ap.add_argument("--tag", default="thread_levels")
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        Path(args.worker).write_text(json.dumps(blocks(args.rounds, args.steps,
                                                       not args.no_sort)))
        return
    import numpy as np

    runs = []
    for p in range(args.processes):
        tmp = RESULTS / f".{args.tag}_{p}.json"
        subprocess.run([sys.executable, __file__, "--rounds", str(args.rounds), "--steps",
                        str(args.steps), "--worker", str(tmp)]
                       + ["--no-sort"] * args.no_sort, check=True, env=dict(os.environ))
        runs.append(json.loads(tmp.read_text()))
        tmp.unlink()
        for b in runs[-1]["blocks"]:
            print(p, b["threads"], f"{b['us_per_step']:.0f} us/step", flush=True)
    ratios = [[r["blocks"][i]["us_per_step"] / r["blocks"][i + 1]["us_per_step"]
               for i in range(0, len(r["blocks"]), 2)] for r in runs]
    flat = [x for r in ratios for x in r]
    two = [b["us_per_step"] for r in runs for b in r["blocks"] if b["threads"] == 2]
    one = [b["us_per_step"] for r in runs for b in r["blocks"] if b["threads"] == 1]
    result = {"scene": "clusters_settle settled bed, 2,000 four-sphere clusters",
              "steps_per_block": args.steps, "cell_order_renumbering": not args.no_sort,
              "processes": runs,
              "ratio_1_over_2_per_round": ratios,
              "ratio_median": float(np.median(flat)), "ratio_min": float(min(flat)),
              "ratio_max": float(max(flat)),
              "one_thread_us": [float(min(one)), float(np.median(one)), float(max(one))],
              "two_threads_us": [float(min(two)), float(np.median(two)), float(max(two))]}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.tag}.json").write_text(json.dumps(result, indent=1))
    print(f"1 thread over 2 threads, per round: median {result['ratio_median']:.2f}, "
          f"{result['ratio_min']:.2f}-{result['ratio_max']:.2f}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    t0 = min(b["at_s"] for r in runs for b in r["blocks"])
    for k, colour in ((1, "tab:blue"), (2, "tab:orange")):
        for p, r in enumerate(runs):
            xs = [b["at_s"] - t0 for b in r["blocks"] if b["threads"] == k]
            ys = [b["us_per_step"] for b in r["blocks"] if b["threads"] == k]
            ax.plot(xs, ys, "o-", color=colour, label=f"{k} thread{'s' * (k > 1)}"
                    if p == 0 else None)
    ax.set_xlabel("time since the first block [s] (one line per process)")
    ax.set_ylabel("microseconds per step")
    ax.set_ylim(bottom=0)
    ax.set_title(f"settled bed of 2,000 clusters, {args.steps}-step blocks: 1 / 2 threads "
                 f"{result['ratio_min']:.2f}-{result['ratio_max']:.2f}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(RESULTS / f"{args.tag}.png", dpi=120)


if __name__ == "__main__":
    main()
