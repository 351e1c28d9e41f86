"""`dpm advise` on three scenes: the advisor's choice at 1 % and 5 % against a fine reference.

Scenes and quantities (``examples/``):

1. box_settle: glass spheres settling in an open box (Hertz-Mindlin, e = 0.3, 0.2 s: at
   rest); the settled height (mean centre height above the floor at the end);
2. rotating_drum: 4 mm glass beads in a 100 mm drum at 20 rpm; the dynamic angle of
   repose, the mean over samples every 0.02 s in the second half of the run;
3. hopper: the flat-bottomed silo of ``examples/hopper_discharge.py`` (5 mm beads, plug
   switched off at 0.25 s); the discharge rate in a window after the start-up transient.

Two phases, one thread per run, the scenes' own compiled step modules
(``DPM_KERNELS=scene``); the replicas run side by side on a pool of ``--workers`` processes
(default 2). A replica is an independent run whose start is perturbed by an amount no
measurement tells apart (every body moved by up to 1e-3 of its radius and its velocity
changed by ~1e-7 m/s, seed k for replica k; replica 0 is the scene as built):

- calibration, on the small (``--quick``) size of each scene: R replicas at the coarsest
  step the advisor takes (n_c steps per shortest contact: the engine's 5, 1 % inside, or 0.3
  of the Rayleigh step if smaller) and 1.5, 2 and 3 times it, and R_ref replicas of a
  reference at 80 (``CAL_REPLICAS``: R = R_ref = 1 for box_settle, whose settled height
  scatters by ~0.1 %, far below its step errors; 24 for the drum, 4 for the silo). The
  systematic error of each step, ``|mean_R - mean_ref| / mean_ref``, its standard
  uncertainty ``sigma sqrt(1/R + 1/R_ref)``, and the scatter of one run sigma (the sample
  standard deviation pooled over every step's replicas, each group about its own mean,
  with its degrees of freedom; box_settle: a twin against the example's set-up, one
  degree of freedom) go to ``advise.json`` and, condensed (``python -m
  dpm.advice.condense``), into the advisor's tables before it is asked;
- check, on the full size: for each tolerance the advice (``dpm.advise``: the step and the
  replicas N), N runs of it (at most ``--max-runs``; an advice needing more is reported,
  not verified), R_ref replicas of the reference (``CHECK_REF_REPLICAS``) and one run of
  the example's own set-up (its cost per run). Measured error: ``|mean_N - mean_ref| /
  mean_ref`` with its standard uncertainty ``sigma sqrt(1/N + 1/R_ref)``, sigma pooled over
  the check's replicas; "met" when it is within the tolerance (and, reported too, when it
  is at the upper end of its uncertainty).

Costs are CPU seconds of the runs (one thread; the first step, which loads the compiled
kernels, left out) per simulated second, summed over the replicas; the default's cost is
its step with the replicas it needs for the same tolerance. The calibration and the check
share the scenes' kind, not their size: the check shows how the calibration carries over
to a larger scene of the same kind, not to a new kind. ``--quick`` calibrates and checks
on a smaller, shorter size still (``SMOKE_REPLICAS`` replicas, at most one run of each
advice: a smoke test of the whole path in a minute or two; its sensitivities stay out of
the shipped tables).
Writes benchmarks/results/advise.json and advise.png (advise_quick.*).

    python benchmarks/advise.py            # ~1 h on the 2-core machine (1,009 s with the drum
                                           # at 3 replicas; the drum alone at 24: 2,552 s)
    python benchmarks/advise.py --calibration-only
    python benchmarks/advise.py --calibration benchmarks/results/advise.json   # the check
    python benchmarks/advise.py --quick
"""

from __future__ import annotations

import os

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module
os.environ.setdefault("DPM_BACKGROUND_COMPILE", "0")

import json
import math
import sys
import tempfile
import time
import warnings
from pathlib import Path

import harness
import numpy as np

import dpm
from dpm.advice import Setting, apply_setting, run_and_measure
from dpm.advice.condense import condense
from dpm.advice.scene import scene_facts

