"""Parametric study of the tumbling screening machine (Alkhaldi 2007, sec. 4.4).

Runs the sweeps of the thesis on ``examples/screening_machine.py``'s machine, one case per
worker process (``concurrent.futures.ProcessPoolExecutor`` from the standard library, its
workers started fresh: it keeps the pool, hands them the cases and returns results or the
worker's own exception, so no process management is written here), then draws the efficiency against
each parameter beside the thesis' figures and writes every case's figures to JSON.

Sweeps (each against the reference case: 50 rpm, alpha = 1 deg, beta = 0.65 deg,
eccentricity 25 mm, barrel turning with the shaft, 147 particles/s):

- ``rpm``: machine speed 20, 50, 100, 150, 250 rpm (thesis: 78 % at 50, 72 % at 150, 58 %
  at 250, about 40 % at a very low speed),
- ``feed``: 75, 147, 300 particles/s continuous, and the whole package as a batch
  (thesis: efficiency rises with the feed rate; batch better while the mesh is not
  blocked),
- ``inclination``: beta = 0, 0.65, 1.5 deg at alpha = 0, and alpha = 1 at beta = 0.65
  (thesis: 76 % at alpha = 0, beta = 0.65; 78.2 % at alpha = 1, beta = 0.65),
- ``eccentricity``: 0, 40, 100, 300 mm at alpha = beta = 1 deg (thesis: best about 80 %
  at 40 mm, large eccentricities bad),
- ``barrel``: at 150 rpm, zeta = 0.6: spinning with the shaft, fixed, oscillating with
  K = 0.7 and t_p = 0.02 s (thesis: 58 %, 69 %, 75 %),
- ``friction``: particle-deck friction 0, 0.06, 0.15, 0.3 (thesis, on its two-deck glass
  machine: output falls to almost nothing at 0.3; optimum near 0.06).

    python examples/screening_study.py --quick                 # 2 short cases (CI)
    python examples/screening_study.py --until 20 --jobs 2     # the study
    python examples/screening_study.py --sweeps rpm barrel --until 10
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from screening_machine import Case, machine_efficiency, run_case  # noqa: E402

import dpm  # noqa: E402

#: sweep name -> (parameter shown on the x axis, [(x, case changes)], thesis points)
SWEEPS: dict[str, tuple[str, list[tuple[float, dict]], dict[float, float]]] = {
    "rpm": ("machine speed [rpm]",
            [(v, {"rpm": v}) for v in (20.0, 50.0, 100.0, 150.0, 250.0)],
            {50.0: 78.0, 150.0: 72.0, 250.0: 58.0}),
    "feed": ("feed rate [particles/s] (batch drawn at 0)",
             [(v, {"feed_rate": v}) for v in (75.0, 147.0, 300.0)]
             + [(0.0, {"mode": "batch"})], {}),
    "inclination": ("beta [deg] (alpha = 0; the star: alpha = 1)",
                    [(v, {"alpha": 0.0, "beta": v}) for v in (0.0, 0.65, 1.5)]
                    + [(0.65001, {"alpha": 1.0, "beta": 0.65})],
                    {0.65: 76.0, 0.65001: 78.2}),
    "eccentricity": ("shaft eccentricity [mm]",
                     [(v, {"eccentricity": v / 1000, "alpha": 1.0, "beta": 1.0})
                      for v in (0.0, 40.0, 100.0, 300.0)], {40.0: 80.0}),
    "barrel": ("barrel: 0 spinning, 1 fixed, 2 oscillating K = 0.7",
               [(0.0, {"rpm": 150.0, "zeta": 0.6, "barrel": "free"}),
                (1.0, {"rpm": 150.0, "zeta": 0.6, "barrel": "fixed"}),
                (2.0, {"rpm": 150.0, "zeta": 0.6, "barrel": "oscillating",
                       "oscillation_factor": 0.7, "oscillation_period": 0.02})],
               {0.0: 58.0, 1.0: 69.0, 2.0: 75.0}),
    "friction": ("particle-deck friction coefficient",
                 [(v, {"wall_friction": v}) for v in (0.0, 0.06, 0.15, 0.3)], {}),
}


def cases(names: list[str], base: Case) -> list[tuple[str, float, Case]]:
    out = []
    for name in names:
        if name not in SWEEPS:
            raise SystemExit(f"screening_study: unknown sweep {name!r}; "
                             f"allowed: {', '.join(SWEEPS)}")
        for x, change in SWEEPS[name][1]:
            out.append((name, x, replace(base, label=f"{name}={x:g}", **change)))
    return out


def draw(results: dict, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(results)
    cols = min(3, len(names))
    rows = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.3 * rows), squeeze=False)
    for ax, name in zip(axes.flat, names, strict=False):
        label, _, thesis = SWEEPS[name]
        pts = sorted(results[name], key=lambda r: r["x"])
        xs = [r["x"] for r in pts]
        ax.plot(xs, [r["machine_efficiency"] for r in pts], "o-", label="dpm, c (eq. 4.33)")
        ax.plot(xs, [100 * r["fraction_exited"] for r in pts], "s:", color="grey",
                label="dpm, exited / fed [%]")
        if thesis:
            tx = sorted(thesis)
            ax.plot(tx, [thesis[x] for x in tx], "k*", ms=10, label="Alkhaldi (2007)")
        ax.set_xlabel(label, fontsize=8)
        ax.set_ylabel("%")
        ax.set_ylim(0, 100)
        ax.grid(alpha=0.3)
        ax.set_title(name)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=90)


def main(argv: list[str] | None = None) -> None:
    if dpm.parallel.launched_ranks() > 1:  # (every rank would run every case, in pools)
        raise SystemExit("screening_study.py runs its cases in a process pool of its own "
                         "(--jobs): start it without mpiexec; under mpiexec, run one case "
                         "with screening_machine.py")
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sweeps", nargs="*", default=list(SWEEPS), help="which sweeps")
    p.add_argument("--until", type=float, default=20.0, help="simulated time per case [s]")
    p.add_argument("--particles", type=int, default=3483, help="package size")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="worker processes")
    p.add_argument("--quick", action="store_true",
                   help="two cases of 0.3 s with 150 particles (a check that it runs)")
    p.add_argument("--output", default="screening_study", help="output stem (.json, .png)")
    p.add_argument("--replot", action="store_true",
                   help="recompute the figures from the output's JSON and redraw (no runs)")
    args = p.parse_args(argv)
    if args.replot:
        path = Path(args.output).with_suffix(".json")
        out = json.loads(path.read_text())
        for rs in out["results"].values():
            for r in rs:
                r["machine_efficiency"] = machine_efficiency(r["sorted"], r["gangue"])
        path.write_text(json.dumps(out, indent=1))
        draw(out["results"], str(Path(args.output).with_suffix(".png")))
        return
    base = Case(until=args.until, particles=args.particles)
    todo = cases(args.sweeps, base)
    if args.quick:
        base = Case(until=0.3, particles=150)
        todo = [(n, x, replace(c, until=0.3, particles=150))
                for n, x, c in cases(["barrel"], base)[1:]]
    results: dict[str, list[dict]] = {}
    t0 = time.perf_counter()
    # fresh interpreters ("spawn"), not forks: a fork of a process whose numba threading
    # layer (OpenMP) has started can die in the child
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=max(1, args.jobs), mp_context=spawn) as pool:
        jobs = {pool.submit(run_case, c): (n, x) for n, x, c in todo}
        for fut in as_completed(jobs):
            name, x = jobs[fut]
            r = fut.result()
            r["x"] = x
            r["fraction_exited"] = r["exited"] / max(r["fed"], 1)
            r.pop("series", None) if args.quick else None
            results.setdefault(name, []).append(r)
            print(f"{name} = {x:g}: c = {r['machine_efficiency']:.1f} %, exited "
                  f"{r['exited']} of {r['fed']}, {r['wall_s']:.0f} s wall", flush=True)
    wall = time.perf_counter() - t0
    out = {"command": "python examples/screening_study.py " + " ".join(argv or sys.argv[1:]),
           "wall_s": wall, "jobs": args.jobs, "base": asdict(base), "results": results,
           "thesis": {n: {str(k): v for k, v in SWEEPS[n][2].items()} for n in results}}
    Path(args.output).with_suffix(".json").write_text(json.dumps(out, indent=1))
    draw(results, str(Path(args.output).with_suffix(".png")))
    print(f"{len(todo)} cases in {wall:.0f} s; {args.output}.json, {args.output}.png")


if __name__ == "__main__":
    main()
