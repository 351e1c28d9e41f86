"""Contact-level work-precision tables for `dpm advise`: error of one collision against
steps per contact, restitution and integrator, worst over the contact's start within a step.

A sphere (r = 1 mm, 2500 kg/m3, E = 10 MPa, nu = 0.3, the scene of
``benchmarks/impact_models.py``) hits a plane head-on at 0.5 m/s, no gravity. Eight copies
side by side start their contact at 0, 1/8, ..., 7/8 of a step (a gap of phi v dt): a
contact in a granular scene starts anywhere within a step (``impact_models.py`` measures
phase 0 only), so each row gives the mean over the phases (the bias that an ensemble of
contacts sees) and the worst phase (signed). Measured against each model's
analytic solution (closed forms, or scipy's ODE of the force law; the references of
``benchmarks/impact_models.py``): the restitution (rebound speed / approach speed, after the
contact, so exact in free flight), the largest overlap (parabola through the samples) and
the contact duration (the force's end extrapolated as in :mod:`dpm.impact.measure`).

Models: ``hertz_mindlin`` (Tsuji damping), ``hooke`` (the linear spring-dashpot family:
``linear_spring_dashpot`` and ``maw_linear_spring`` share its dimensionless problem and its
errors), ``walton_braun``, ``hertz_brilliantov`` (restitution set at the impact speed);
restitution 0.1, 0.3, 0.5, 0.7, 0.9, 1.0; 2 to 200 steps per contact; every explicit
integrator but ``taylor`` (unstable on undamped contacts, docs/integrators.md) and the
implicit ``newmark_beta`` and ``numerov``. Every model is bound in one step per integrator
(``dpm.impact.measure.bind``), so each integrator compiles once.

Writes benchmarks/results/advise_contact_errors.json (``--quick``: fewer rows, no implicit
integrators, ``advise_contact_errors_quick.json``). ``python -m dpm.advice.condense``
turns it, with the other benchmark results, into ``dpm/data/work_precision.json``.

    python benchmarks/advise_tables.py            # ~10-20 min, most of it compiling
    python benchmarks/advise_tables.py --quick
"""

from __future__ import annotations

import json
import math
import time

import harness
import numba
import numpy as np
import shared_scenes as im  # the references of impact_models.py: same scene, same solvers

import dpm

MODELS = ["hertz_mindlin", "hooke", "walton_braun", "hertz_brilliantov"]
RESTITUTIONS = [0.1, 0.3, 0.5, 0.7, 0.9, 1.0]
STEPS = [2, 3, 4, 5, 6, 7, 8, 10, 12, 15, 20, 30, 50, 100, 200]
EXPLICIT = ["velocity_verlet", "symplectic_euler", "position_verlet", "gear4", "gear5"]
IMPLICIT = ["newmark_beta", "numerov"]
PHASES = [k / 8 for k in range(8)]
R, RHO, YOUNG, NU, V, M = im.R, im.RHO, im.YOUNG, im.NU, im.V, im.M


def case(model: str, e: float) -> tuple[dict, dict, float]:
    """(the model's parameters, the analytic reference, the force's end exponent)."""
    reg = dpm.registry()
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    if model == "hertz_mindlin":
        if e >= 1.0:
            ref = {"duration": 2.868265699194 * (M * M / (R * im.ESTAR**2 * V)) ** 0.2,
                   "max_overlap": (15 * M * V * V / (16 * im.ESTAR * math.sqrt(R))) ** 0.4,
                   "restitution": 1.0}
            return {"restitution": 1.0}, ref, 1.5
        law = reg.lookup("impact_model", model)(restitution=e)
        return {"restitution": e}, im.ode(im.tsuji(law.beta)), 1.0
    if model == "hooke":
        return {"restitution": e}, im.linear_for(4 / 3 * im.ESTAR * R, e), 1.0
    if model == "walton_braun":
        kl = 1e4
        ref = {"duration": math.pi / 2 * (math.sqrt(M / kl) + math.sqrt(M * e * e / kl)),
               "max_overlap": V * math.sqrt(M / kl), "restitution": e}
        return {"stiffness": kl, "restitution": e}, ref, 1.0
    if model == "hertz_brilliantov":
        hb = reg.lookup("impact_model", model)(restitution=e, reference_speed=V)
        A = hb.dissipation(mat, mat, M, R, V) if e < 1.0 else 0.0
        ref = im.ode(lambda d, dd: max(im.KH * (d**1.5 + A * math.sqrt(d) * dd), 0.0))
        return {"dissipation": A}, ref, 1.5 if e >= 1.0 else 1.0
    raise ValueError(model)


