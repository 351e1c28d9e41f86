"""`dpm advise` on three scenes: the advisor's choice at 1 % and 5 % against a fine reference.

Scenes and quantities (``examples/``):

1. box_settle: glass spheres settling in an open box (Hertz-Mindlin, e = 0.3, 0.2 s: at
   rest); the settled height (mean centre height above the floor at the end);
2. rotating_drum: 4 mm glass beads in a 100 mm drum at 20 rpm; the dynamic angle of
   repose, the mean over samples every 0.02 s in the second half of the run;
3. hopper: the flat-bottomed silo of ``examples/hopper_discharge.py`` (5 mm beads, plug
   switched off at 0.25 s); the discharge rate in a window after the start-up transient.

Two phases, one thread, the scenes' own compiled step modules (``DPM_KERNELS=scene``):

- calibration, on the small (``--quick``) size of each scene: the example's set-up
  (``default``), the same with every initial velocity changed by ~1e-7 m/s (``twin``: the
  run-to-run scatter sigma = |Q_twin - Q| / sqrt(2) / Q of a chaotic flow), the coarsest
  step the advisor takes (n_c steps per shortest contact: the engine's 5, 1 % inside, or
  0.3 of the Rayleigh step if smaller) and 1.5, 2 and 3 times it, and a reference at 80.
  The quantity's errors |Q(n) - Q(80)| / Q(80) at these steps, its scatter sigma (the RMS
  of three differences of two runs, over sqrt(2): twin - default, and the two finest
  steps - reference) and the calibration's contact law go to
  ``advise.json`` and, condensed (``python -m dpm.advice.condense``), into the advisor's
  tables before it is asked;
- check, on the full size: ``default``, ``twin``, ``reference`` (80 steps per contact),
  and the advisor's choice at 1 % and 5 % (``dpm.advise(..., verify=True)``: the run at the
  chosen dt, whose quantity and wall time are the measured ones here, and the pilot at
  dt/2 for the Richardson estimate).

Measured error: |Q - Q_ref| / Q_ref; measured cost: CPU seconds of the run (one thread; the
first step, which loads the compiled kernels, left out) per simulated second (the wall
time is recorded too; on the shared machine it moves with the other work). The calibration
and the check share the scenes' kind, not their size: the check shows how the calibration
carries over to a larger scene of the same kind, not to a new kind. ``--quick`` calibrates
and checks on the small size (a smoke test; its sensitivities stay out of the shipped
tables). Writes benchmarks/results/advise.json and advise.png (advise_quick.*).

    python benchmarks/advise.py            # ~20 min on the shared 2-core machine
    python benchmarks/advise.py --quick
"""

from __future__ import annotations

import os

os.environ.setdefault("DPM_KERNELS", "scene")  # timings of the scene's own step module
os.environ.setdefault("DPM_BACKGROUND_COMPILE", "0")

import argparse
import json
import math
import platform
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE.parent / "examples"))

import box_settle  # noqa: E402
import hopper_discharge  # noqa: E402
import rotating_drum  # noqa: E402

import dpm  # noqa: E402
from dpm.advice import Setting, apply_setting, run_and_measure  # noqa: E402
from dpm.advice.condense import condense  # noqa: E402
from dpm.advice.scene import scene_facts  # noqa: E402

N_REF = 80.0        # steps per shortest contact of the reference runs
MAX_RAYLEIGH = 0.3  # the advisor's default cap on dt / Rayleigh step
CAL_FACTORS = (1.0, 1.5, 2.0, 3.0)  # calibration steps: these times the coarsest
TOLERANCES = (0.01, 0.05)


def scenes(quick: bool) -> dict[str, dict]:
    """name -> builder, quantity, run time [s], window: the small (calibration, --quick) or
    the full (check) size."""
    if quick:
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


def run_at(spec: dict, n: float | None = None, twin: bool = False) -> dict:
    """The scene at n steps per shortest contact (None: the example's dt), perturbed for a
    twin."""
    sim = spec["build"]()
    if twin:
        perturbed(sim)
    if n is not None:
        f = scene_facts(sim)
        apply_setting(sim, Setting("as set", f.integrator, shortest_contact(sim) / n,
                                   0.4 * f.r_min))
    r = measure(spec, sim)
    r["steps_per_contact"] = n
    return r


def coarsest(spec: dict) -> float:
    """Steps per shortest contact of the advisor's largest step on this scene."""
    sim = spec["build"]()
    tc = shortest_contact(sim)
    rayleigh = sim.time_step_report().rayleigh
    return max(5.05, tc / (MAX_RAYLEIGH * rayleigh)) if rayleigh else 5.05


