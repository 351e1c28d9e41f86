"""MPI scaling of dpm against its threads and against LIGGGHTS on the same ranks.

The box_settle scene (benchmarks/scenes/box_settle: glass spheres settling in a box of
walls, Hertz-Mindlin, dt = 1e-5 s) at several sizes, each run in the same sitting by

- dpm on one process, one thread (the baseline of the efficiency);
- dpm on one process, two threads;
- dpm on 1 and 2 MPI ranks (``mpiexec -n R python benchmarks/mpi_scaling.py --worker``),
  one thread each, with each rank's split of the step: stepping, waiting for and
  exchanging the halo, migrating at rebuilds, the whole-state gather and scatter at the
  calls' ends;
- LIGGGHTS 3.8 on 1 and 2 ranks (``mpirun -np R liggghts``, its ``processors * * *``
  default grid).

Strong scaling: the same scene on 1 and 2 ranks; weak scaling: about 10,000 spheres per
rank (the lattice twice as tall on 2 ranks). Parallel efficiency = rate(R) / (R x
rate(1)). Writes benchmarks/results/mpi_scaling[_quick].json and .png.

    python benchmarks/mpi_scaling.py                 # 1e4 and 1e5 spheres, 2000 steps
    python benchmarks/mpi_scaling.py --quick         # 1e4 spheres, 500 steps
    python benchmarks/mpi_scaling.py --oversubscribe 4               # + a 4-rank run
    python benchmarks/mpi_scaling.py --rounds 3     # each configuration 3 times in turn

With ``--rounds`` every ratio (efficiency, against threads, against LIGGGHTS) is the
median of the rounds' ratios, each round's runs one after another, and the plot shows
the median rates; the splits are the last round's. On a shared or virtual machine one
sitting's ratio can swing by 0.3 (the same code gave two threads 0.63 and 0.98 of twice
one thread in two sittings here): quote medians of rounds there.

Machines with more cores: ``--ranks 1 2 4 8``. A run on more ranks than cores
(``--oversubscribe``) is a correctness run only: its time means nothing.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness
from shared_scenes import settled_packing

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent
SCENE = HERE / "scenes" / "box_settle"
LATTICES = {10000: (20, 20, 25), 100000: (40, 40, 63), 20000: (20, 20, 50),
            1000000: (100, 100, 100)}
WARMUP = 50


def _mpiexec() -> str:
    beside = Path(sys.executable).parent / "mpiexec"
    return str(beside) if beside.exists() else (shutil.which("mpiexec") or "mpiexec")


def mpi_missing() -> str | None:
    """Why dpm cannot run on several ranks here (no ``mpiexec``, no mpi4py), or None: the
    rank runs are then left out and the JSON says so (key ``"mpi"``)."""
    import importlib.util

    if not Path(_mpiexec()).exists() and shutil.which(_mpiexec()) is None:
        return "missing: no mpiexec on PATH (Open MPI or MPICH): no rank runs"
    if importlib.util.find_spec("mpi4py") is None:
        return "missing: mpi4py is not installed (pip install mpi4py): no rank runs"
    return None


def worker(lat: tuple[int, int, int], steps: int, out: str, threads: int,
           packing: str | None = None) -> None:
    """Run under mpiexec (or alone): the box_settle scene, timed after a warm-up; from
    ``packing`` (a CSV of :func:`settled_packing`) instead of the lattice if given."""
    import dpm

    ex = harness.example("box_settle")
    csv = Path(packing) if packing else ex.initial_packing(*lat)
    sim = ex.build(csv)
    if packing:  # (a settled bed overlaps by a few % of a radius, as it did in the run)
        sim.overlap_tolerance = 0.2
    sim.threads = threads
    t0 = time.perf_counter()
    sim.run(steps=WARMUP, progress=False)
    first = time.perf_counter() - t0
    be = sim.backend
    if hasattr(be, "totals"):
        be.totals.clear()
    t0 = time.perf_counter()
    sim.run(steps=steps - WARMUP, progress=False)
    wall = time.perf_counter() - t0
    n = len(sim.bodies)
    tot = dict(getattr(be, "totals", {}))
    tim = dict(getattr(be, "timing", {}))
    rows = [tot | {"owned": tim.get("owned", n), "ghosts": tim.get("ghosts", 0),
                   "touching_weight": tim.get("touching_weight", 0.0),
                   "halo_bytes_per_step": tim.get("halo_bytes_per_step", 0.0)}]
    if dpm.parallel.launched_ranks() > 1:
        from mpi4py import MPI

        rows = MPI.COMM_WORLD.allgather(rows[0])
    if dpm.parallel.rank() == 0:
        print(f"particle_steps_per_s {n * (steps - WARMUP) / wall:.6g}", flush=True)
        Path(out).write_text(json.dumps({
            "particles": n, "timed_steps": steps - WARMUP, "wall_s": wall,
            "particle_steps_per_s": n * (steps - WARMUP) / wall, "first_steps_s": first,
            "mean_z_m": float(sim.bodies.position[:, 2].mean()), "ranks": rows,
            "rebuilds": sim.rebuild_count}))


def run_dpm(lat, steps: int, ranks: int, threads: int, tmp: Path, oversubscribe=False,
            packing: Path | None = None):
    out = tmp / f"dpm_{ranks}_{threads}.json"
    cmd = [sys.executable, __file__, "--worker", *map(str, lat), str(steps), str(out),
           str(threads)] + ([str(packing)] if packing else [])
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI"))}
    env["NUMBA_NUM_THREADS"] = str(max(threads, 1))
    if ranks > 1:
        cmd = [_mpiexec(), "--allow-run-as-root", "--oversubscribe", "-n", str(ranks),
               "--bind-to", "none", *cmd]
    subprocess.run(cmd, check=True, env=env, capture_output=True, text=True,
                   stdin=subprocess.DEVNULL)
    res = json.loads(out.read_text())
    res.update(ranks=res["ranks"], n_ranks=ranks, threads=threads,
               oversubscribed=oversubscribe)
    return res


def run_liggghts(lat, steps: int, ranks: int, tmp: Path, packing: Path | None = None):
    exe = shutil.which("liggghts")
    if exe is None:
        return None
    work = tmp / f"lg{ranks}"
    work.mkdir(parents=True)
    if packing:  # (the same bed as dpm's runs: settled_packing's data file)
        data = packing.with_suffix(".data").name
        shutil.copy(packing.with_suffix(".data"), work / data)
    else:
        subprocess.run(["python3", str(SCENE / "gen_init.py"), *map(str, lat)], cwd=work,
                       check=True, capture_output=True)
        data = f"box_settle_{lat[0]}x{lat[1]}x{lat[2]}.data"
    n = lat[0] * lat[1] * lat[2]
    shutil.copy(SCENE / "box_settle.liggghts", work)
    cmd = [exe, "-in", "box_settle.liggghts", "-var", "DATA", data,
           "-var", "STEPS", str(steps)]
    if ranks > 1:  # (the Debian package's own Open MPI launcher)
        mpirun = "/usr/bin/mpirun" if Path("/usr/bin/mpirun").exists() else "mpirun"
        cmd = [mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(ranks), *cmd]
    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI"))}
    env["OMP_NUM_THREADS"] = "1"
    out = subprocess.run(cmd, cwd=work, check=True, capture_output=True, text=True,
                         env=env).stdout
    loop = float(re.search(r"Loop time of ([0-9.eE+-]+)", out).group(1))
    comm = re.search(r"Comm\s*\|[^|]*\|[^|]*\|[^|]*\|[^|]*\|\s*([0-9.]+)", out)
    zs = [ln.split() for ln in out.splitlines() if re.match(rf"\s+{steps}\s+{n}\s", ln)]
    return {"particles": n, "steps": steps, "n_ranks": ranks, "loop_s": loop,
            "particle_steps_per_s": n * steps / loop,
            "comm_percent": float(comm.group(1)) if comm else None,
            "mean_z_m": float(zs[-1][3]) if zs else None}


#: each ratio of a row: (numerator, denominator, factor); with several rounds, the median
#: of the rounds' ratios (each round's runs follow one another: a slower spell of a shared
#: machine falls on both sides of a ratio more often than across rounds)
RATIOS = {"efficiency_2_ranks": ("dpm_2_ranks", "dpm_1", 2.0),
          "efficiency_2_threads": ("dpm_2_threads", "dpm_1", 2.0),
          "dpm_2_ranks_over_2_threads": ("dpm_2_ranks", "dpm_2_threads", 1.0),
          "liggghts_efficiency_2_ranks": ("liggghts_2", "liggghts_1", 2.0),
          "ratio_2_ranks_to_liggghts_2_ranks": ("dpm_2_ranks", "liggghts_2", 1.0),
          "ratio_1_to_liggghts_1": ("dpm_1", "liggghts_1", 1.0)}


def ratios(rounds: list[dict]) -> dict:
    """The row's ratios (:data:`RATIOS`): the median over the rounds, and every round's."""
    out = {}
    for name, (num, den, f) in RATIOS.items():
        per = [r[num] / (f * r[den]) for r in rounds if num in r and den in r]
        if per:
            out[name] = float(statistics.median(per))
            if len(per) > 1:
                out[name + "_rounds"] = per
    return out


def shares(res: dict) -> dict:
    """Mean over ranks of each part of the timed run, as fractions of its wall time."""
    rows = res["ranks"]
    wall = res["wall_s"]
    if not rows or "steps_s" not in rows[0]:
        return {}
    mean = {k: sum(r.get(k, 0.0) for r in rows) / len(rows)
            for k in ("steps_s", "halo_s", "wait_s", "migrate_s", "relist_s", "gather_s",
                      "scatter_s")}
    return {"halo_share": mean["halo_s"] / wall, "migrate_share": mean["migrate_s"] / wall,
            # (of the migration's share: the list rebuild after it, which one process
            # does too; recorded since stop 49, 0 in older results)
            "relist_share": mean["relist_s"] / wall,
            "gather_scatter_share": (mean["gather_s"] + mean["scatter_s"]) / wall,
            # (the overlap vote after a call's last step; until NOTES row 66 the vote after
            # every step's forces, a rank waiting for the slowest one's forces, which now
            # waits in the halo share: one wait a step, with the vote and the messages)
            "wait_share": mean["wait_s"] / wall,
            "compute_share": (mean["steps_s"] - mean["halo_s"] - mean["migrate_s"]
                              - mean["wait_s"]) / wall,
            "owned_imbalance": max(r["owned"] for r in rows)
            / (sum(r["owned"] for r in rows) / len(rows)),
            "ghost_fraction": sum(r["ghosts"] for r in rows)
            / max(sum(r["owned"] for r in rows), 1),
            "halo_bytes_per_step": sum(r["halo_bytes_per_step"] for r in rows)}


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sizes = result["strong"]
    fig, axs = plt.subplots(1, 2, figsize=(11, 4))
    labels = ["dpm 1 rank", "dpm 2 threads", "dpm 2 ranks", "LIGGGHTS 1", "LIGGGHTS 2"]
    keys = ["dpm_1", "dpm_2_threads", "dpm_2_ranks", "liggghts_1", "liggghts_2"]
    width = 0.8 / len(keys)
    for k, (key, lab) in enumerate(zip(keys, labels, strict=True)):
        xs, ys = [], []
        for i, s in enumerate(sizes):
            per = [r[key] for r in s.get("rounds", []) if key in r]  # (median of rounds)
            r = s.get(key)
            if r:
                xs.append(i + (k - 2) * width)
                ys.append(statistics.median(per) if per else r["particle_steps_per_s"])
        axs[0].bar(xs, ys, width, label=lab)
    axs[0].set_xticks(range(len(sizes)), [f"{s['particles']:,}" for s in sizes])
    axs[0].set_xlabel("spheres (box_settle)")
    axs[0].set_ylabel("particle-steps per second")
    axs[0].set_title("strong scaling on this machine, same sitting")
    axs[0].set_ylim(0, 1.4 * axs[0].get_ylim()[1])  # (room for the legend above the bars)
    axs[0].legend(fontsize=8, ncol=2, loc="upper left")
    parts = ["compute_share", "wait_share", "halo_share", "migrate_share",
             "gather_scatter_share"]
    bottom = [0.0] * len(sizes)
    for part in parts:
        vals = [s.get("dpm_2_ranks_shares", {}).get(part, 0.0) for s in sizes]
        lab = {"halo_share": "halo + vote (waits for the slower rank)",
               "wait_share": "wait (overlap vote)"}.get(part, part.replace("_share", ""))
        axs[1].bar(range(len(sizes)), vals, bottom=bottom, label=lab)
        bottom = [b + v for b, v in zip(bottom, vals, strict=True)]
    axs[1].set_xticks(range(len(sizes)), [f"{s['particles']:,}" for s in sizes])
    axs[1].set_ylabel("share of the 2-rank run's wall time (mean over ranks)")
    eff = ", ".join(f"{s['particles']:,}: {s['efficiency_2_ranks']:.2f}" for s in sizes
                    if "efficiency_2_ranks" in s) or "no rank runs"
    axs[1].set_title(f"dpm on 2 ranks: efficiency {eff}", fontsize=9)
    axs[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = harness.parser(__doc__, "10,000 spheres, 500 steps")
    ap.add_argument("--worker", nargs="+", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--sizes", type=int, nargs="+", default=None, help="(10000 100000)")
    ap.add_argument("--steps", type=int, default=None, help="(2000)")
    ap.add_argument("--oversubscribe", type=int, default=0, metavar="R",
                    help="also a correctness run on R ranks (more than the cores)")
    ap.add_argument("--no-liggghts", action="store_true")
    ap.add_argument("--tag", default=None, help="results/<tag>.json (mpi_scaling[_quick])")
    ap.add_argument("--rounds", type=int, default=1,
                    help="run every configuration this many times in turn; each ratio is "
                    "the median of the rounds' (the records kept are the last round's)")
    ap.add_argument("--settle", type=int, default=0, metavar="S",
                    help="time the bed after S steps of settling (settled_packing: run "
                    "once by dpm on 2 threads, then every configuration starts from it) "
                    "instead of the lattice's first steps; no weak-scaling row")
    a = ap.parse_args()
    if a.worker:
        lat = tuple(int(x) for x in a.worker[:3])
        worker(lat, int(a.worker[3]), a.worker[4], int(a.worker[5]),
               a.worker[6] if len(a.worker) > 6 else None)
        return
    a.sizes = a.sizes or ([10000] if a.quick else [10000, 100000])
    a.steps = a.steps or (500 if a.quick else 2000)
    no_mpi = mpi_missing()
    if no_mpi:
        print(f"MPI {no_mpi}", flush=True)
    strong, weak = [], []
    with tempfile.TemporaryDirectory() as tmpd:
        tmp = Path(tmpd)
        for size in a.sizes:
            lat = LATTICES[size]
            steps = a.steps
            packing = settled_packing(lat, a.settle) if a.settle else None
            row = {"particles": lat[0] * lat[1] * lat[2], "lattice": lat, "steps": steps,
                   "settled_steps": a.settle, "rounds": []}
            for k in range(a.rounds):  # (the configurations in turn, round after round)
                got = {"dpm_1": run_dpm(lat, steps, 1, 1, tmp, packing=packing),
                       "dpm_2_threads": run_dpm(lat, steps, 1, 2, tmp, packing=packing),
                       "dpm_2_ranks": None if no_mpi else
                       run_dpm(lat, steps, 2, 1, tmp, packing=packing)}
                if not a.no_liggghts:
                    got["liggghts_1"] = run_liggghts(lat, steps, 1, tmp / f"{size}_{k}",
                                                     packing)
                    got["liggghts_2"] = run_liggghts(lat, steps, 2, tmp / f"{size}_{k}",
                                                     packing)
                row.update(got)  # (the last round's records, with their splits)
                row["rounds"].append({name: r["particle_steps_per_s"]
                                      for name, r in got.items() if r})
            row.update(ratios(row["rounds"]))
            row["dpm_2_ranks_shares"] = shares(row["dpm_2_ranks"]) if row["dpm_2_ranks"] else {}
            strong.append(row)
            (tmp / "x").mkdir(exist_ok=True)
            print(json.dumps({k: v for k, v in row.items() if not isinstance(v, dict)}),
                  flush=True)
        if 10000 in a.sizes and not a.settle and not no_mpi:  # weak: 10,000 per rank
            w1 = strong[a.sizes.index(10000)]["dpm_1"]
            w2 = run_dpm(LATTICES[20000], a.steps, 2, 1, tmp)
            weak = [{"ranks": 1, "particles": w1["particles"],
                     "particle_steps_per_s": w1["particle_steps_per_s"]},
                    {"ranks": 2, "particles": w2["particles"],
                     "particle_steps_per_s": w2["particle_steps_per_s"],
                     "efficiency": w2["particle_steps_per_s"]
                     / (2 * w1["particle_steps_per_s"]), "shares": shares(w2)}]
        over = None
        if a.oversubscribe and not no_mpi:
            lat = LATTICES[a.sizes[0]]
            over = run_dpm(lat, min(a.steps, 500), a.oversubscribe, 1, tmp, True,
                           settled_packing(lat, a.settle) if a.settle else None)
    result = {"scene": "box_settle", "mpi": no_mpi or f"dpm on 2 ranks ({_mpiexec()})",
              "peer": harness.peer(a.no_liggghts), "strong": strong, "weak": weak,
              "oversubscribed_correctness_run": over}
    path = harness.write("mpi_scaling", result, a.quick, a.tag)
    harness.png(plot, result, path=path.with_suffix(".png"))
    print(f"wrote {path} and .png")


if __name__ == "__main__":
    main()
