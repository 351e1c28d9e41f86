"""Would overlapping the halo with the interior forces pay? Each MPI rank's step times,
step by step, and what they cost under three schedules.

The MPI step (:func:`dpm.kernels.step.ranked_run`) waits once a step for every rank: the
vote on the rebuild and the halo travel together after the pre-force part, and the
forces start when both are in. A rank whose step took longer this time makes the others
wait, even where the ranks' totals are equal. The classic remedy (and #15's "interior
force work overlapped where it pays") posts the messages, computes the pairs among owned
elements meanwhile, and waits only before the pairs with a ghost. This script measures
whether that would pay on this machine, before building it: it runs the box_settle
worker of ``mpi_scaling.py`` with the Python step loop (``DPM_MPI_LOOP=python``, the same
kernels, one call each per step) and times each rank's pre-force and force kernels at
every step. From those series, per run:

- ``lockstep``: each step as long as its slowest rank's (the schedule of today);
- ``overlap``: a rank waits for the others' halos only after its interior pairs (its
  force kernel's time times the share of its listed pairs that have no ghost partner);
  the vote is global, so every rank's halo counts, posted after its pre-force part;
- ``no_waits``: the slowest rank's total (no schedule does better without moving bodies
  between ranks: the imbalance of the totals, which a re-cut evens).

``lockstep / no_waits - 1`` is what per-step noise costs; ``(lockstep - overlap) /
lockstep`` what the overlap would win. The step kernels' seconds are measured; the
schedules are computed from them (the messages' own seconds, ~0.5 ms a step at 1e5 with
the Python loop's mpi4py calls, are left out of all three).

    python benchmarks/mpi_step_jitter.py                     # 2 ranks, settled 1e5 bed
    python benchmarks/mpi_step_jitter.py --lattice 20 20 25 --steps 2000 --packing ''

Writes benchmarks/results/mpi_step_jitter.json and .png (each rank's step time, rolling
mean over 50 steps, and the lockstep step).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE))
PACKING = HERE / "scenes" / "box_settle" / "box_settle_40x40x63_settled20000.csv"
WARMUP = 50


def worker(lat: list[int], steps: int, out: str, packing: str) -> None:
    """Under mpiexec: the scene, then ``steps`` steps with each rank's kernels timed."""
    from box_settle import _example


    ex = _example()
    csv = Path(packing) if packing else ex.initial_packing(*lat)
    sim = ex.build(csv)
    if packing:
        sim.overlap_tolerance = 0.2
    sim.threads = 1
    sim.run(steps=WARMUP, progress=False)
    be = sim.backend
    module = be.module
    times: list[tuple[int, float]] = []

    class Timed:
        """The step module with its two per-step kernels timed (kind 0 pre-force, 1
        forces); everything else passed through."""

        def __getattr__(self, name):
            fn = getattr(module, name)
            if name not in ("ranked_pre_force", "ranked_forces"):
                return fn
            kind = int(name == "ranked_forces")

            def timed(*args):
                t0 = time.perf_counter()
                r = fn(*args)
                times.append((kind, time.perf_counter() - t0))
                return r
            return timed

    be.module = Timed()
    be._compile_in_turn = lambda *a, **k: None  # (compiled in the warm-up)
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    # the share of this rank's listed pairs with no ghost partner (the interior work)
    loc = be.local
    c = loc.contacts
    first_ghost = int(loc.bodies.element_start[loc.n_owned])
    keys = c.key[:c.count]
    interior = float(np.mean(keys < first_ghost)) if len(keys) else 1.0
    pre = np.array([t for k, t in times if k == 0])
    frc = np.array([t for k, t in times if k == 1])
    n = min(len(pre), len(frc))
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    rows = comm.gather({"pre_s": pre[:n].tolist(), "forces_s": frc[:n].tolist(),
                        "interior_share": interior, "owned": int(loc.n_owned),
                        "ghosts": int(loc.bodies.ghosts), "wall_s": wall,
                        "halo_s": float(be.totals.get("halo_s", 0.0))}, root=0)
    if comm.rank == 0:
        Path(out).write_text(json.dumps({"ranks": rows, "steps": steps,
                                         "particles": len(sim.bodies)}))


def schedules(pre: np.ndarray, frc: np.ndarray, interior: np.ndarray) -> dict:
    """Seconds of the run under the three schedules (module docstring); ``pre``,
    ``frc``: (ranks, steps) kernel seconds; ``interior``: each rank's interior share."""
    ranks, n = pre.shape
    lock = float(np.sum(np.max(pre + frc, axis=0)))
    t = np.zeros(ranks)
    for s in range(n):
        posted = t + pre[:, s]  # each rank's halo and vote posted
        inner = posted + interior * frc[:, s]  # its interior pairs done
        t = np.maximum(inner, posted.max()) + (1.0 - interior) * frc[:, s]
    return {"lockstep_s": lock, "overlap_s": float(t.max()),
            "no_waits_s": float(np.max(np.sum(pre + frc, axis=1)))}


