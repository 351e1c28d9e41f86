"""A/B of two source trees of dpm on MPI ranks: the box_settle worker of
``mpi_scaling.py`` run from each tree in turn (``PYTHONPATH``), in one sitting.

Each round runs tree A, then tree B, each as ``mpiexec -n R python mpi_scaling.py
--worker ...`` with its own tree first on the path (dpm installed in editable mode loses
to ``PYTHONPATH``). Prints and writes (``results/mpi_ab.json``) the particle-steps per
second of every run, the medians and their ratio B / A, and each tree's per-rank split of
the last run (stepping, step kernels, halo, migration, gather).

    git worktree add /tmp/before <commit>
    python benchmarks/mpi_ab.py /tmp/before . --lattice 20 20 25 --steps 3000 --rounds 3
    python benchmarks/mpi_ab.py /tmp/before . --lattice 40 40 63 --steps 2000 \
        --packing benchmarks/scenes/box_settle/box_settle_40x40x63_settled20000.csv

Also the medians of each part's seconds per run (mean of the ranks): migration with its
list rebuild, gather, halo, step kernels.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))


def run(tree: Path, lat: list[int], steps: int, ranks: int, out: Path,
        packing: Path | None = None) -> dict:
    from mpi_scaling import _mpiexec

    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI"))}
    env["PYTHONPATH"] = str(tree.resolve())
    env["NUMBA_NUM_THREADS"] = "1"
    env.setdefault("DPM_KERNELS", "scene")
    script = tree.resolve() / "benchmarks" / "mpi_scaling.py"
    cmd = [_mpiexec(), "--allow-run-as-root", "--oversubscribe", "-n", str(ranks),
           "--bind-to", "none", sys.executable, str(script), "--worker", *map(str, lat),
           str(steps), str(out), "1"] + ([str(packing.resolve())] if packing else [])
    done = subprocess.run(cmd, env=env, capture_output=True, text=True,
                          stdin=subprocess.DEVNULL, cwd=tree.resolve())
    if done.returncode:
        raise SystemExit(f"mpi_ab: {' '.join(cmd)} failed ({done.returncode}):\n"
                         f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
    return json.loads(out.read_text())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", type=Path, help="tree A (before)")
    ap.add_argument("b", type=Path, help="tree B (after)")
    ap.add_argument("--lattice", type=int, nargs=3, default=[20, 20, 25])
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tag", default="mpi_ab")
    ap.add_argument("--packing", type=Path, default=None,
                    help="start from this bed (a CSV of mpi_scaling.py --settle) instead "
                         "of the lattice")
    args = ap.parse_args()
    rates: dict[str, list[float]] = {"a": [], "b": []}
    # seconds per run in each part, mean of the ranks (the medians are compared)
    parts = ("migrate_s", "relist_s", "gather_s", "halo_s", "work_s")
    part_s: dict[str, dict[str, list[float]]] = {k: {p: [] for p in parts} for k in "ab"}
    last: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds + 1):  # (round 0 warms both trees' caches, untimed)
            for key in ("a", "b"):
                res = run(getattr(args, key), args.lattice, args.steps, args.ranks,
                          Path(tmp) / f"{key}.json", args.packing)
                if r:
                    rates[key].append(res["particle_steps_per_s"])
                    for p in parts:
                        part_s[key][p].append(statistics.mean(
                            row.get(p, 0.0) for row in res["ranks"]))
                    last[key] = res
                    print(key, f"{res['particle_steps_per_s']:.4g}", flush=True)
    med = {k: statistics.median(v) for k, v in rates.items()}
    split = {k: [{f: round(row.get(f, 0.0), 4) for f in
                  ("steps_s", "work_s", "halo_s", "wait_s", "migrate_s", "relist_s",
                   "gather_s", "scatter_s", "calls", "rebuilds", "migrations_skipped",
                   "migrants", "recuts", "owned", "ghosts", "halo_bytes_per_step",
                   "touching_weight")}
                 for row in last[k]["ranks"]] for k in last}
    out = {"a": str(args.a), "b": str(args.b), "lattice": args.lattice,
           "steps": args.steps, "ranks": args.ranks, "particle_steps_per_s": rates,
           "median": med, "b_over_a": med["b"] / med["a"], "split_last_run": split,
           "packing": str(args.packing) if args.packing else None,
           "part_s_mean_of_ranks": part_s,
           "part_s_median": {k: {p: statistics.median(v) for p, v in d.items()}
                             for k, d in part_s.items()}}
    print(f"median A {med['a']:.4g}, B {med['b']:.4g}: B / A = {out['b_over_a']:.3f}")
    for p in parts:
        print(f"  {p} median A {out['part_s_median']['a'][p]:.3f} s, "
              f"B {out['part_s_median']['b'][p]:.3f} s")
    res_dir = HERE / "results"
    res_dir.mkdir(exist_ok=True)
    (res_dir / f"{args.tag}.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