HERE = Path(__file__).resolve().parent
box_settle = harness.example("box_settle")
hopper_discharge = harness.example("hopper_discharge")
rotating_drum = harness.example("rotating_drum")

N_REF = 80.0        # steps per shortest contact of the reference runs
MAX_RAYLEIGH = 0.3  # the advisor's default cap on dt / Rayleigh step
CAL_FACTORS = (1.0, 1.5, 2.0, 3.0)  # calibration steps: these times the coarsest
TOLERANCES = (0.01, 0.05)
#: calibration replicas (R at each step, R_ref at the reference) per scene: box_settle's
#: settled height scatters by 0.08 % of itself (a twin), far below its step errors: one run
#: each; the drum's angle (~0.5-0.9 %) and the silo's rate (~3-5 %) need replicas (the
#: drum 24 a side: bound to 0.35 %, what its 1 % advice needs; 3 bounded it to 0.97 %)
CAL_REPLICAS = {"box_settle": (1, 1), "rotating_drum": (24, 24), "hopper": (4, 4)}
#: reference replicas of the check (full size)
CHECK_REF_REPLICAS = {"box_settle": 1, "rotating_drum": 12, "hopper": 4}
#: --quick: calibration replicas of every scene (R = R_ref = 1: the scatter from a twin)
SMOKE_REPLICAS = (1, 1)


def scenes(quick: bool | str) -> dict[str, dict]:
    """name -> builder, quantity, run time [s], window: the small (calibration, True) or
    the full (check, False) size, or ``"smoke"``: the --quick run's, smaller and shorter."""
    if quick == "smoke":
        box = dict(lattice=(6, 6, 6), until=0.12)
        drum = dict(fill=0.15, until=0.35, window=(0.2, 0.35))
        silo = dict(orifice=0.03, radius=0.04, height=0.035, until=0.4, window=(0.33, 0.4))
    elif quick:
        box = dict(lattice=(10, 10, 10), until=0.2)
        drum = dict(fill=0.25, until=1.0, window=(0.5, 1.0))
        silo = dict(orifice=0.03, radius=0.04, height=0.07, until=0.65, window=(0.35, 0.65))
    else:
        box = dict(lattice=(20, 20, 10), until=0.2)
        drum = dict(fill=0.4, until=1.2, window=(0.6, 1.2))
        silo = dict(orifice=0.03, radius=0.04, height=0.1, until=0.75, window=(0.35, 0.75))
    return {
        "box_settle": {
            "quantity": "settled_height", "until": box["until"], "window": None,
            "build": lambda: box_settle.build(box_settle.initial_packing(*box["lattice"])),
            "describe": f"{np.prod(box['lattice'])} glass spheres, d = 2 mm, E = 5 MPa, "
                        f"e = 0.3, {box['until']:g} s"},
        "rotating_drum": {
            "quantity": "angle_of_repose", "until": drum["until"], "window": drum["window"],
            "build": lambda: rotating_drum.build(fill=drum["fill"]),
            "describe": f"drum 100 mm at 20 rpm, fill {drum['fill']:g}, 4 mm beads, "
                        f"{drum['until']:g} s, angle averaged over {drum['window']} s"},
        "hopper": {
            "quantity": "discharge_rate", "until": silo["until"], "window": silo["window"],
            "build": lambda: hopper_discharge.silo(silo["orifice"], radius=silo["radius"],
                                                   height=silo["height"])[0],
            "describe": f"flat silo R = {silo['radius'] * 1e3:g} mm, bed "
                        f"{silo['height'] * 1e3:g} mm, orifice {silo['orifice'] * 1e3:g} mm, "
                        f"5 mm beads, opened at 0.25 s, rate over {silo['window']} s"},
    }


def perturbed(sim: dpm.Simulation, eps: float = 1e-3, seed: int = 7) -> dpm.Simulation:
    """Every body moved by up to ``eps`` of its radius and its velocity changed by ~1e-7
    m/s: a start no measurement tells apart, whose chaotic run decorrelates (a velocity
    change alone left the silo's discharge in its window unchanged)."""
    rng = np.random.default_rng(seed)
    b = sim.bodies
    b.position += rng.uniform(-eps, eps, b.position.shape) * b.radius[:, None]
    b.velocity += rng.normal(0.0, 1e-7, b.velocity.shape)
    return sim


