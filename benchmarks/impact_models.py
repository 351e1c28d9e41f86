"""Impact models: error against steps per contact, and cost per contact evaluation.

For every registered built-in model a sphere (r = 1 mm, 2500 kg/m3, E = 10 MPa, nu = 0.3)
hits a wall head-on at 0.5 m/s with dt = T/n for n steps per contact (T: the analytic
contact duration). The measured duration, largest overlap and restitution are compared
with the model's analytic solution (closed forms, or scipy's solve_ivp of the force law
as its docstring writes it, implemented here independently of dpm's own helpers).

Cost: (1) the law alone, ns per call, from a numba loop over 100,000 contact states;
(2) the engine, ns per active contact per step (best of three runs of 60 steps at
T/200), for a cubic lattice of slightly overlapping spheres (about 3 contacts per sphere),
velocity Verlet, one thread: the whole step divided by the contacts, so it includes the
integration and the neighbour list.

Writes benchmarks/results/impact_models.json and impact_models.png (``--quick``:
impact_models_quick.*) and prints the speed-against-error table.

    python benchmarks/impact_models.py            # n = 10 .. 1000, lattice 20^3
    python benchmarks/impact_models.py --quick    # n = 10, 50, 200, lattice 10^3
"""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import harness
import numba
import numpy as np
from numba import njit
from scipy.spatial import cKDTree
from shared_scenes import (  # the head-on impact and its analytic references
    ESTAR,
    KH,
    NAMES,
    NU,
    RHO,
    YOUNG,
    M,
    R,
    V,
    linear_for,
    maw_k,
    ode,
    tsuji,
)

import dpm
from dpm.impact.measure import collide

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module

HERE = Path(__file__).resolve().parent


def cases() -> list[dict]:
    """Model, parameters, analytic reference, and the end-of-contact force exponent."""
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    reg = dpm.registry()

    def law(name, **p):
        return reg.lookup("impact_model", name)(**p)

    e = 0.5
    hm = law("hertz_mindlin", restitution=e)
    hb = law("hertz_brilliantov", restitution=e, reference_speed=V)
    A = hb.dissipation(mat, mat, M, R, V)
    kc = 2e4
    lc = law("linear_cohesion", restitution=e, cohesion_energy_density=kc)
    tsuji_lc = tsuji(lc.beta)
    kl = 1e4
    out = [
        {"model": "linear_spring_dashpot", "params": {"stiffness": 1e4, "restitution": e},
         "ref": linear_for(1e4, e)},
        {"model": "hooke", "params": {"restitution": e},
         "ref": linear_for(4 / 3 * ESTAR * R, e)},
        {"model": "maw_linear_spring", "params": {"restitution": e, "impact_velocity": V},
         "ref": linear_for(maw_k(V), e)},
        {"model": "walton_braun", "params": {"stiffness": kl, "restitution": e},
         "ref": {"duration": math.pi / 2 * (math.sqrt(M / kl) + math.sqrt(M * e * e / kl)),
                 "max_overlap": V * math.sqrt(M / kl), "restitution": e}},
        {"model": "hertz_mindlin", "params": {"restitution": e}, "ref": ode(tsuji(hm.beta))},
        {"model": "hertz_mindlin", "label": "hertz_mindlin (e=1)",
         "params": {"restitution": 1.0}, "end_exponent": 1.5,
         "ref": {"duration": 2.868265699194 * (M * M / (R * ESTAR**2 * V)) ** 0.2,
                 "max_overlap": (15 * M * V * V / (16 * ESTAR * math.sqrt(R))) ** 0.4,
                 "restitution": 1.0}},
        {"model": "hertz_brilliantov", "params": {"dissipation": A},
         "ref": ode(lambda d, dd: max(KH * (d**1.5 + A * math.sqrt(d) * dd), 0.0))},
        {"model": "linear_cohesion", "params": {"restitution": e, "cohesion_energy_density": kc},
         "ref": ode(lambda d, dd: tsuji_lc(d, dd) - kc * math.pi * R * d, release=False)},
    ]
    for c in out:
        c.setdefault("label", c["model"])
        c["params"]["friction"] = 0.3
    return out


# -------------------------------------------------------------------------- cost


