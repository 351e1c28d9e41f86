"""A/B of the MPI migration's Python part between two source trees of dpm.

Each round runs the box_settle scene on ``--ranks`` ranks (one thread each) from tree A,
then from tree B (``PYTHONPATH``, as ``mpi_ab.py``): 50 steps, then ``--steps`` timed
steps, with ``MpiBackend._migrate`` timed at every call (the exchange, the new rows and
lists' entries; not the list rebuild that follows). Each rank reports its migrations'
mean and median milliseconds and ``migrate_s`` (migration with the list rebuild) as a
share of its stepping time; rank 0 a hash of the end positions by id, which must be the
same for both trees when the change keeps the arithmetic. Writes
``results/<tag>.json``.

    git worktree add /tmp/before <commit>
    python benchmarks/mpi_migration_ab.py /tmp/before . --lattice 40 40 63 --steps 1950
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def worker(lat: list[int], steps: int, out: str) -> None:
    import numpy as np

    sys.path.insert(0, str(HERE))
    from box_settle import _example

    import dpm
    from dpm.parallel.backend import MpiBackend

    ex = _example()
    sim = ex.build(ex.initial_packing(*lat))
    sim.threads = 1
    sim.run(steps=50, progress=False)
    times: list[float] = []
    original = MpiBackend._migrate

    def timed(self, *args, **kw):
        t = time.perf_counter()
        original(self, *args, **kw)
        times.append(time.perf_counter() - t)

    MpiBackend._migrate = timed
    be = sim.backend
    be.totals.clear()
    t0 = time.perf_counter()
    sim.run(steps=steps, progress=False)
    wall = time.perf_counter() - t0
    from mpi4py import MPI

    mine = {"migrations": len(times),
            "mean_ms": 1e3 * float(np.mean(times)) if times else 0.0,
            "median_ms": 1e3 * float(np.median(times)) if times else 0.0,
            "migrate_share": be.totals.get("migrate_s", 0.0) / be.totals["steps_s"],
            "work_s": be.totals.get("work_s", 0.0),
            "skipped": int(getattr(be, "skipped_migrations", 0))}
    ranks = MPI.COMM_WORLD.gather(mine)
    if dpm.parallel.rank() == 0:
        o = np.argsort(sim.bodies.id)
        digest = hashlib.sha1(np.ascontiguousarray(sim.bodies.position[o]).tobytes())
        Path(out).write_text(json.dumps({"wall_s": wall, "ranks": ranks,
                                         "positions_sha1": digest.hexdigest()[:12]}))


def run(tree: Path, lat: list[int], steps: int, ranks: int, out: Path) -> dict:
    from mpi_scaling import _mpiexec

    env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMI"))}
    env["PYTHONPATH"] = str(tree.resolve())
    env["NUMBA_NUM_THREADS"] = "1"
    env.setdefault("DPM_KERNELS", "scene")
    cmd = [_mpiexec(), "--allow-run-as-root", "--oversubscribe", "-n", str(ranks),
           "--bind-to", "none", sys.executable, str(Path(__file__).resolve()), "--worker",
           *map(str, lat), str(steps), str(out)]
    subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    return json.loads(out.read_text())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", nargs="?", type=Path, help="tree A (before)")
    ap.add_argument("b", nargs="?", type=Path, help="tree B (after)")
    ap.add_argument("--lattice", type=int, nargs=3, default=[40, 40, 63])
    ap.add_argument("--steps", type=int, default=1950)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--tag", default="mpi_migration_ab")
    ap.add_argument("--worker", nargs=5, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        *lat, steps, out = args.worker
        worker([int(x) for x in lat], int(steps), out)
        return
    sys.path.insert(0, str(HERE))
    runs: dict[str, list] = {"a": [], "b": []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for name, tree in (("a", args.a), ("b", args.b)):
                res = run(tree, args.lattice, args.steps, args.ranks,
                          Path(tmp) / f"{name}{r}.json")
                runs[name].append(res)
                print(name, "mean ms per migration by rank",
                      [round(x["mean_ms"], 1) for x in res["ranks"]], "skipped",
                      res["ranks"][0]["skipped"], "hash", res["positions_sha1"], flush=True)
    summary = {k: {"mean_ms_by_rank": [statistics.median(run["ranks"][i]["mean_ms"]
                                                         for run in v)
                                       for i in range(args.ranks)],
                   "migrate_share_by_rank": [statistics.median(
                       run["ranks"][i]["migrate_share"] for run in v)
                       for i in range(args.ranks)],
                   "hashes": sorted({run["positions_sha1"] for run in v})}
               for k, v in runs.items()}
    out = HERE / "results" / f"{args.tag}.json"
    out.write_text(json.dumps({"a": str(args.a), "b": str(args.b), "lattice": args.lattice,
                               "steps": args.steps, "ranks": args.ranks, "runs": runs,
                               "median_of_rounds": summary}, indent=1))
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