def measure(spec: dict, sim: dpm.Simulation) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = run_and_measure(sim, spec["quantity"], spec["until"], spec["window"])
    sim.close()
    return {"value": m.value, "wall_s": m.wall_s, "cost": m.cost, "cpu_s": m.cpu_s,
            "cpu_cost": m.cpu_cost, "steps": m.steps, "bodies": m.bodies, "dt": sim.dt}


def shortest_contact(sim: dpm.Simulation) -> float:
    f = scene_facts(sim)
    return min(f.contact_time(p) for p in f.pairs)


def run_at(spec: dict, n: float | None = None, twin: bool = False, replica: int = 0,
           dt: float | None = None, skin: float | None = None) -> dict:
    """The scene at n steps per shortest contact (None: the example's dt, or ``dt``);
    replica k > 0 (or a twin: k = 7) starts perturbed with seed k."""
    sim = spec["build"]()
    if twin:
        replica = 7
    if replica:
        perturbed(sim, seed=replica)
    if n is not None or dt is not None:
        f = scene_facts(sim)
        apply_setting(sim, Setting("as set", f.integrator,
                                   dt if dt is not None else shortest_contact(sim) / n,
                                   skin if skin is not None else 0.4 * f.r_min))
    r = measure(spec, sim)
    r["steps_per_contact"] = n
    r["replica"] = replica
    return r


def _task(quick: bool | str, name: str, kw: dict) -> dict:
    """One run in a worker process (the scene rebuilt there from its name)."""
    import numba

    numba.set_num_threads(1)
    return run_at(scenes(quick)[name], **kw)


def run_all(jobs: list[tuple[bool, str, dict]], workers: int) -> list[dict]:
    """The runs ``jobs`` (quick, scene, keywords of :func:`run_at`) on a pool of
    ``workers`` processes (one thread each), results in the order given."""
    jobs = [(q, n, {a: b for a, b in kw.items() if a != "weight"}, kw.get("weight", 1.0))
            for q, n, kw in jobs]
    if workers <= 1:
        return [_task(q, n, kw) for q, n, kw, _ in jobs]
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    order = sorted(range(len(jobs)), key=lambda k: -jobs[k][3])  # the longest first
    with ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn")) as ex:
        futs = {k: ex.submit(_task, *jobs[k][:3]) for k in order}
        return [futs[k].result() for k in range(len(jobs))]


def coarsest(spec: dict) -> float:
    """Steps per shortest contact of the advisor's largest step on this scene."""
    sim = spec["build"]()
    tc = shortest_contact(sim)
    rayleigh = sim.time_step_report().rayleigh
    return max(5.05, tc / (MAX_RAYLEIGH * rayleigh)) if rayleigh else 5.05


def pooled_scatter(groups: list[list[float]], scale: float) -> tuple[float, int]:
    """Sample standard deviation of one run, pooled over groups of replicas of the same
    set-up (each group about its own mean), relative to ``scale``; its degrees of freedom
    (the sum of each group's size less one)."""
    ss, dof = 0.0, 0
    for g in groups:
        if len(g) >= 2:
            m = sum(g) / len(g)
            ss += sum((x - m) ** 2 for x in g)
            dof += len(g) - 1
    return (math.sqrt(ss / dof) / abs(scale) if dof else math.nan), dof


