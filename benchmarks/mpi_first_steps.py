"""Time to the first steps of a scene on MPI ranks when its ranked step functions are not
compiled yet: two source trees of dpm in turn, in one sitting.

Each round removes the ranked step functions (``ranked_run``, ``ranked_pre_force``,
``ranked_forces``) from numba's cache of dpm's step modules, then runs the box_settle
worker of ``mpi_scaling.py`` (1,200 spheres, ``--ranks`` ranks) from tree A, and again
for tree B, and reads its ``first_steps_s`` (the first 50 steps, compile included). The
removed cache files are put back at the end. Writes ``results/TAG.json``.

    git worktree add /tmp/before <commit>
    python benchmarks/mpi_first_steps.py /tmp/before . --ranks 3 --rounds 2 --tag X
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
CACHE = Path.home() / ".cache" / "dpm" / "steps" / "__pycache__"


def main() -> None:
    from mpi_ab import run

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a", type=Path, help="tree A (before)")
    ap.add_argument("b", type=Path, help="tree B (after)")
    ap.add_argument("--ranks", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--tag", default="mpi_first_steps")
    args = ap.parse_args()
    kept = Path(tempfile.mkdtemp())
    for f in CACHE.glob("*ranked_*"):
        shutil.copy2(f, kept)
    got = {"a": [], "b": []}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(args.rounds):
                for key in ("a", "b"):
                    for f in CACHE.glob("*ranked_*"):
                        f.unlink()
                    res = run(getattr(args, key), [10, 10, 12], 200, args.ranks,
                              Path(tmp) / f"{key}.json")
                    got[key].append(res["first_steps_s"])
                    print(key, f"{res['first_steps_s']:.1f} s", flush=True)
    finally:
        for f in kept.iterdir():
            shutil.copy2(f, CACHE / f.name)
        shutil.rmtree(kept)
    out = {"ranks": args.ranks, "a": str(args.a), "b": str(args.b),
           "first_steps_s": got,
           "median": {k: statistics.median(v) for k, v in got.items()}}
    print(f"median A {out['median']['a']:.1f} s, B {out['median']['b']:.1f} s")
    (HERE / "results" / f"{args.tag}.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
