"""Cold compile of two scene kinds in turn, as a new user meets them: time to the first
steps of a first scene in an empty cache, then of a second scene that differs only in its
integrator (a new step module; whatever the first left in the cache is reused).

An A/B of checkouts, in one sitting, rounds alternated, each run with its own PYTHONPATH
and a fresh cache directory per round:

    git worktree add /tmp/before <commit>
    python benchmarks/compile_kinds.py /tmp/before . --rounds 2

``--boundaries many`` adds far-away boundaries of every other built-in kind (wall, tube,
bend, mesh, sieve) to the box: a step module of six boundary kinds, as the test suite's
sentinel scenes; ``--integrators velocity_verlet`` times the first scene only.

Writes ``benchmarks/results/compile_kinds.json`` (seconds per process, from its start to
the end of its first 5 steps, one thread, the scene's own step module).
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

SCENE = """
import time
t0 = time.perf_counter()
import dpm
sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81), integrator={integrator!r}, threads=1)
g = dpm.Material("g", density=2500, young=1e7, poisson=0.3)
sim.contact(g, g, model="hertz_mindlin", restitution=0.5, friction=0.5)
sim.add_boundary("box", material=g, lower=(0, 0, 0), upper=(0.02, 0.02, 0.04), open="+z")
sim.add_particles("sphere", material=g, radius=2e-3,
                  positions=dpm.lattice((0, 0, 0), (0.02, 0.02, 0.02), spacing=4.5e-3))
if {many}:
    F = 10.0
    sim.add_boundary("wall", material=g, center=(F, 0, 0), half_extents=(0.01, 0.01))
    sim.add_boundary("tube", material=g, start=(F, F, 0), axis=(0, 0, 1), length=0.01,
                     radius=0.01)
    sim.add_boundary("bend", material=g, center=(-F, 0, 0), bend_radius=0.05,
                     pipe_radius=0.01, angle=1.0)
    sim.add_boundary("mesh", material=g, vertices=[(0, F, 0), (0.01, F, 0), (0, F + 0.01, 0)],
                     faces=[(0, 1, 2)])
    sim.add_boundary("sieve", material=g, center=(0, -F, 0), half_extents=(0.01, 0.01),
                     hole=2e-3, bar=1e-3, clearance_model="fixed")
sim.run(steps=5, progress=False)
print(time.perf_counter() - t0)
"""

KINDS = ("velocity_verlet", "symplectic_euler")


def first_steps(tree: Path, cache: Path, integrator: str, many: bool = False) -> float:
    env = dict(os.environ, PYTHONPATH=str(tree), DPM_CACHE_DIR=str(cache),
               NUMBA_CACHE_DIR=str(cache), DPM_KERNELS="scene", DPM_BACKGROUND_COMPILE="0",
               DPM_QUIET="1")
    out = subprocess.run([sys.executable, "-c", SCENE.format(integrator=integrator, many=many)],
                         cwd=tempfile.gettempdir(), env=env, capture_output=True, text=True,
                         check=True)
    return float(out.stdout.split()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--tag", default="compile_kinds")
    ap.add_argument("--boundaries", choices=("box", "many"), default="box")
    ap.add_argument("--integrators", nargs="+", default=list(KINDS))
    a = ap.parse_args()
    kinds = a.integrators
    trees = {"before": a.before.resolve(), "after": a.after.resolve()}
    runs: dict[str, list[dict]] = {k: [] for k in trees}
    for r in range(a.rounds):
        for label, tree in trees.items():
            with tempfile.TemporaryDirectory() as cache:
                row = {kind: first_steps(tree, Path(cache), kind, a.boundaries == "many")
                       for kind in kinds}
            runs[label].append(row)
            print(f"round {r + 1} {label}: " + ", ".join(f"{k} {v:.1f} s"
                                                        for k, v in row.items()), flush=True)
    med = {label: {k: statistics.median(x[k] for x in rows) for k in kinds}
           for label, rows in runs.items()}
    commits = {k: subprocess.run(["git", "-C", str(v), "rev-parse", "--short", "HEAD"],
                                 capture_output=True, text=True).stdout.strip()
               for k, v in trees.items()}
    out = {"what": __doc__.splitlines()[0], "trees": {k: str(v) for k, v in trees.items()},
           "commits": commits, "boundaries": a.boundaries,
           "runs_s": runs, "median_s": med,
           "after_over_before": {k: med["after"][k] / med["before"][k] for k in kinds},
           "date": time.strftime("%Y-%m-%d")}
    path = Path(__file__).parent / "results" / f"{a.tag}.json"
    path.write_text(json.dumps(out, indent=1))
    print(json.dumps(out["after_over_before"]), "->", path)


if __name__ == "__main__":
    main()