def calibration_phase(specs: dict, workers: int, size: bool | str = True) -> dict:
    """Per scene: R replicas at each calibration step and R_REF at the reference; the
    systematic error of each step (replica means), its standard uncertainty, and the
    scatter of one run pooled over every step's replicas."""
    out = {}
    jobs: list[tuple[bool, str, dict]] = []
    plan: dict[str, dict] = {}
    for name, spec in specs.items():
        n_cal = coarsest(spec)
        R, R_ref = CAL_REPLICAS[name]
        keys = []
        for k in range(R_ref):
            keys.append(("reference", k))
            jobs.append((size, name, {"n": N_REF, "replica": k, "weight": N_REF}))
        for f in CAL_FACTORS:
            for k in range(R):
                keys.append((f"x{f:g}", k))
                jobs.append((size, name, {"n": f * n_cal, "replica": k, "weight": f * n_cal}))
        if R == 1:  # the scatter from a twin of the example's set-up (one degree of freedom)
            for tw in (False, True):
                keys.append(("twin" if tw else "default", 0))
                jobs.append((size, name, {"twin": tw, "weight": 20.0}))
        plan[name] = {"n_cal": n_cal, "R": R, "R_ref": R_ref, "keys": keys,
                      "first": len(jobs) - len(keys)}
    t0 = time.perf_counter()
    res = run_all(jobs, workers)
    wall = time.perf_counter() - t0
    (Path(tempfile.gettempdir()) / "advise_calibration_runs.json").write_text(
        json.dumps({"plan": plan, "runs": res}, default=str))  # kept should what follows fail
    for name, spec in specs.items():
        pl = plan[name]
        runs: dict[str, list[dict]] = {}
        for key, r in zip(pl["keys"], res[pl["first"]:pl["first"] + len(pl["keys"])],
                          strict=True):
            runs.setdefault(key[0], []).append(r)
        R, R_ref = pl["R"], pl["R_ref"]
        refs = [r["value"] for r in runs["reference"]]
        qr = sum(refs) / len(refs)
        groups = [[r["value"] for r in v] for k, v in runs.items()
                  if k not in ("default", "twin")]
        if R == 1 and R_ref == 1:
            groups = [[r["value"] for r in runs["default"] + runs["twin"]]]
            how = "the example's set-up and a twin started perturbed (1 degree of freedom)"
        else:
            how = (f"sample standard deviation pooled over {len(groups)} steps' replicas, "
                   "each about its own mean")
        sigma, dof = pooled_scatter(groups, qr)
        u = sigma * math.sqrt(1 / R + 1 / R_ref)
        points = []
        for f in CAL_FACTORS:
            vals = [r["value"] for r in runs[f"x{f:g}"]]
            d = abs(sum(vals) / len(vals) / qr - 1)
            points.append({"steps_per_contact": f * pl["n_cal"], "measured_error": d,
                           "systematic_error": d, "uncertainty": u, "replicas": R})
        sim = spec["build"]()
        facts = scene_facts(sim)
        k = int(np.argmin([facts.contact_time(p) for p in facts.pairs]))
        pair = facts.pairs[k]
        win = spec["window"]
        out[spec["quantity"]] = {
            "runs": runs, "scatter": sigma, "scatter_dof": dof, "scatter_method": how,
            "replicas": R, "reference_replicas": R_ref, "points": points,
            "window": None if win is None else win[1] - win[0],
            "contact": {"integrator": facts.integrator, "model": pair.model,
                        "restitution": pair.restitution, "pair": pair.label},
            "bodies": runs["reference"][0]["bodies"], "scene": f"{name} ({spec['describe']})",
            "cpu_s": sum(r["cpu_s"] for v in runs.values() for r in v)}
        pts = ", ".join(f"{100 * p['systematic_error']:.3g} +- {100 * u:.2g} % at "
                        f"{p['steps_per_contact']:.3g}" for p in points)
        print(f"calibration {name} (R = {R}, R_ref = {R_ref}): Q_ref = {qr:.6g}; {pts}; "
              f"sigma {100 * sigma:.3g} % ({dof} dof)", flush=True)
    print(f"calibration: {wall:.0f} s wall", flush=True)
    return out


