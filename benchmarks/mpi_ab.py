"""A/B of two source trees of dpm on MPI ranks: the box_settle worker of
``mpi_scaling.py`` run from each tree in turn (``PYTHONPATH``), in one sitting.

Each round runs tree A, then tree B, each as ``mpiexec -n R python mpi_scaling.py
--worker ...`` with its own tree first on the path (dpm installed in editable mode loses
to ``PYTHONPATH``). Prints and writes (``results/mpi_ab.json``) the particle-steps per
second of every run, the medians and their ratio B / A, and each tree's per-rank split of
the last run (stepping, step kernels, halo, migration, gather).

    git worktree add /tmp/before <commit>
    python benchmarks/mpi_ab.py /tmp/before . --lattice 20 20 25 --steps 3000 --rounds 3
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


def run(tree: Path, lat: list[int], steps: int, ranks: int, out: Path) -> dict:
    from mpi_scaling import _mpiexec

    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI"))}
    env["PYTHONPATH"] = str(tree.resolve())
    env["NUMBA_NUM_THREADS"] = "1"
    env.setdefault("DPM_KERNELS", "scene")
    script = tree.resolve() / "benchmarks" / "mpi_scaling.py"
    cmd = [_mpiexec(), "--allow-run-as-root", "--oversubscribe", "-n", str(ranks),
           "--bind-to", "none", sys.executable, str(script), "--worker", *map(str, lat),
           str(steps), str(out), "1"]
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
    args = ap.parse_args()
    rates: dict[str, list[float]] = {"a": [], "b": []}
    last: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds + 1):  # (round 0 warms both trees' caches, untimed)
            for key in ("a", "b"):
                res = run(getattr(args, key), args.lattice, args.steps, args.ranks,
                          Path(tmp) / f"{key}.json")
                if r:
                    rates[key].append(res["particle_steps_per_s"])
                    last[key] = res
                    print(key, f"{res['particle_steps_per_s']:.4g}", flush=True)
    med = {k: statistics.median(v) for k, v in rates.items()}
    split = {k: [{f: round(row.get(f, 0.0), 4) for f in
                  ("steps_s", "work_s", "halo_s", "wait_s", "migrate_s", "gather_s",
                   "scatter_s",
                   "calls", "rebuilds", "recuts", "owned", "ghosts", "touching_weight")}
                 for row in last[k]["ranks"]] for k in last}
    out = {"a": str(args.a), "b": str(args.b), "lattice": args.lattice,
           "steps": args.steps, "ranks": args.ranks, "particle_steps_per_s": rates,
           "median": med, "b_over_a": med["b"] / med["a"], "split_last_run": split}
    print(f"median A {med['a']:.4g}, B {med['b']:.4g}: B / A = {out['b_over_a']:.3f}")
    res_dir = HERE / "results"
    res_dir.mkdir(exist_ok=True)
    (res_dir / f"{args.tag}.json").write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