def calibration_phase(specs: dict) -> dict:
    out = {}
    for name, spec in specs.items():
        t0 = time.perf_counter()
        n_cal = coarsest(spec)
        runs = {"default": run_at(spec), "twin": run_at(spec, twin=True),
                "reference": run_at(spec, N_REF)}
        for f in CAL_FACTORS:
            runs[f"x{f:g}"] = run_at(spec, f * n_cal)
        q0, qr = runs["default"]["value"], runs["reference"]["value"]
        # the scatter: three differences of two runs, each sqrt(2) sigma: the twin against
        # the default, and the two finest calibration steps against the reference (their
        # step error is part of it: an overestimate)
        diffs = [runs["twin"]["value"] / q0 - 1] + [
            runs[f"x{f:g}"]["value"] / qr - 1 for f in CAL_FACTORS[-2:]]
        sigma = math.sqrt(sum(d * d for d in diffs) / len(diffs)) / math.sqrt(2)
        points = [{"steps_per_contact": f * n_cal,
                   "measured_error": abs(runs[f"x{f:g}"]["value"] / qr - 1)}
                  for f in CAL_FACTORS]
        sim = spec["build"]()
        facts = scene_facts(sim)
        k = int(np.argmin([facts.contact_time(p) for p in facts.pairs]))
        pair = facts.pairs[k]
        out[spec["quantity"]] = {
            "runs": runs, "scatter": sigma, "points": points,
            "contact": {"integrator": facts.integrator, "model": pair.model,
                        "restitution": pair.restitution, "pair": pair.label},
            "bodies": runs["default"]["bodies"], "scene": f"{name} ({spec['describe']})",
            "wall_s": time.perf_counter() - t0}
        pts = ", ".join(f"{100 * p['measured_error']:.3g} % at {p['steps_per_contact']:.3g}"
                        for p in points)
        print(f"calibration {name}: Q_ref = {qr:.6g}; {pts}; scatter {100 * sigma:.3g} % "
              f"({time.perf_counter() - t0:.0f} s)", flush=True)
    return out