def check_phase(specs: dict, tables: str | None, quick: bool | str, workers: int,
                max_runs: int, cell_cpu: float, cal: dict | None = None) -> dict:
    """For each scene: the advice at each tolerance (with its replicas N), N runs of it
    (at most ``max_runs`` and what ``cell_cpu`` CPU seconds allow), R_REF runs of the
    reference, one of the default (its cost per run). ``cal``: the calibration's runs of
    the same scenes (--quick): its reference replicas taken instead of running them
    again."""
    out: dict = {}
    jobs: list[tuple[bool, str, dict]] = []
    plan: dict[str, list] = {}
    for name, spec in specs.items():
        tc = shortest_contact(spec["build"]())
        keys: list = []
        R_ref = CHECK_REF_REPLICAS[name]
        if cal is None:
            for k in range(R_ref):
                keys.append(("reference", k))
                jobs.append((quick, name, {"n": N_REF, "replica": k, "weight": N_REF}))
        keys.append(("default", 0))
        jobs.append((quick, name, {"weight": 20.0}))
        if R_ref == 1:  # a twin of the default: the scatter of one run (one dof)
            keys.append(("default", 7))
            jobs.append((quick, name, {"twin": True, "weight": 20.0}))
        row = {"quantity": spec["quantity"], "describe": spec["describe"], "advice": {},
               "shortest_contact": tc}
        for tol in TOLERANCES:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a = dpm.advise(spec["build"](), tolerance=tol, quantity=spec["quantity"],
                               run_time=spec["until"], window=spec["window"], tables=tables)
            c = a.choice
            # runs within the cell's CPU budget (predicted cost x 1.3, the model's accuracy);
            # none of an advice out of reach or at the reference's own step (its replicas
            # against the reference's would test the scatter only, not the step)
            fit = int(cell_cpu // (1.3 * c.cost * spec["until"]))
            run_n = min(c.replicas, max_runs, max(fit, 1))
            why = ""
            if not a.feasible:
                run_n, why = 0, "out of reach"
            elif c.steps_per_contact >= 0.9 * N_REF:
                run_n, why = 0, "the reference's own step"
            elif run_n < c.replicas:
                why = f"{run_n} of {c.replicas} runs fit the check's budget"
            for k in range(run_n):
                keys.append((f"{tol:g}", k))
                jobs.append((quick, name, {"dt": c.setting.dt, "skin": c.setting.skin,
                                           "replica": k, "weight": tc / c.setting.dt}))
            row["advice"][f"{tol:g}"] = {"advice": a, "runs_planned": run_n,
                                         "not_verified_because": why}
        plan[name] = [keys, len(jobs) - len(keys), row]
    t0 = time.perf_counter()
    res = run_all(jobs, workers)
    print(f"check: {time.perf_counter() - t0:.0f} s wall", flush=True)
    for name, spec in specs.items():
        keys, first, row = plan[name]
        runs: dict[str, list[dict]] = {}
        for key, r in zip(keys, res[first:first + len(keys)], strict=True):
            runs.setdefault(key[0], []).append(r)
        if cal is not None:
            runs["reference"] = cal[spec["quantity"]]["runs"]["reference"]
        refs = [r["value"] for r in runs["reference"]]
        qr = float(np.mean(refs))
        groups = [[r["value"] for r in v] for v in runs.values()]
        sigma, dof = pooled_scatter(groups, qr)
        default = dict(runs["default"][0], cpu_cost=float(np.mean(
            [r["cpu_cost"] for r in runs["default"]])))
        row.update(reference={"runs": runs["reference"], "mean": qr, "replicas": len(refs),
                              "dt": runs["reference"][0]["dt"],
                              "cpu_cost": float(np.mean([r["cpu_cost"]
                                                         for r in runs["reference"]]))},
                   default=dict(default, steps_per_contact=row["shortest_contact"]
                                / default["dt"],
                                error_one_run=abs(default["value"] / qr - 1)),
                   scatter=sigma, scatter_dof=dof)
        for tol in TOLERANCES:
            entry = row["advice"][f"{tol:g}"]
            a = entry.pop("advice")
            c, d = a.choice, a.default
            mine = runs.get(f"{tol:g}", [])
            vals = [r["value"] for r in mine]
            n_run = len(vals)
            err = abs(float(np.mean(vals)) / qr - 1) if vals else math.nan
            # the measured error's standard uncertainty: this check's pooled sigma
            u = sigma * math.sqrt(1 / max(n_run, 1) + 1 / len(refs)) if vals else math.nan
            verified = n_run == c.replicas and a.feasible
            per_run = float(np.mean([r["cpu_cost"] for r in mine])) if mine else math.nan
            entry.update({
                "setting": {"impact_model": c.setting.impact_model,
                            "integrator": c.setting.integrator, "dt": c.setting.dt,
                            "skin": c.setting.skin},
                "steps_per_contact": c.steps_per_contact, "limited_by": c.limited_by,
                "feasible": a.feasible, "replicas": c.replicas, "runs": n_run,
                "predicted_error": c.error, "predicted_statistical": c.statistical_error,
                "predicted_bound": c.total_error, "predicted_parts": c.parts,
                "predicted_sigma": c.sigma,
                "predicted_cost_per_run": c.cost, "predicted_cost": c.total_cost,
                "default_replicas": d.replicas, "default_feasible": a.default_feasible,
                "default_predicted_error": d.error,
                "default_predicted_cost_per_run": d.cost,
                "default_predicted_cost": d.total_cost,
                "values": vals, "measured_error": err, "uncertainty": u,
                "measured_cost_per_run": per_run,
                "measured_cost": per_run * c.replicas,
                "default_measured_cost": default["cpu_cost"] * d.replicas,
                "verified": verified,
                "met": bool(verified and err <= tol),
                "met_at_upper": bool(verified and err + u <= tol),
                "cheaper_than_default": per_run * c.replicas
                < default["cpu_cost"] * d.replicas,
                "warnings": a.warnings, "report": str(a)})
            print(f"{name} {100 * tol:g} %: dt {c.setting.dt:.3g} ({c.steps_per_contact:.3g} "
                  f"steps/contact) x N = {c.replicas} (ran {n_run}), predicted "
                  f"{100 * c.error:.2g} % + {100 * c.statistical_error:.2g} %, "
                  f"{c.total_cost:.3g} s/s; measured {100 * err:.2g} +- {100 * u:.2g} %, "
                  f"{per_run * c.replicas:.3g} s/s; default N = {d.replicas}, "
                  f"{default['cpu_cost'] * d.replicas:.3g} s/s; sigma {100 * sigma:.2g} % "
                  f"({dof} dof)", flush=True)
        out[name] = row
    return out


def plot(result: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.6))
    marks = {"box_settle": "o", "rotating_drum": "s", "hopper": "^"}
    for name, row in result["scenes"].items():
        for tol, r in row["advice"].items():
            if not r["runs"]:
                continue
            col = "C0" if tol == "0.01" else "C1"
            a1.errorbar(max(r["predicted_bound"], 3e-4), max(r["measured_error"], 3e-4),
                        yerr=r["uncertainty"], fmt=marks[name], color=col, ms=8,
                        mfc=col if r["verified"] else "none",
                        label=f"{name}, {100 * float(tol):g} %, N = {r['replicas']}"
                        + ("" if r["verified"] else f" (ran {r['runs']}: not verified)"))
            a2.loglog(r["predicted_cost"], r["measured_cost"], marks[name], color=col, ms=8)
            a2.loglog(r["default_predicted_cost"], r["default_measured_cost"], marks[name],
                      mfc="none", color=col, ms=8)
    a1.set_xscale("log")
    a1.set_yscale("log")
    lim = [3e-4, 0.2]
    a1.plot(lim, lim, "k-", lw=0.8)
    for t in TOLERANCES:
        a1.axhline(t, color="C0" if t == 0.01 else "C1", lw=0.8, ls="--")
    a1.set_xlabel("predicted error bound (systematic + 2 sigma / sqrt N)")
    a1.set_ylabel("measured |mean_N - mean_ref| / mean_ref")
    a1.set_title("error of the replica mean (bars: standard uncertainty)", fontsize=10)
    a1.legend(fontsize=6)
    c = [1, 3000]
    a2.plot(c, c, "k-", lw=0.8)
    a2.set_xlabel("predicted cost, all replicas [s per simulated s]")
    a2.set_ylabel("measured cost, all replicas [CPU s per simulated s]")
    a2.set_title("cost, one thread (open: the default step with the replicas it needs)",
                 fontsize=10)
    fig.suptitle("dpm advise: step and replicas at 1 % (blue) and 5 % (orange) against the "
                 "mean of reference replicas at 80 steps per contact", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(result: dict) -> str:
    lines = ["| scene, quantity | tolerance | steps/contact (dt [s]) | N | predicted error: "
             "systematic + 2 sigma/sqrt N | measured error +- u (runs) | met (at the upper "
             "end) | cost advice, predicted / measured [s/s] | default: N, cost predicted / "
             "measured [s/s] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, row in result["scenes"].items():
        first = True
        for tol, r in row["advice"].items():
            head = f"{name}, {row['quantity']}" if first else ""
            first = False
            if r["verified"]:
                met = ("yes" if r["met"] else "NO") + (" (yes)" if r["met_at_upper"]
                                                       else " (no)")
            else:
                met = f"not verified: {r['not_verified_because']}"
            ok = "" if r["feasible"] else " (out of reach)"
            dn = (f"{r['default_replicas']}" if r["default_feasible"]
                  else f"{r['default_replicas']} (cannot reach)")
            lines.append(
                f"| {head} | {100 * float(tol):g} % | {r['steps_per_contact']:.3g} "
                f"({r['setting']['dt']:.3g}) | {r['replicas']}{ok} | "
                f"{100 * r['predicted_error']:.2g} % + {100 * r['predicted_statistical']:.2g} % "
                f"= {100 * r['predicted_bound']:.2g} % | {100 * r['measured_error']:.2g} +- "
                f"{100 * r['uncertainty']:.2g} % ({r['runs']}) | {met} | "
                f"{r['predicted_cost']:.3g} / {r['measured_cost']:.3g} | {dn}, "
                f"{r['default_predicted_cost']:.3g} / {r['default_measured_cost']:.3g} |")
        ref = row["reference"]
        lines.append(f"| | reference | {N_REF:g} ({ref['dt']:.3g}) | {ref['replicas']} | - | "
                     f"sigma of one run {100 * row['scatter']:.2g} % ({row['scatter_dof']} "
                     f"dof) | - | {ref['cpu_cost'] * ref['replicas']:.3g} (measured) | "
                     f"default one run {100 * row['default']['error_one_run']:.2g} % off, "
                     f"{row['default']['steps_per_contact']:.3g} steps/contact |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__, "calibrate and check on the small scenes (a smoke test)")
    ap.add_argument("--calibration", default=None, metavar="JSON",
                    help="take the calibration from this earlier result (advise.json: the "
                    "small scenes; advise_quick.json: the --quick ones) instead of running it")
    ap.add_argument("--calibration-only", action="store_true",
                    help="stop after the calibration (and, without --quick, the tables)")
    ap.add_argument("--scenes", nargs="+", default=None, metavar="NAME",
                    help="only these scenes (box_settle rotating_drum hopper); writes "
                    "advise[_quick]_partial.json, never the shipped tables")
    ap.add_argument("--workers", type=int, default=2,
                    help="processes running the replicas side by side (default 2)")
    ap.add_argument("--max-runs", type=int, default=None,
                    help="at most this many runs of an advice in the check (default 12, "
                    "--quick 1): an advice needing more is reported, not verified")
    ap.add_argument("--cell-cpu", type=float, default=600.0,
                    help="CPU seconds (predicted) the check spends on one advice's runs "
                    "(default 600)")
    ap.add_argument("--cal-replicas", nargs="+", default=(), metavar="NAME=R,R_REF",
                    help="calibration replicas of a scene instead of CAL_REPLICAS, e.g. "
                    "rotating_drum=20,20")
    ap.add_argument("--check-ref", nargs="+", default=(), metavar="NAME=R_REF",
                    help="reference replicas of a scene's check instead of "
                    "CHECK_REF_REPLICAS, e.g. rotating_drum=12")
    ap.add_argument("--merge-into", default=None, metavar="JSON",
                    help="with --scenes: write these scenes' calibration and check into "
                    "this full result (advise.json) in place of its own, then condense the "
                    "shipped tables from it and draw its plot again")
    a = ap.parse_args(argv)
    if a.quick:  # (the smoke size: one replica a step, a twin for the scatter)
        for name in CAL_REPLICAS:
            CAL_REPLICAS[name] = SMOKE_REPLICAS
    for item in a.cal_replicas:
        name, _, val = item.partition("=")
        r, _, r_ref = val.partition(",")
        CAL_REPLICAS[name] = (int(r), int(r_ref or r))
    for item in a.check_ref:
        name, _, val = item.partition("=")
        CHECK_REF_REPLICAS[name] = int(val)
    a.max_runs = a.max_runs or (1 if a.quick else 12)
    size = "smoke" if a.quick else True  # (the calibration's; the check's: "smoke" or full)
    if a.merge_into and not a.scenes:
        ap.error("--merge-into needs --scenes (a full run writes advise.json itself)")
    import numba

    numba.set_num_threads(1)
    t0 = time.perf_counter()
    stem = ("advise_quick" if a.quick else "advise") + ("_partial" if a.scenes else "")

    def pick(specs: dict) -> dict:
        return {k: v for k, v in specs.items() if not a.scenes or k in a.scenes}

    if a.calibration:
        cal = json.loads(Path(a.calibration).read_text())["calibration"]
        print(f"calibration from {a.calibration}", flush=True)
    else:
        cal = calibration_phase(pick(scenes(size)), a.workers, size)
    result = {"quick": a.quick, "run": harness.machine() | {"argv": sys.argv[1:]},
              "n_ref": N_REF, "max_rayleigh": MAX_RAYLEIGH, "z": 2.0, "workers": a.workers,
              "calibration": cal}
    harness.RESULTS.mkdir(parents=True, exist_ok=True)
    path = harness.RESULTS / f"{stem}.json"
    # the calibration into the advisor's tables, then the advice: the full run writes the
    # shipped tables, the quick or partial one (or one with --results elsewhere) a
    # temporary file, from the shipped results and this run's calibration
    path.write_text(json.dumps(result, indent=1))  # (--calibration can take it from here)
    if a.quick or a.scenes or harness.RESULTS != harness.SHIPPED:
        tmp = Path(tempfile.mkdtemp())
        for f in harness.SHIPPED.glob("*.json"):
            (tmp / f.name).write_text(f.read_text())
        (tmp / "advise.json").write_text(json.dumps(result, indent=1))
        tables = str(tmp / "work_precision.json")
        condense(tmp, Path(tables))
    else:
        condense(harness.SHIPPED)
        tables = None
    if a.calibration_only:
        print(f"\nwrote {path} ({time.perf_counter() - t0:.0f} s)")
        return 0
    check = "smoke" if a.quick else False
    result["scenes"] = check_phase(pick(scenes(check)), tables, check, a.workers,
                                   a.max_runs, a.cell_cpu,
                                   cal if a.quick and not a.calibration else None)
    result["wall_s"] = time.perf_counter() - t0
    path.write_text(json.dumps(result, indent=1, default=str))
    harness.png(plot, result, path=path.with_suffix(".png"))
    print()
    print(table(result))
    print(f"\nwrote {path} and .png ({result['wall_s']:.0f} s)")
    if a.merge_into:
        merge(result, Path(a.merge_into), argv)
    return 0


def merge(partial: dict, into: Path, argv: list[str] | None) -> None:
    """A rerun of some scenes (``--scenes``) written into the full result: their
    calibration and check replace the full result's, a record of the rerun (its command,
    wall time and replicas) goes to ``reruns``, the shipped tables are condensed again and
    the plot drawn again."""
    full = json.loads(into.read_text())
    full["calibration"].update(partial["calibration"])
    full.setdefault("scenes", {}).update(json.loads(json.dumps(partial.get("scenes", {}),
                                                               default=str)))
    full.setdefault("reruns", []).append({
        "argv": list(argv if argv is not None else sys.argv[1:]),
        "scenes": sorted(partial.get("scenes", {}) or partial["calibration"]),
        "wall_s": partial.get("wall_s"), "cal_replicas": dict(CAL_REPLICAS),
        "check_ref_replicas": dict(CHECK_REF_REPLICAS)})
    into.write_text(json.dumps(full, indent=1, default=str))
    if into.resolve().parent == harness.SHIPPED and not full.get("quick"):
        condense(harness.SHIPPED)
    plot(full, into.with_suffix(".png"))
    print()
    print(table(full))
    print(f"\nmerged into {into} (tables condensed again) and its .png")


if __name__ == "__main__":
    raise SystemExit(main())