def batch(model: str, params: dict, integrator: str, dt: float, end_exponent: float,
          ref: dict) -> dict:
    """One sphere per phase, side by side, each hitting the plane; the worst relative
    errors over the phases: their mean and the worst (signed), and whether the run went
    through."""
    from dpm.impact.measure import bind

    sim = dpm.Simulation(dt=dt, gravity=(0, 0, 0), integrator=integrator, dt_check="off",
                         max_overlap=1.0)
    sim.speed_guard = False  # the integrator's own error, past the engine's guards
    sim.guards.escape = "off"
    sim.guards.energy = "off"
    bind(sim, im.NAMES)
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    wall = dpm.Material("wall", density=RHO, young=YOUNG, poisson=NU)
    p = dict(params, friction=0.3)
    sim.contact(mat, mat, model=model, **p)
    sim.contact(mat, wall, model=model, **p)
    sim.add_boundary("plane", material=wall, point=(0, 0, 0), normal=(0, 0, 1))
    gaps = np.array([max(ph, 1e-6) for ph in PHASES]) * V * dt
    gaps[0] = -1e-9 * R  # phase 0: touching at t = 0, as impact_models.py
    pos = np.array([[4 * R * k, 0.0, R + g] for k, g in enumerate(gaps)])
    sim.add_particles("sphere", material=mat, radius=R, positions=pos,
                      velocities=np.tile([0.0, 0.0, -V], (len(pos), 1)))
    n = len(pos)
    fs, ds = [], []
    started = np.zeros(n, bool)
    done = np.zeros(n, bool)
    after = 0
    for _ in range(200000):
        sim.run(steps=1, progress=False)
        b = sim.bodies
        if len(b) != n or not np.all(np.isfinite(b.position)):
            return {"ok": False}
        d = R - b.position[:, 2]
        f = b.force[:, 2].copy()
        fs.append(f)
        ds.append(d)
        started |= f != 0.0
        done |= started & (f == 0.0) & (d < 0.0)
        if done.all():
            after += 1
            if after > 3:  # position Verlet's velocity needs two free steps
                break
    else:
        return {"ok": False}
    F = np.array(fs)
    D = np.array(ds)
    t = dt * np.arange(1, len(F) + 1)
    out = {"ok": True}
    worst = {"duration_err": 0.0, "max_overlap_err": 0.0, "restitution_err": 0.0}
    mean = dict.fromkeys(worst, 0.0)
    q = 1.0 / end_exponent
    for k in range(n):
        f, d = F[:, k], D[:, k]
        on = np.nonzero(f != 0.0)[0]
        if len(on) == 0:
            return {"ok": False}
        last = on[-1]
        f1 = abs(f[last - 1]) ** q if last > 0 else 0.0
        f2 = abs(f[last]) ** q
        t_end = t[last] + (dt * f2 / (f1 - f2) if f1 > f2 else 0.0)
        t_start = max(gaps[k], 0.0) / V
        j = int(np.argmax(d))
        dmax = d[j]
        if 0 < j < len(d) - 1:
            a, bb, c = d[j - 1], d[j], d[j + 1]
            den = a - 2 * bb + c
            if den < 0:
                dmax = bb - 0.125 * (c - a) ** 2 / den
        e = sim.bodies.velocity[k, 2] / V
        errs = {"duration_err": (t_end - t_start) / ref["duration"] - 1,
                "max_overlap_err": dmax / ref["max_overlap"] - 1,
                "restitution_err": e / ref["restitution"] - 1}
        for key, val in errs.items():
            if not math.isfinite(val):
                return {"ok": False}
            mean[key] += float(val) / n
            if abs(val) > abs(worst[key]):
                worst[key] = float(val)
    out.update(mean)
    out.update({f"worst_{key}": val for key, val in worst.items()})
    return out


def sweep(integrators: list[str], models: list[str], restitutions: list[float],
          steps: list[int]) -> dict:
    table: dict = {}
    for integ in integrators:
        t0 = time.perf_counter()
        table[integ] = {}
        for model in models:
            table[integ][model] = {}
            for e in restitutions:
                params, ref, p = case(model, e)
                rows = []
                for n in steps:
                    dt = ref["duration"] / n
                    try:
                        r = batch(model, params, integ, dt, p, ref)
                    except dpm.UnstableRunError as exc:
                        r = {"ok": False, "error": str(exc).splitlines()[0]}
                    r["steps_per_contact"] = n
                    rows.append(r)
                table[integ][model][f"{e:g}"] = rows
        print(f"{integ}: {time.perf_counter() - t0:.0f} s", flush=True)
    return table


def main(argv: list[str] | None = None) -> int:
    ap = harness.parser(__doc__, "velocity Verlet and gear4 only, fewer rows")
    ap.add_argument("--integrator", action="append", default=None,
                    help="only this integrator (repeatable)")
    a = ap.parse_args(argv)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        if a.quick:
            integs = a.integrator or ["velocity_verlet", "gear4"]
            table = sweep(integs, ["hertz_mindlin", "hooke"], [0.3, 0.5, 1.0],
                          [3, 5, 7, 10, 20, 50])
        else:
            integs = a.integrator or EXPLICIT + IMPLICIT
            table = sweep(integs, MODELS, RESTITUTIONS, STEPS)
    finally:
        numba.set_num_threads(threads)
    result = {"scene": {"radius_m": R, "density": RHO, "young_Pa": YOUNG, "poisson": NU,
                        "impact_speed_m_s": V, "geometry": "sphere on a plane, head-on",
                        "phases": PHASES, "worst_of_phases": True},
              "equivalent": {"linear_spring_dashpot": "hooke", "maw_linear_spring": "hooke",
                             "linear_cohesion": "hertz_mindlin"},
              "table": table}
    path = harness.RESULTS / f"{harness.stem('advise_contact_errors', a.quick)}.json"
    if a.integrator and path.exists():  # add to what an earlier run measured
        old = json.loads(path.read_text())
        old["table"].update(table)
        result["table"] = old["table"]
    path = harness.write("advise_contact_errors", result, a.quick)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
