"""Time to the first step of every example, as a new user meets it, in three states of
the kernel cache, and the speed of the universal step module against a scene's own.

For each example (``--quick`` size), in a cache directory that holds only what
``dpm compile`` wrote (the universal step modules):

- ``universal``: a new scene after ``dpm compile`` (the default ``kernels="auto"`` takes
  the universal module; the background compile is switched off so that it does not
  share the cores with the next measurement);
- ``cold``: the same scene on its own step module, compiled now (what every new scene
  cost before the universal module, and what a run without ``dpm compile`` costs);
- ``warm``: the scene again, its own module now cached.

Each figure is the whole process from its start to the end of the first step (the
example's first ``Simulation.run`` is cut to one step; the process then exits). Then
box_settle's 10,000 spheres are stepped on both modules, both warm, A/B in turn.

    python benchmarks/first_step.py            # every example, ~20 min on 2 cores
    python benchmarks/first_step.py --examples box_settle rotating_drum
    python benchmarks/first_step.py --quick    # box_settle only; dpm compile of its
                                               # integrator (velocity_verlet) only

Writes ``benchmarks/results/first_step[_quick].json`` and ``.png``.
"""

from __future__ import annotations

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

ROOT = Path(__file__).resolve().parents[1]
#: example -> extra arguments (besides --quick) that keep its files out of the way
EXAMPLES = {
    "box_settle": ["--output", "{tmp}/box.h5"],
    "drop_test": ["--output", "{tmp}"],
    "rotating_drum": ["--output", "{tmp}/drum.h5"],
    "hopper_discharge": ["--output", "{tmp}"],
    "rotary_kiln": ["--output", "{tmp}"],
    "ball_mill": ["--output", "{tmp}"],
    "tumbling_screen": ["--output", "{tmp}/screen.h5"],
    "screening_machine": [],
    "grate": ["--output", "{tmp}"],
}
#: --quick: ``dpm compile`` of box_settle's integrator only (every built-in one: ~10 min
#: on 2 cores; the universal module box_settle takes is this one)
QUICK_INTEGRATORS = ["velocity_verlet"]

#: run an example until the end of its first step (its first Simulation.run cut to one)
FIRST_STEP = r"""
import os, runpy, sys
import dpm
_run = dpm.Simulation.run
def first(self, *a, **kw):
    _run(self, steps=1, progress=False)
    print("FIRST_STEP universal=%d" % int(getattr(self.backend, "universal", False)),
          flush=True)
    os._exit(0)
dpm.Simulation.run = first
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
"""


def timed(cmd: list[str], env: dict, cwd: str) -> tuple[float, str]:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{r.stdout[-2000:]}\n{r.stderr[-3000:]}")
    return wall, r.stdout


def first_step(example: str, env: dict, tmp: str) -> tuple[float, bool]:
    args = [a.format(tmp=tmp) for a in EXAMPLES[example]]
    path = str(ROOT / "examples" / f"{example}.py")
    wall, out = timed([sys.executable, "-c", FIRST_STEP, path, "--quick", *args], env, tmp)
    m = re.search(r"FIRST_STEP universal=(\d)", out)
    if m is None:
        raise RuntimeError(f"{example}: no first step seen:\n{out[-2000:]}")
    return wall, m.group(1) == "1"