def check_phase(specs: dict, tables: str | None, cal: dict | None = None) -> dict:
    """``cal``: the calibration's runs of the same scenes (--quick), taken instead of
    running the default, twin and reference again."""
    out = {}
    for name, spec in specs.items():
        t0 = time.perf_counter()
        tc = shortest_contact(spec["build"]())
        if cal is not None:
            runs = cal[spec["quantity"]]["runs"]
            default, twin, ref = runs["default"], runs["twin"], runs["reference"]
        else:
            default = run_at(spec)
            twin = run_at(spec, twin=True)
            ref = run_at(spec, N_REF)
        q0 = default["value"]
        row = {"quantity": spec["quantity"], "describe": spec["describe"],
               "reference": ref,
               "scatter": abs(twin["value"] - q0) / math.sqrt(2) / abs(q0), "twin": twin,
               "default": dict(default, steps_per_contact=tc / default["dt"],
                               error=abs(q0 / ref["value"] - 1)),
               "advice": {}}
        for tol in TOLERANCES:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a = dpm.advise(spec["build"](), tolerance=tol, quantity=spec["quantity"],
                               verify=True, run_time=spec["until"], window=spec["window"],
                               pilot=spec["build"], tables=tables)
            v = a.verification
            c = a.choice
            err = abs(v.values[0] / ref["value"] - 1)
            row["advice"][f"{tol:g}"] = {
                "setting": {"impact_model": c.setting.impact_model,
                            "integrator": c.setting.integrator, "dt": c.setting.dt,
                            "skin": c.setting.skin},
                "steps_per_contact": c.steps_per_contact, "limited_by": c.limited_by,
                "feasible": a.feasible, "predicted_error": c.error,
                "predicted_parts": c.parts, "predicted_cost": c.cost,
                "default_predicted_error": a.default.error,
                "default_predicted_cost": a.default.cost,
                "value": v.values[0], "value_half_dt": v.values[1], "measured_error": err,
                "measured_cost": v.cpu_cost[0], "measured_wall_cost": v.cost[0],
                "richardson": v.estimate, "order": v.order, "met": err <= tol,
                "cheaper_than_default": v.cpu_cost[0] < default["cpu_cost"],
                "warnings": a.warnings, "report": str(a)}
            print(f"{name} {100 * tol:g} %: dt {c.setting.dt:.3g} ({c.steps_per_contact:.3g} "
                  f"steps/contact), predicted {100 * c.error:.3g} % {c.cost:.3g} s/s, measured "
                  f"{100 * err:.3g} % {v.cpu_cost[0]:.3g} s/s, Richardson "
                  f"{100 * v.estimate:.3g} %; default measured "
                  f"{100 * row['default']['error']:.3g} % {default['cpu_cost']:.3g} s/s, "
                  f"scatter {100 * row['scatter']:.3g} %",
                  flush=True)
        row["wall_s"] = time.perf_counter() - t0
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
            col = "C0" if tol == "0.01" else "C1"
            a1.loglog(max(r["predicted_error"], 3e-4), max(r["measured_error"], 3e-4),
                      marks[name], color=col, ms=8,
                      label=f"{name}, {100 * float(tol):g} %")
            a2.loglog(r["predicted_cost"], r["measured_cost"], marks[name], color=col, ms=8)
        a1.axhline(row["scatter"], color="0.6", lw=0.8, ls=":")
        d = row["default"]
        a2.loglog(row["advice"]["0.01"]["default_predicted_cost"], d["cpu_cost"], marks[name],
                  mfc="none", color="k", ms=8)
    lim = [3e-4, 0.2]
    a1.plot(lim, lim, "k-", lw=0.8)
    for t in TOLERANCES:
        a1.axhline(t, color="C0" if t == 0.01 else "C1", lw=0.8, ls="--")
    a1.set_xlabel("predicted relative error")
    a1.set_ylabel("measured |Q - Q_ref| / Q_ref")
    a1.set_title("error (dotted: run-to-run scatter of each scene)", fontsize=10)
    a1.legend(fontsize=7)
    c = [0.5, 200]
    a2.plot(c, c, "k-", lw=0.8)
    a2.set_xlabel("predicted cost [s per simulated s]")
    a2.set_ylabel("measured cost [CPU s per simulated s]")
    a2.set_title("cost, one thread (open black: the examples' defaults)", fontsize=10)
    fig.suptitle("dpm advise: the choice at 1 % (blue) and 5 % (orange) against an 80 "
                 "steps-per-contact reference", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(result: dict) -> str:
    lines = ["| scene, quantity | set-up | steps/contact | dt [s] | predicted error | "
             "measured error | Richardson | predicted cost [s/s] | measured cost [s/s] | met |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, row in result["scenes"].items():
        d = row["default"]
        first = row["advice"]["0.01"]
        lines.append(f"| {name}, {row['quantity']} | default | {d['steps_per_contact']:.3g} | "
                     f"{d['dt']:.3g} | {100 * first['default_predicted_error']:.2g} % | "
                     f"{100 * d['error']:.2g} % | - | {first['default_predicted_cost']:.3g} | "
                     f"{d['cpu_cost']:.3g} | - |")
        for tol, r in row["advice"].items():
            met = "yes" if r["met"] else "NO"
            lines.append(f"| | advice {100 * float(tol):g} % | {r['steps_per_contact']:.3g} | "
                         f"{r['setting']['dt']:.3g} | {100 * r['predicted_error']:.2g} % | "
                         f"{100 * r['measured_error']:.2g} % | {100 * r['richardson']:.2g} % | "
                         f"{r['predicted_cost']:.3g} | {r['measured_cost']:.3g} | {met} |")
        lines.append(f"| | reference | {N_REF:g} | {row['reference']['dt']:.3g} | - | "
                     f"(scatter {100 * row['scatter']:.2g} %) | - | - | "
                     f"{row['reference']['cpu_cost']:.3g} | - |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="calibrate and check on the small scenes (a smoke test)")
    ap.add_argument("--calibration", default=None, metavar="JSON",
                    help="take the calibration from this earlier result (advise_quick.json: "
                    "the same small scenes) instead of running it")
    a = ap.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    t0 = time.perf_counter()
    stem = "advise_quick" if a.quick else "advise"
    if a.calibration:
        cal = json.loads(Path(a.calibration).read_text())["calibration"]
        print(f"calibration from {a.calibration}", flush=True)
    else:
        cal = calibration_phase(scenes(True))
    result = {"quick": a.quick, "machine": {"python": platform.python_version(),
                                           "cpu": platform.processor() or platform.machine()},
              "n_ref": N_REF, "max_rayleigh": MAX_RAYLEIGH, "calibration": cal}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{stem}.json"
    # the sensitivities into the advisor's tables, then the advice: the full run writes the
    # shipped tables, the quick one a temporary file
    path.write_text(json.dumps(result, indent=1))  # (--calibration can take it from here)
    if a.quick:
        tmp = Path(tempfile.mkdtemp())
        for f in RESULTS.glob("*.json"):
            (tmp / f.name).write_text(f.read_text())
        (tmp / "advise.json").write_text(json.dumps(result, indent=1))
        tables = str(tmp / "work_precision.json")
        condense(tmp, Path(tables))
    else:
        condense(RESULTS)
        tables = None
    result["scenes"] = check_phase(scenes(a.quick), tables,
                                   cal if a.quick and not a.calibration else None)
    result["wall_s"] = time.perf_counter() - t0
    path.write_text(json.dumps(result, indent=1))
    plot(result, RESULTS / f"{stem}.png")
    print()
    print(table(result))
    print(f"\nwrote {path} and .png ({result['wall_s']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
