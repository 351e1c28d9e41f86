"""`dpm advise` on three scenes: the advisor's choice at 1 % and 5 % against a fine reference.

Scenes and quantities (``examples/``):

1. box_settle: glass spheres settling in an open box (Hertz-Mindlin, e = 0.3); the settled
   height (mean centre height above the floor at the end);
2. rotating_drum: 4 mm glass beads in a 100 mm drum at 20 rpm; the dynamic angle of
   repose, the mean over samples every 0.02 s in the second half of the run;
3. hopper: the flat-bottomed silo of ``examples/hopper_discharge.py`` (5 mm beads, orifice
   D, plug switched off at 0.25 s); the discharge rate in the window after the start-up
   transient.

Per scene, one thread, in this order:

- ``default``: the example's own set-up (its dt, the default skin);
- ``twin``: the same with every initial velocity changed by ~1e-7 m/s: the run-to-run
  scatter of the quantity (granular flow is chaotic), sigma = |Q_twin - Q| / sqrt(2) / Q;
- ``e+``, ``e-``: the restitution of every contact law times 1.2 and 0.8: the sensitivity
  S_e = d ln Q / d ln e, taken as (|Q+ - Q-| + sqrt(2) sigma Q) / (Q ln(1.2/0.8)) (the
  scatter added: an upper bound), written to ``advise.json`` and condensed into the
  advisor's tables (``python -m dpm.advice.condense``) before the advice is asked;
- ``reference``: the example's set-up at 80 steps per shortest contact;
- the advisor's choice at 1 % and at 5 % (``dpm.advise(..., verify=True)``: the run at the
  chosen dt, whose quantity and wall time are the measured ones here, and the pilot at dt/2
  for the Richardson estimate).

Measured error: |Q - Q_ref| / Q_ref; measured cost: wall seconds of the run (the first
step, which loads the compiled kernels, left out) per simulated second. Written to
benchmarks/results/advise.json and advise.png (``--quick``: smaller scenes,
advise_quick.*, with the sensitivities kept out of the shipped tables).

    python benchmarks/advise.py            # ~15 min on the 2-core machine
    python benchmarks/advise.py --quick    # ~5 min
"""

from __future__ import annotations

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
E_FACTOR = 1.2      # the restitution is scaled by E_FACTOR and 1 / ... (0.8) for S_e
E_LOW = 0.8
TOLERANCES = (0.01, 0.05)


def scenes(quick: bool) -> dict[str, dict]:
    """name -> builder, quantity, run time [s], window."""
    if quick:
        box = dict(lattice=(10, 10, 10), until=0.08)
        drum = dict(fill=0.25, until=1.0, window=(0.5, 1.0))
        silo = dict(orifice=0.025, radius=0.025, height=0.05, until=0.45, window=(0.3, 0.45))
    else:
        box = dict(lattice=(20, 20, 10), until=0.12)
        drum = dict(fill=0.4, until=2.0, window=(1.0, 2.0))
        silo = dict(orifice=0.03, radius=0.04, height=0.12, until=0.85, window=(0.35, 0.85))
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


def scale_restitution(sim: dpm.Simulation, factor: float) -> None:
    """Every contact law of the scene with its restitution times ``factor``."""
    for p in scene_facts(sim).pairs:
        params = dict(p.law.params, restitution=min(1.0, p.restitution * factor))
        sim.contact(p.a, p.b, model=p.model, **params)


def perturbed(sim: dpm.Simulation, eps: float = 1e-7, seed: int = 7) -> dpm.Simulation:
    rng = np.random.default_rng(seed)
    sim.bodies.velocity += rng.normal(0.0, eps, sim.bodies.velocity.shape)
    return sim


def measure(spec: dict, sim: dpm.Simulation) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = run_and_measure(sim, spec["quantity"], spec["until"], spec["window"])
    sim.close()
    return {"value": m.value, "wall_s": m.wall_s, "cost": m.cost, "steps": m.steps,
            "bodies": m.bodies, "dt": sim.dt}


def shortest_contact(sim: dpm.Simulation) -> float:
    f = scene_facts(sim)
    return min(f.contact_time(p) for p in f.pairs)


def sensitivity_phase(specs: dict) -> dict:
    out = {}
    for name, spec in specs.items():
        t0 = time.perf_counter()
        runs = {"default": measure(spec, spec["build"]()),
                "twin": measure(spec, perturbed(spec["build"]()))}
        for key, f in (("e+", E_FACTOR), ("e-", E_LOW)):
            sim = spec["build"]()
            scale_restitution(sim, f)
            runs[key] = measure(spec, sim)
        q0 = runs["default"]["value"]
        sigma = abs(runs["twin"]["value"] - q0) / math.sqrt(2) / abs(q0)
        dq = abs(runs["e+"]["value"] - runs["e-"]["value"]) / abs(q0)
        dl = math.log(E_FACTOR / E_LOW)
        out[name] = {"quantity": spec["quantity"], "runs": runs, "scatter": sigma,
                     "restitution_measured": dq / dl,
                     "restitution": (dq + math.sqrt(2) * sigma) / dl,
                     "delta_restitution": E_FACTOR - 1, "bodies": runs["default"]["bodies"],
                     "scene": f"{name} ({spec['describe']})",
                     "wall_s": time.perf_counter() - t0}
        print(f"{name}: Q = {q0:.6g}, scatter {100 * sigma:.3g} %, S_e measured "
              f"{dq / dl:.3g}, used {out[name]['restitution']:.3g} "
              f"({time.perf_counter() - t0:.0f} s)", flush=True)
    return out