def plot(res: dict, pre: np.ndarray, frc: np.ndarray, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    w = 1e3 * (pre + frc)
    k = 50
    fig, ax = plt.subplots(figsize=(8, 4.2))
    kern = np.ones(k) / k
    for r in range(w.shape[0]):
        ax.plot(np.convolve(w[r], kern, mode="valid"), lw=1.2, label=f"rank {r}")
    ax.plot(np.convolve(w.max(axis=0), kern, mode="valid"), "k--", lw=1.0,
            label="slowest rank each step (lockstep)")
    ax.set_xlabel("step")
    ax.set_ylabel(f"step kernels [ms], mean over {k} steps")
    s = res["schedules"]
    ax.set_title(f"{res['particles']:,} spheres on {w.shape[0]} ranks: per-step noise "
                 f"{100 * res['noise_loss']:.1f} %, overlap would win "
                 f"{100 * res['overlap_gain']:.1f} %\n(lockstep {s['lockstep_s']:.1f} s, "
                 f"overlap {s['overlap_s']:.1f} s, no waits {s['no_waits_s']:.1f} s)",
                 fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lattice", type=int, nargs=3, default=[40, 40, 63])
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--packing", default=str(PACKING),
                    help="a settled packing CSV (mpi_scaling.py --settle writes it); '' for "
                    "the lattice")
    ap.add_argument("--tag", default="mpi_step_jitter")
    ap.add_argument("--worker", nargs=4, metavar=("NX NY NZ", "STEPS", "OUT", "PACKING"),
                    help=argparse.SUPPRESS)
    a, rest = ap.parse_known_args()
    if a.worker:
        lat = [int(x) for x in a.worker[0].split()]
        worker(lat, int(a.worker[1]), a.worker[2], a.worker[3])
        return
    if a.packing and not Path(a.packing).exists():
        raise SystemExit(f"mpi_step_jitter: --packing {a.packing!r} does not exist; write "
                         "it with mpi_scaling.py --settle 20000, or pass --packing ''")
    from mpi_scaling import _mpiexec

    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI"))}
    env.update(NUMBA_NUM_THREADS="1", DPM_MPI_LOOP="python")
    env.setdefault("DPM_KERNELS", "scene")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "jitter.json"
        cmd = [_mpiexec(), "--allow-run-as-root", "--oversubscribe", "-n", str(a.ranks),
               "--bind-to", "none", sys.executable, __file__, "--worker",
               " ".join(map(str, a.lattice)), str(a.steps), str(out), a.packing]
        done = subprocess.run(cmd, env=env, capture_output=True, text=True,
                              stdin=subprocess.DEVNULL)
        if done.returncode:
            raise SystemExit(f"mpi_step_jitter: {' '.join(cmd)} failed:\n"
                             f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
        raw = json.loads(out.read_text())
    n = min(len(r["pre_s"]) for r in raw["ranks"])
    pre = np.array([r["pre_s"][:n] for r in raw["ranks"]])
    frc = np.array([r["forces_s"][:n] for r in raw["ranks"]])
    interior = np.array([r["interior_share"] for r in raw["ranks"]])
    sch = schedules(pre, frc, interior)
    w = pre + frc
    res = {"machine": platform.machine(), "cores": os.cpu_count(), "ranks": a.ranks,
           "particles": raw["particles"], "steps_timed": n, "lattice": a.lattice,
           "packing": Path(a.packing).name if a.packing else None,
           "per_rank": [{"owned": r["owned"], "ghosts": r["ghosts"],
                         "interior_share": r["interior_share"],
                         "step_ms_mean": 1e3 * float(w[i].mean()),
                         "step_ms_std": 1e3 * float(w[i].std()),
                         "step_kernels_s": float(w[i].sum()),
                         "halo_s_measured": r["halo_s"]}
                        for i, r in enumerate(raw["ranks"])],
           "schedules": sch,
           "noise_loss": sch["lockstep_s"] / sch["no_waits_s"] - 1.0,
           "imbalance_loss": sch["no_waits_s"] / float(w.sum(axis=1).mean()) - 1.0,
           "overlap_gain": (sch["lockstep_s"] - sch["overlap_s"]) / sch["lockstep_s"]}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{a.tag}.json").write_text(json.dumps(res, indent=1))
    plot(res, pre, frc, RESULTS / f"{a.tag}.png")
    print(json.dumps({k: v for k, v in res.items() if k != "per_rank"}, indent=1))
    for i, r in enumerate(res["per_rank"]):
        print(f"rank {i}: {r['owned']} owned, {r['ghosts']} ghosts, interior share "
              f"{r['interior_share']:.3f}, step {r['step_ms_mean']:.2f} +- "
              f"{r['step_ms_std']:.2f} ms")


if __name__ == "__main__":
    main()
