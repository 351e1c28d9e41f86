"""The step module's two forms on small and mesh scenes: the parallel form (``prange``
loops, one parallel launch each even on one thread) against the one-thread form that a run
on one thread takes (:func:`dpm.plan.one_thread_form`), chosen in turn on the same scenes
in one process by ``$DPM_ONE_THREAD_FORM`` (benchmarks/NOTES.md rows 46 and 50).

The scenes are ``boundaries.mesh_scaling``'s floors (with its far-away sentinel
boundaries, ``sphere_orientation=False``): 1 sphere on 2 triangles, 81 spheres on 200,
2,000 spheres on one 210 mm floor of 200 and of 2,048 triangles. Prints ns per
sphere-step of each form and their ratio, three rounds (``results/step_forms.json``).
``--box-settle``: the box_settle scene instead (``results/step_forms_box_settle.json``);
``--meshgran``: the meshGran port's loop (``results/step_forms_meshgran.json``);
``--clusters``: the settled bed of 2,000 clusters (``results/step_forms_clusters.json``).

    python benchmarks/step_forms.py
    python benchmarks/step_forms.py --box-settle 20 20 25 --steps 5000   # 10,000 spheres
    python benchmarks/step_forms.py --meshgran
    python benchmarks/step_forms.py --clusters
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

sys.path.insert(0, str(Path(__file__).resolve().parent))

CASES = [(1, None, 1), (10, None, 81), (10, 0.21, 2000), (32, 0.21, 2000)]


def scene(m: int, side: float | None, n_spheres: int):
    import boundaries as B

    import dpm

    cell = 4e-3 if side is None else side / m
    verts, faces = B.grid_floor(m, cell)
    a = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    w = dpm.Material("steel", density=7800.0, young=2e7, poisson=0.3)
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, 0), dt_check="off", threads=1,
                         skin=B.SKIN, sphere_orientation=False)
    sim.contact(a, a, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.contact(a, w, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("mesh", material=w, vertices=verts, faces=faces)
    B.sentinels(sim, w)
    half, r = 0.5 * m * cell, B.R
    rng = np.random.default_rng(1)
    k = max(1, min(int(math.ceil(math.sqrt(n_spheres))), int(2 * half / (2.2 * r))))
    g = (np.arange(k) - 0.5 * (k - 1)) * 2.2 * r
    xy = np.array([(x, y) for x in g for y in g])[:n_spheres]
    xy = xy + rng.uniform(-0.02 * r, 0.02 * r, xy.shape)
    sim.add_particles("sphere", material=a, radius=r,
                      positions=np.c_[xy, np.full(len(xy), r * 0.9999)])
    sim.run(steps=5, progress=False)
    return sim


def forms_in_turn(label: str, measure, rounds: int, field: str, unit: str, stem: str,
                  ratio_name: str = "one_thread_over_parallel", **meta) -> None:
    """``measure()`` (one figure, in ``unit``) on the parallel form, then the one-thread
    form, ``rounds`` pairs after one untimed pair; prints each, writes ``results/<stem>.json``
    (``meta``, the figures under ``field``, their medians and one-thread over parallel)."""
    import statistics

    vals: dict[str, list[float]] = {"parallel": [], "one_thread": []}
    for r in range(rounds + 1):
        for flag, key in (("0", "parallel"), ("1", "one_thread")):
            os.environ["DPM_ONE_THREAD_FORM"] = flag  # (read at each run's start)
            v = measure()
            if r:
                vals[key].append(v)
                print(f"{label} {key} form: {v:.4g} {unit}", flush=True)
    med = {k: statistics.median(v) for k, v in vals.items()}
    out = meta | {field: vals, "median": med,
                  ratio_name: med["one_thread"] / med["parallel"]}
    print(f"medians: parallel {med['parallel']:.4g}, one-thread {med['one_thread']:.4g} "
          f"{unit}: one-thread / parallel {out[ratio_name]:.3f}")
    path = Path(__file__).resolve().parent / "results" / f"{stem}.json"
    path.write_text(json.dumps(out, indent=1))


def box_settle_ab(lattice: list[int], steps: int, rounds: int) -> None:
    """box_settle (``box_settle.run_dpm``, one thread, a new scene each run) on the two
    forms in turn; particle-steps per second."""
    import box_settle

    forms_in_turn(f"box_settle {'x'.join(map(str, lattice))}",
                  lambda: box_settle.run_dpm(lattice, steps, threads=1)["particle_steps_per_s"],
                  rounds, "particle_steps_per_s", "particle-steps/s", "step_forms_box_settle",
                  lattice=lattice, steps=steps)


def meshgran_ab(rounds: int) -> None:
    """The meshGran port's dpm loop (``meshgran.run_dpm``: 500 spheres streamed in over
    0.5 s, run to 2.5 s, one thread) on the two forms in turn; particle-steps per second
    over the whole loop."""
    import meshgran

    forms_in_turn("meshGran", lambda: meshgran.run_dpm(0.5, 2.5)["particle_steps_per_s"],
                  rounds, "particle_steps_per_s", "particle-steps/s", "step_forms_meshgran")


def clusters_ab(rounds: int, steps: int) -> None:
    """``clusters_settle.py``'s 2,000 four-sphere clusters from its own lattice start,
    settled on two threads (its settle steps), then on one thread the two forms in turn on
    that bed, ``steps`` steps each; us per step."""
    import clusters_settle as cs

    geo = cs.geometry(2000, side=0.035)
    sim = cs.scene(cs.own_start(2000, geo), geo)
    sim.threads = 2
    sim.run(steps=geo["settle_steps"], progress=False)
    sim.threads = 1

    def us_per_step() -> float:
        t = time.perf_counter()
        sim.run(steps=steps, progress=False)
        return (time.perf_counter() - t) / steps * 1e6

    forms_in_turn("settled clusters", us_per_step, rounds, "us_per_step", "us per step",
                  "step_forms_clusters", "one_thread_over_parallel_time", bodies=2000,
                  steps_each=steps)


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--box-settle", type=int, nargs=3, metavar=("NX", "NY", "NZ"),
                    help="instead: box_settle of this lattice on the two forms in turn")
    ap.add_argument("--meshgran", action="store_true",
                    help="instead: the meshGran port's loop on the two forms in turn")
    ap.add_argument("--clusters", action="store_true",
                    help="instead: the settled bed of clusters_settle.py on the two forms")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    if args.box_settle:
        box_settle_ab(args.box_settle, args.steps, args.rounds)
        return
    if args.meshgran:
        meshgran_ab(args.rounds)
        return
    if args.clusters:
        clusters_ab(args.rounds, min(args.steps, 2000))
        return
    sims = [scene(*c) for c in CASES]
    t0 = time.perf_counter()
    for s in sims:  # compile (or load) both forms
        for flag in ("0", "1"):
            os.environ["DPM_ONE_THREAD_FORM"] = flag
            s.run(steps=5, progress=False)
    print(f"both forms ready in {time.perf_counter() - t0:.0f} s", flush=True)
    rows = []
    for r in range(3):
        for case, s in zip(CASES, sims, strict=True):
            ns = []
            for flag in ("0", "1"):  # (the module is chosen at each run's start)
                os.environ["DPM_ONE_THREAD_FORM"] = flag
                n = max(1000, int(1e6 / len(s.bodies)))
                s.run(steps=200, progress=False)
                t = time.perf_counter()
                s.run(steps=n, progress=False)
                ns.append((time.perf_counter() - t) / n / len(s.bodies) * 1e9)
            rows.append({"round": r, "triangles": 2 * case[0] ** 2, "spheres": case[2],
                         "parallel_form_ns": ns[0], "one_thread_form_ns": ns[1],
                         "ratio": ns[1] / ns[0]})
            print(f"floor m={case[0]} side={case[1]} spheres={case[2]}: ns per sphere-step "
                  f"parallel form {ns[0]:.1f}, one-thread form {ns[1]:.1f}, "
                  f"ratio {ns[1] / ns[0]:.3f}", flush=True)
    out = Path(__file__).resolve().parent / "results" / "step_forms.json"
    out.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