@njit(cache=True)
def _drive(law, p, delta, ddelta, vt, meff, reff, dt, hist, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(delta.shape[0]):
            fn, fx, fy, fz, _, _, _ = law(p, delta[i], ddelta[i], vt[i, 0], vt[i, 1], 0.0,
                                          0.0, 0.0, 1.0, meff, reff, 0.0, 0.0, 0.0, dt, hist,
                                          i)
            acc += fn + fx + fy
    return acc


def kernel_cost(case: dict, n: int = 100_000, reps: int = 20) -> float:
    """ns per call of the law alone on n contact states (overlaps up to the peak)."""
    reg = dpm.registry()
    cls = reg.lookup("impact_model", case["model"])
    law = cls(**case["params"])
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    p = tuple(law.pair_row(mat, mat, dpm.impact.PairContext(V, M, R)))
    p = p + (0.0,) * (8 - len(p))  # the step's row: a tuple of (at least) 8 floats
    f = dpm.plan.law_module([law.law_spec()]).law_0  # the law composed from its parts
    rng = np.random.default_rng(1)
    dmax = case["ref"]["max_overlap"]
    delta = rng.uniform(0.0, dmax, n)
    ddelta = rng.uniform(-V, V, n)
    vt = rng.normal(0.0, 0.1 * V, (n, 2))
    hist = np.zeros((n, max(law.history_width(), 1)))
    dt = case["ref"]["duration"] / 50
    _drive(f, p, delta[:10], ddelta[:10], vt[:10], M, R, dt, hist, 1)  # compile
    best = math.inf
    for _ in range(3):
        hist[:] = 0.0
        t0 = time.perf_counter()
        _drive(f, p, delta, ddelta, vt, M, R, dt, hist, reps)
        best = min(best, time.perf_counter() - t0)
    return best / (n * reps) * 1e9


def engine_cost(case: dict, side: int, steps: int) -> float:
    """ns per active contact per step of the whole step (contacts, integration, lists), one
    thread, the scene's step specialised to this law alone."""
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        return _engine_cost(case, side, steps)
    finally:
        numba.set_num_threads(threads)


def _engine_cost(case: dict, side: int, steps: int) -> float:
    sim = dpm.Simulation(dt=case["ref"]["duration"] / 200, dt_check="off")
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    sim.contact(mat, mat, model=case["model"], **case["params"])
    g = np.arange(side) * (2 * R - 0.2 * case["ref"]["max_overlap"])
    pos = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    sim.add_particles("sphere", material=mat, radius=R, positions=pos)
    sim.run(steps=5, progress=False)  # compile / load and prime
    best = math.inf
    for _ in range(3):
        before = len(cKDTree(sim.bodies.position).query_pairs(2 * R))
        t0 = time.perf_counter()
        sim.run(steps=steps, progress=False)
        wall = time.perf_counter() - t0
        after = len(cKDTree(sim.bodies.position).query_pairs(2 * R))
        best = min(best, wall / (steps * 0.5 * (before + after)) * 1e9)
    return best


# -------------------------------------------------------------------------- run


def errors(case: dict, n: int) -> dict:
    ref = case["ref"]
    c = collide(case["model"], case["params"], speed=V, dt=ref["duration"] / n, radii=(R,),
                density=RHO, young=YOUNG, poisson=NU,
                end_exponent=case.get("end_exponent", 1.0), bind_models=NAMES)
    return {"steps_per_contact": n, "dt": c.dt,
            "duration": c.duration, "max_overlap": c.max_overlap, "restitution": c.restitution,
            "duration_err": c.duration / ref["duration"] - 1,
            "max_overlap_err": c.max_overlap / ref["max_overlap"] - 1,
            "restitution_err": c.restitution / ref["restitution"] - 1}


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 8.5))
    keys = [("duration_err", "contact duration"), ("max_overlap_err", "largest overlap"),
            ("restitution_err", "restitution")]
    for ax, (key, title) in zip(axes.flat, keys, strict=False):
        for m in result["models"]:
            n = [r["steps_per_contact"] for r in m["rows"]]
            err = [max(abs(r[key]), 1e-9) for r in m["rows"]]
            ax.loglog(n, err, "o-", label=m["label"])
        ax.set_xlabel("steps per contact")
        ax.set_ylabel("|relative error|")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    ax = axes[1, 1]
    labels = [m["label"] for m in result["models"]]
    y = np.arange(len(labels))
    ax.barh(y - 0.2, [m["kernel_ns_per_call"] for m in result["models"]], 0.4,
            label="law alone, ns / call")
    ax.barh(y + 0.2, [m["engine_ns_per_contact_step"] for m in result["models"]], 0.4,
            label="engine, ns / contact / step")
    ax.set_yticks(y, labels, fontsize=7)
    ax.set_xlabel("ns")
    ax.set_title("cost per contact evaluation")
    ax.legend(fontsize=7, loc="lower right")
    fig.suptitle(f"dpm impact models: sphere on a wall at {V} m/s, velocity Verlet")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    ap = harness.parser(__doc__, "fewer step counts, small lattice")
    args = ap.parse_args(argv)
    ns = [10, 50, 200] if args.quick else [10, 20, 50, 100, 200, 500, 1000]
    side, steps = (10, 40) if args.quick else (20, 60)
    models = []
    for case in cases():
        rows = [errors(case, n) for n in ns]
        models.append({"model": case["model"], "label": case["label"],
                       "params": case["params"], "reference": case["ref"], "rows": rows,
                       "kernel_ns_per_call": kernel_cost(case),
                       "engine_ns_per_contact_step": engine_cost(case, side, steps)})
        print(f"done {case['label']}", flush=True)
    result = {"scene": {"radius_m": R, "density": RHO, "young_Pa": YOUNG, "poisson": NU,
                        "impact_speed_m_s": V, "geometry": "sphere on a wall, head-on",
                        "integrator": "velocity_verlet", "lattice": side**3},
              "models": models}
    path = harness.write("impact_models", result, args.quick)
    harness.png(plot, result, path=path.with_suffix(".png"))
    # the table a user reads to pick a model
    pick = [n for n in (20, 50, 200) if n in ns] or ns
    head = " | ".join(f"{k} @{n}" for n in pick for k in ("T", "dmax", "e"))
    print(f"\n| model | {head} | law ns/call | engine ns/contact |")
    print("|---" * (3 + 3 * len(pick)) + "|")
    for m in models:
        by = {r["steps_per_contact"]: r for r in m["rows"]}
        cells = " | ".join(f"{100 * by[n][k]:+.2f}%" for n in pick
                           for k in ("duration_err", "max_overlap_err", "restitution_err"))
        print(f"| {m['label']} | {cells} | {m['kernel_ns_per_call']:.1f} | "
              f"{m['engine_ns_per_contact_step']:.1f} |")
    print(f"\nwrote {path} and .png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