def compare_phase(specs: dict, sens: dict, tables: str | None) -> dict:
    out = {}
    for name, spec in specs.items():
        t0 = time.perf_counter()
        sim = spec["build"]()
        facts = scene_facts(sim)
        tc = shortest_contact(sim)
        skin = 0.4 * facts.r_min
        ref_setting = Setting("as set", facts.integrator, tc / N_REF, skin)
        apply_setting(sim, ref_setting)
        ref = measure(spec, sim)
        default = sens[name]["runs"]["default"]
        row = {"quantity": spec["quantity"], "describe": spec["describe"],
               "reference": dict(ref, steps_per_contact=N_REF),
               "scatter": sens[name]["scatter"], "S_e": sens[name]["restitution"],
               "default": dict(default, steps_per_contact=tc / facts.dt,
                               error=abs(default["value"] / ref["value"] - 1)),
               "advice": {}}
        for tol in TOLERANCES:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                a = dpm.advise(spec["build"](), tolerance=tol, quantity=spec["quantity"],
                               verify=True, run_time=spec["until"], window=spec["window"],
                               pilot=spec["build"], tables=tables)
            v = a.verification
            c = a.choice
            row["advice"][f"{tol:g}"] = {
                "setting": {"impact_model": c.setting.impact_model,
                            "integrator": c.setting.integrator, "dt": c.setting.dt,
                            "skin": c.setting.skin},
                "steps_per_contact": c.steps_per_contact, "limited_by": c.limited_by,
                "predicted_error": c.error, "predicted_parts": c.parts,
                "predicted_cost": c.cost, "default_predicted_error": a.default.error,
                "default_predicted_cost": a.default.cost,
                "value": v.values[0], "value_half_dt": v.values[1],
                "measured_error": abs(v.values[0] / ref["value"] - 1),
                "measured_cost": v.cost[0], "richardson": v.estimate, "order": v.order,
                "met": abs(v.values[0] / ref["value"] - 1) <= tol,
                "cheaper_than_default": v.cost[0] < default["cost"],
                "warnings": a.warnings, "report": str(a)}
            r = row["advice"][f"{tol:g}"]
            print(f"{name} {100 * tol:g} %: dt {c.setting.dt:.3g} ({c.steps_per_contact:.3g} "
                  f"steps/contact), predicted {100 * c.error:.3g} % {c.cost:.3g} s/s, measured "
                  f"{100 * r['measured_error']:.3g} % {r['measured_cost']:.3g} s/s, Richardson "
                  f"{100 * v.estimate:.3g} %; default measured "
                  f"{100 * row['default']['error']:.3g} % {default['cost']:.3g} s/s",
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
            a1.loglog(max(r["predicted_error"], 1e-5), max(r["measured_error"], 1e-5),
                      marks[name], color=col, ms=8,
                      label=f"{name}, {100 * float(tol):g} %")
            a2.loglog(r["predicted_cost"], r["measured_cost"], marks[name], color=col, ms=8)
        a1.axhline(row["scatter"], color="0.6", lw=0.8, ls=":")
        d = row["default"]
        a2.loglog(row["advice"]["0.01"]["default_predicted_cost"], d["cost"], marks[name],
                  mfc="none", color="k", ms=8)
    lim = [1e-5, 0.2]
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
    a2.set_ylabel("measured cost [s per simulated s]")
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
                     f"{d['cost']:.3g} | - |")
        for tol, r in row["advice"].items():
            met = "yes" if r["met"] else "NO"
            lines.append(f"| | advice {100 * float(tol):g} % | {r['steps_per_contact']:.3g} | "
                         f"{r['setting']['dt']:.3g} | {100 * r['predicted_error']:.2g} % | "
                         f"{100 * r['measured_error']:.2g} % | {100 * r['richardson']:.2g} % | "
                         f"{r['predicted_cost']:.3g} | {r['measured_cost']:.3g} | {met} |")
        lines.append(f"| | reference | {N_REF:g} | {row['reference']['dt']:.3g} | - | "
                     f"(scatter {100 * row['scatter']:.2g} %) | - | - | "
                     f"{row['reference']['cost']:.3g} | - |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller scenes (~5 min)")
    a = ap.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    t0 = time.perf_counter()
    specs = scenes(a.quick)
    stem = "advise_quick" if a.quick else "advise"
    sens = sensitivity_phase(specs)
    result = {"quick": a.quick, "machine": {"python": platform.python_version(),
                                           "cpu": platform.processor() or platform.machine()},
              "n_ref": N_REF, "sensitivity": {
                  specs[k]["quantity"]: v for k, v in sens.items()}}
    RESULTS.mkdir(exist_ok=True)
    path = RESULTS / f"{stem}.json"
    # the sensitivities into the advisor's tables, then the advice: the full run writes the
    # shipped tables, the quick one a temporary file
    if a.quick:
        tmp = Path(tempfile.mkdtemp())
        for f in RESULTS.glob("*.json"):
            (tmp / f.name).write_text(f.read_text())
        (tmp / "advise.json").write_text(json.dumps(result, indent=1))
        tables = str(tmp / "work_precision.json")
        condense(tmp, Path(tables))
    else:
        path.write_text(json.dumps(result, indent=1))
        condense(RESULTS)
        tables = None
    result["scenes"] = compare_phase(specs, {k: v for k, v in sens.items()}, tables)
    result["wall_s"] = time.perf_counter() - t0
    path.write_text(json.dumps(result, indent=1))
    plot(result, RESULTS / f"{stem}.png")
    print()
    print(table(result))
    print(f"\nwrote {path} and .png ({result['wall_s']:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