def speed(env: dict, tmp: str, pairs: int, steps: int) -> dict:
    """Whole-process wall of box_settle (10,000 spheres, ``steps`` steps), universal and
    own module in turn, both warm."""
    cmd = [sys.executable, str(ROOT / "examples" / "box_settle.py"), "--steps", str(steps)]
    walls: dict[str, list[float]] = {"scene": [], "universal": []}
    for kernels in ("scene", "universal"):  # warm both first
        timed([*cmd[:2], "--steps", "10"], dict(env, DPM_KERNELS=kernels), tmp)
    for _ in range(pairs):
        for kernels in ("scene", "universal"):
            walls[kernels].append(timed(cmd, dict(env, DPM_KERNELS=kernels), tmp)[0])
    med = {k: statistics.median(v) for k, v in walls.items()}
    return {"steps": steps, "spheres": 10000, "walls_s": walls, "median_s": med,
            "universal_over_own": med["universal"] / med["scene"]}


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(result["examples"])
    fig, ax = plt.subplots(figsize=(9, 4.2))
    width = 0.27
    for k, (state, colour) in enumerate((("cold", "tab:red"), ("universal", "tab:blue"),
                                         ("warm", "tab:green"))):
        xs = [i + (k - 1) * width for i in range(len(names))]
        ax.bar(xs, [result["examples"][n][state] for n in names], width, color=colour,
               label={"cold": "own module compiled now",
                      "universal": "new scene after `dpm compile`",
                      "warm": "own module cached"}[state])
    ax.axhline(15, color="k", lw=0.8, ls="--")
    ax.text(len(names) - 0.5, 15.5, "15 s goal", ha="right", fontsize=8)
    ax.set_xticks(range(len(names)), names, rotation=30, ha="right")
    ax.set_ylabel("process start to end of first step [s]")
    ax.set_title(f"Time to the first step ({result['machine']})", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> int:
    ap = harness.parser(__doc__, "box_settle only, dpm compile of velocity_verlet only, one "
                        "A/B pair of 300 steps")
    ap.add_argument("--examples", nargs="*", default=None, choices=list(EXAMPLES))
    ap.add_argument("--jobs", type=int, default=2, help="dpm compile --jobs")
    ap.add_argument("--pairs", type=int, default=None, help="A/B pairs of the speed run (3)")
    ap.add_argument("--steps", type=int, default=None, help="steps of the speed run (3000)")
    ap.add_argument("--out", default=None, help="JSON path (results/first_step[_quick].json)")
    args = ap.parse_args()
    if args.examples is None:
        args.examples = ["box_settle"] if args.quick else list(EXAMPLES)
    args.pairs = args.pairs or (1 if args.quick else 3)
    args.steps = args.steps or (300 if args.quick else 3000)
    root = Path(tempfile.mkdtemp(prefix="dpm-first-step-"))
    base = root / "compiled"
    env = dict(os.environ, DPM_CACHE_DIR=str(base), DPM_BACKGROUND_COMPILE="0",
               DPM_THREADS="1")
    env.pop("NUMBA_CACHE_DIR", None)
    only = [x for i in QUICK_INTEGRATORS for x in ("--integrator", i)] if args.quick else []
    compile_s, _ = timed([sys.executable, "-m", "dpm.cli", "compile", "--jobs",
                          str(args.jobs), *only], env, str(root))
    print(f"dpm compile --jobs {args.jobs} {' '.join(only)}: {compile_s:.1f} s", flush=True)
    result = {"dpm_compile_s": compile_s, "dpm_compile_jobs": args.jobs,
              "dpm_compile_integrators": QUICK_INTEGRATORS if args.quick else "every built-in",
              "examples": {}}
    facts = harness.machine()  # (the plot's title names the machine)
    result["machine"] = f"{facts['cpu']}, {facts['cpu_count']} cores"
    for ex in args.examples:
        cache = root / ex
        shutil.copytree(base, cache)
        tmp = tempfile.mkdtemp(dir=root)
        e = dict(env, DPM_CACHE_DIR=str(cache))
        uni, used = first_step(ex, dict(e, DPM_KERNELS="auto"), tmp)
        cold, _ = first_step(ex, dict(e, DPM_KERNELS="scene"), tmp)
        warm, own = first_step(ex, dict(e, DPM_KERNELS="auto"), tmp)
        result["examples"][ex] = {"universal": uni, "cold": cold, "warm": warm,
                                  "universal_used": used, "warm_used_own": not own}
        print(f"{ex}: cold {cold:.1f} s, after dpm compile {uni:.1f} s "
              f"(universal: {used}), warm {warm:.1f} s", flush=True)
    spd = speed(env, str(root), args.pairs, args.steps)
    result["box_settle_speed"] = spd
    print(f"box_settle 10,000 x {args.steps}: universal / own wall "
          f"{spd['universal_over_own']:.3f}", flush=True)
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result | {"run": harness.machine()}, indent=1))
    else:
        out = harness.write("first_step", result, args.quick)
    harness.png(plot, result, path=out.with_suffix(".png"))
    shutil.rmtree(root, ignore_errors=True)
    print(f"wrote {out} and {out.with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
