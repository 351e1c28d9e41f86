"""``dpm.advise``: the cheapest set-up that meets a tolerance on a quantity of interest."""

from __future__ import annotations

import copy
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from .model import MAX_REPLICAS, Z_SCATTER, Model, Prediction, Setting, replicas_for
from .quantities import Quantity, run_and_measure
from .quantities import quantity as find_quantity
from .scene import SceneFacts, alternative_law, scene_facts
from .tables import load_tables


@dataclass
class Verification:
    """Pilot runs of the scene at the chosen step and at half of it: the quantity at each,
    the Richardson estimate of the chosen step's relative error,
    ``|Q(dt) - Q(dt/2)| / (|Q(dt/2)| (1 - 2^-p))``, with p the order of the contacts' error at
    that step (from the tables), and the measured cost [wall and CPU s per simulated s]."""

    dt: tuple[float, float]
    values: tuple[float, float]
    order: float
    estimate: float
    cost: tuple[float, float]
    run_time: float
    tolerance: float
    #: CPU seconds per simulated second of each pilot (one thread)
    cpu_cost: tuple[float, float] = (float("nan"), float("nan"))

    @property
    def within(self) -> bool:
        return self.estimate <= self.tolerance


@dataclass
class Advice:
    """What :func:`advise` recommends.

    ``choice``: the cheapest set-up predicted to meet the tolerance (its setting, predicted
    relative systematic error and parts, the replicas it needs, predicted cost in wall
    seconds per simulated second on one thread, per run and of all replicas);
    ``default``: the scene's own set-up under the same models, with the replicas it needs
    for the same tolerance; ``feasible``: whether any set-up meets the tolerance (if not,
    ``choice`` is the most accurate one); ``candidates``: every integrator and model's
    best; ``assumptions`` and ``warnings`` (out of the validated range) as sentences;
    ``verification``: the pilot runs, when asked.

    ``replicas`` (N) is a run plan, not a scene setting: run the advised set-up N times
    with starts perturbed by an amount no measurement tells apart (e.g. every body moved by
    1e-3 of its radius, a different seed each) and average the quantity over the N runs.
    ``apply`` sets the step, not the runs.
    """

    quantity: str
    unit: str
    tolerance: float
    choice: Prediction
    default: Prediction
    feasible: bool
    candidates: list[Prediction]
    assumptions: list[str]
    warnings: list[str]
    run_time: float | None = None
    verification: Verification | None = None
    facts: SceneFacts | None = field(default=None, repr=False)
    #: whether the scene's own set-up meets the tolerance with at most MAX_REPLICAS
    default_feasible: bool = True
    #: one run's relative scatter sigma at the scene's window (0: none measured)
    scatter: float = 0.0
    #: replicas needed where more than ``max_replicas`` (None: within, or no number helps)
    replicas_needed: int | None = None
    #: for a tolerance out of reach by replicas: how many times longer an averaging window
    #: would let ``max_replicas`` runs reach it (sigma ~ 1/sqrt(window), a steady flow)
    window_factor: float | None = None
    max_replicas: int = MAX_REPLICAS
    z: float = Z_SCATTER

    @property
    def replicas(self) -> int:
        """N: independent runs of the chosen set-up with perturbed starts, their quantity
        averaged, that the tolerance needs (a run plan: ``apply`` does not set it)."""
        return int(self.choice.replicas)

    @property
    def speedup(self) -> float:
        """Predicted cost of the scene's own set-up (its step, with the replicas it needs
        for the same tolerance) over the choice's (all its replicas)."""
        return self.default.total_cost / self.choice.total_cost

    def apply(self, sim: Any) -> None:
        """Set the chosen step, skin, integrator and impact model on ``sim`` (a scene that
        has not run yet). A clustered shape's resolution cannot be changed on built bodies:
        rebuild them with the chosen ``resolution``."""
        apply_setting(sim, self.choice.setting)

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.pop("facts", None)
        d["replicas"] = self.replicas
        for k, p in (("choice", self.choice), ("default", self.default)):
            d[k].update(statistical_error=p.statistical_error, total_error=p.total_error,
                        total_cost=p.total_cost)
        return d

    def __str__(self) -> str:
        c, d = self.choice, self.default
        pct = 100 * self.tolerance
        n = c.replicas
        rt = ((lambda cost: f", {cost * self.run_time:.3g} s for {self.run_time:g} s")
              if self.run_time else (lambda cost: ""))  # noqa: E731
        lines = [f"dpm advise: {self.quantity} within {pct:g} %"
                 + ("" if self.feasible else " - NOT REACHED within the measured range"
                    if self.replicas_needed is None else
                    f" - NOT REACHED with up to {self.max_replicas} replicas"),
                 f"  choice:  {c.setting.describe()}",
                 f"           {c.steps_per_contact:.3g} steps per shortest contact (dt "
                 f"limited by {c.limited_by})",
                 f"           replicas: {n} (independent runs with perturbed starts, their "
                 f"{self.quantity} averaged; one run scatters by sigma = "
                 f"{100 * c.sigma:.2g} %)",
                 f"           predicted error {100 * c.total_error:.3g} %: systematic "
                 f"{100 * c.error:.3g} % (time step {100 * c.parts['time_step']:.3g} %, "
                 f"impact model {100 * c.parts['impact_model']:.3g} %, shape "
                 f"{100 * c.parts['shape']:.3g} %) + statistical {self.z:g} sigma / sqrt({n}) "
                 f"= {100 * c.statistical_error:.3g} %",
                 f"           predicted cost {c.total_cost:.3g} s per simulated second (one "
                 f"thread; {c.cost:.3g} per run x {n})" + rt(c.total_cost),
                 f"  default: {d.setting.describe()}: {d.steps_per_contact:.3g} steps per "
                 f"contact, systematic error {100 * d.error:.3g} %, "
                 + (f"needs {d.replicas} replica{'s' if d.replicas != 1 else ''} for "
                    f"the same tolerance: cost "
                    f"{d.total_cost:.3g} s/s (the choice: {self.speedup:.2f}x cheaper)"
                    if self.default_feasible else
                    f"cannot reach the tolerance with up to {self.max_replicas} replicas "
                    f"(cost {d.cost:.3g} s/s per run)")]
        seen = set()
        others = []
        for p in self.candidates:
            key = (p.setting.integrator, p.setting.impact_model)
            if key in seen or p is c:
                seen.add(key)
                continue
            seen.add(key)
            reach = ("" if p.total_error <= self.tolerance * (1 + 1e-9)
                     else "  (cannot reach the tolerance)")
            others.append(f"    {p.setting.impact_model:18s} {p.setting.integrator:17s} "
                          f"dt {p.setting.dt:.3g} s x {p.replicas}  error "
                          f"{100 * p.total_error:.3g} %  cost {p.total_cost:.3g} s/s{reach}")
        if others:
            lines.append("  other candidates (best of each; dt x replicas):")
            lines += others[:12]
        v = self.verification
        if v is not None:
            lines.append(f"  verification: {self.quantity} = {v.values[0]:.6g} at dt = "
                         f"{v.dt[0]:.4g} s, {v.values[1]:.6g} at dt/2 over {v.run_time:g} s; "
                         f"Richardson estimate (p = {v.order:.2f}) {100 * v.estimate:.3g} % "
                         f"{'within' if v.within else 'OUTSIDE'} the tolerance (predicted "
                         f"systematic {100 * c.error:.3g} %; one run each: the difference "
                         f"holds the scatter too); measured {v.cost[0]:.3g} s/s "
                         f"(predicted {c.cost:.3g})")
        lines.append("  assumptions:")
        lines += [f"  - {a}" for a in self.assumptions]
        if self.warnings:
            lines.append("  out of the validated range / warnings:")
            lines += [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)


def apply_setting(sim: Any, s: Setting) -> None:
    """Give ``sim`` the step, skin, integrator and impact model of ``s``."""
    from ..plugins import registry

    if s.integrator != sim.integrator.name:
        if sim.step_count:
            raise ParameterError(f"Advice.apply(): the integrator {s.integrator!r} can only "
                                 "be set before the first run")
        sim.integrator = registry().lookup("integrator", s.integrator, "Advice.apply()")()
        sim._prepared = False
    if s.impact_model != "as set":
        facts = scene_facts(sim)
        for p in facts.pairs:
            if p.model != s.impact_model:
                law = alternative_law(p, s.impact_model, facts.impact_speed)
                sim.contact(p.a, p.b, model=s.impact_model, **law.params)
    sim.dt = s.dt
    sim.skin = s.skin


def _check(tolerance: Any, run_time: Any, window: Any, impact_speed: Any,
           coordination: Any, max_rayleigh: Any) -> None:
    def bad(name: str, value: Any, allowed: str) -> None:
        raise ParameterError(f"dpm.advise(): {name}={value!r}; allowed: {allowed}")

    def number(x: Any) -> bool:
        return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)

    if not number(tolerance) or not 0 < tolerance < 1:
        bad("tolerance", tolerance, "a relative error in (0, 1), e.g. 0.01 for 1 %")
    if run_time is not None and (not number(run_time) or run_time <= 0):
        bad("run_time", run_time, "a simulated time > 0 [s]")
    if window is not None:
        ok = (isinstance(window, Sequence) and len(window) == 2 and all(map(number, window))
              and window[0] < window[1])
        if not ok:
            bad("window", window, "(start, end) [s] with start < end")
    if impact_speed is not None and (not number(impact_speed) or impact_speed <= 0):
        bad("impact_speed", impact_speed, "a speed > 0 [m/s]")
    if coordination is not None and (not number(coordination) or coordination <= 0):
        bad("coordination", coordination, "touching partners per element > 0")
    if not number(max_rayleigh) or not 0 < max_rayleigh <= 1:
        bad("max_rayleigh", max_rayleigh, "a fraction of the Rayleigh step in (0, 1]")


def advise(sim: Any, tolerance: float = 0.01, quantity: str | Quantity = "settled_height", *,
           verify: bool = False, run_time: float | None = None,
           window: tuple[float, float] | None = None, impact_speed: float | None = None,
           coordination: float | None = None, integrators: Sequence[str] | None = None,
           models: Sequence[str] | None = None, max_rayleigh: float = 0.3,
           pilot: Callable[[], Any] | None = None, tables: str | None = None) -> Advice:
    """The cheapest impact model, integrator, time step, skin and shape resolution that keep
    the relative error of ``quantity`` within ``tolerance``, with the predicted error and
    cost per simulated second, the assumptions, and where the advice leaves the measured
    range (docs/advise.md gives the models and their sources).

    Parameters
    ----------
    sim : Simulation
        The scene, built (bodies, boundaries, contact laws); it is read, not run.
    tolerance : float
        Relative error of the quantity allowed, in (0, 1): 0.01 for 1 %.
    quantity : str
        ``"settled_height"``, ``"angle_of_repose"`` or ``"discharge_rate"``
        (:data:`dpm.advice.quantities.QUANTITIES`).
    verify : bool
        Also run the scene at the chosen step and at half of it for ``run_time`` and give
        the Richardson estimate of the error (:class:`Verification`).
    run_time : float, optional
        Simulated time of the run [s]: the total cost in the report, the pilots' length.
    window : (float, float), optional
        The quantity's averaging window [s] (angle of repose, discharge rate).
    impact_speed : float, optional
        The speed contacts are resolved at [m/s] (default: the time-step check's, the
        largest initial speed or the free-fall speed over the scene's height).
    coordination : float, optional
        Touching partners per element for the cost (default 4.8, a settled bed).
    integrators, models : list of str, optional
        Only these candidates (models: ``"as set"`` is the scene's own laws).
    max_rayleigh : float
        Largest step as a fraction of the Rayleigh step: default 0.3, the engine's advised
        limit (the settled box_settle bed went unstable at 0.35, 5.1 steps per contact;
        the engine refuses above 1).
    pilot : callable, optional
        Returns a fresh copy of the scene for each pilot run (default: a deep copy).
    tables : str, optional
        Another tables file (default: the shipped ``dpm/data/work_precision.json``).
    """
    q = find_quantity(quantity)
    _check(tolerance, run_time, window, impact_speed, coordination, max_rayleigh)
    if verify and run_time is None:
        raise ParameterError("dpm.advise(): verify=True needs run_time (the pilot runs' "
                             "simulated time [s])")
    q.check(sim)
    tab = load_tables(tables)
    facts = scene_facts(sim, impact_speed)
    sens = tab.sensitivity(q.name)
    wlen = window_length(q, sim, run_time, window)
    mdl = Model(facts, tab, sens, coordination, max_rayleigh, wlen)
    ranked = mdl.search(float(tolerance), None if integrators is None else list(integrators),
                        None if models is None else list(models))
    choice = ranked[0]
    feasible = choice.total_error <= tolerance * (1 + 1e-9)
    skin = facts.skin if facts.skin is not None else 0.4 * facts.r_min
    default = mdl.with_replicas(mdl.predict(Setting("as set", facts.integrator, facts.dt,
                                                    skin, mdl.current_resolution())),
                                float(tolerance))
    default_ok = default.total_error <= tolerance * (1 + 1e-9)
    need = None if feasible else replicas_for(float(tolerance), choice.error, mdl.sigma)
    # a time average's scatter shrinks with its window: the least lengthening that lets
    # MAX_REPLICAS runs reach the tolerance
    factor = need / MAX_REPLICAS if need is not None and wlen is not None else None
    assumptions, warns = _statements(q, facts, mdl, choice, sens, tolerance, feasible,
                                     need, factor)
    advice = Advice(q.name, q.unit, float(tolerance), choice, default, feasible, ranked,
                    assumptions, warns, run_time, None, facts, default_ok, mdl.sigma, need,
                    factor)
    if verify:
        factory = pilot if pilot is not None else (lambda: copy.deepcopy(sim))
        advice.verification = verify_choice(factory, q, choice, mdl, float(run_time),
                                            window, float(tolerance))
    return advice


def window_length(q: Quantity, sim: Any, run_time: float | None,
                  window: tuple[float, float] | None) -> float | None:
    """The length of the quantity's averaging window [s] (None: not known, or a quantity
    of the final state)."""
    if window is not None:
        a, b = window
    elif run_time is not None:
        a, b = q.window(sim, sim.time + float(run_time), None)
    else:
        return None
    return float(b - a) if b > a else None


def _statements(q: Quantity, f: SceneFacts, mdl: Model, c: Prediction, sens: dict | None,
                tol: float, feasible: bool, need: int | None = None,
                factor: float | None = None) -> tuple[list[str], list[str]]:
    w = max(mdl.overlap_ratio(k) for k in range(len(f.pairs)))
    a = [
        "the quantity's error has a systematic part, the sum of independent parts: the "
        "time step (the contacts' error at the step, from measured collision tables), the "
        "impact model (against the scene's Hertz-Mindlin law at the impact speed) and the "
        "shape resolution (surface deviation); and a statistical part, the run-to-run "
        "scatter, which replicas average down",
        f"{q.name}: {q.propagation}",
        _calibration_statement(q, sens),
        _replica_statement(mdl, sens),
        f"a contact's duration or overlap error moves lengths by delta/R = {w:.3g} of it "
        "(Hertz's largest overlap over the radius at the impact speed)",
        f"contacts are resolved at the impact speed {f.impact_speed:.3g} m/s (faster ones "
        "get fewer steps); the collision tables are head-on, averaged over where a contact "
        "starts within a step; friction, rolling resistance and the tangential spring are "
        "taken to err no more than the restitution",
        f"cost: one thread, {mdl.z:g} touching partners per element, per-contact costs of "
        "benchmarks/impact_models.py, per-body and rebuild costs measured on box_settle; "
        "another integrator or model compiles its step module once (about a minute), not "
        "counted; N replicas cost N runs; the default's cost is its own step with the "
        "replicas it needs for the same tolerance",
    ]
    warns: list[str] = []
    if not feasible and need is not None:
        msg = (f"{100 * tol:g} % is out of reach by replicas at this window: the choice's "
               f"systematic error {100 * c.error:.3g} % leaves {100 * (tol - c.error):.2g} % "
               f"for the statistical part, which needs N = {need} replicas, more than "
               f"{MAX_REPLICAS}")
        if factor is not None:
            msg += (f"; a window {factor:.3g} times as long would let {MAX_REPLICAS} do, "
                    f"{need / 8:.3g} times as long 8 (assuming sigma ~ 1/sqrt(window), a "
                    "steady flow)")
        else:
            msg += " (a final state: no window to lengthen)"
        warns.append(msg)
    elif not feasible:
        warns.append(f"no set-up reaches {100 * tol:g} % within the measured tables: the "
                     f"most accurate one's systematic error is {100 * c.error:.3g} % (the "
                     "calibration's bound: its measured step error plus that error's "
                     "uncertainty, which more calibration replicas would shrink); no "
                     "number of replicas helps")
    warns += c.notes
    if c.steps_per_contact < 10:
        warns.append(f"{c.steps_per_contact:.3g} steps per contact: the engine's time-step "
                     "check warns below 10 (expected: the error model covers the step)")
    if f.rayleigh is not None and c.setting.dt > 0.3 * f.rayleigh * (1 + 1e-9):
        warns.append(f"dt is {c.setting.dt / f.rayleigh:.2f} of the Rayleigh step: the engine "
                     "warns above 0.3 (a settled bed went unstable at 0.35)")
    dof = sens.get("scatter_dof") if sens else None
    if mdl.sigma > 0 and dof is not None and dof < 5:
        warns.append(f"the scatter sigma is a sample standard deviation of {dof} degree"
                     f"{'s' if dof != 1 else ''} of freedom: a rough figure")
    if sens is None:
        warns.append(f"{q.name}: no calibration (benchmarks/advise.py): the quantity is "
                     "taken to err as its contacts' restitution")
    else:
        warns.append(f"the step's error calibrated on one scene ({sens.get('scene', '?')}); other "
                     "materials, sizes, fill levels or friction are outside the validated "
                     "range")

    if f.bodies < 1000:
        warns.append(f"{f.bodies} bodies: the cost model is calibrated from 1,000 to 10^6 "
                     "bodies (below, per-call overheads weigh)")
    if f.shapes:
        warns.append("clustered shapes: the shape error propagates one to one (S_shape = 1, "
                     "not validated on a scene); Advice.apply() cannot change the resolution "
                     "of built bodies")
    return a, list(dict.fromkeys(warns))


def _calibration_statement(q: Quantity, sens: dict | None) -> str:
    if not sens:
        return ("no calibration for this quantity: it is taken to err as its contacts' "
                "restitution does")
    pts = sens["points"]
    new = all("uncertainty" in p for p in pts)
    if new:
        r, r_ref = pts[0].get("replicas", 1), sens.get("reference_replicas", 1)
        vals = ", ".join(f"{100 * p.get('systematic_error', p['measured_error']):.2g} +- "
                         f"{100 * p['uncertainty']:.2g} % at {p['steps_per_contact']:.3g}"
                         for p in pts)
        how = (f" steps per contact against 80 (the mean of {r} replica"
               f"{'s' if r != 1 else ''} against the mean of {r_ref}: systematic error +- "
               "its standard uncertainty), each taken as the error plus its uncertainty")
    else:
        vals = ", ".join(f"{100 * p['measured_error']:.2g} % at {p['steps_per_contact']:.3g}"
                         for p in pts)
        how = (f" steps per contact against 80, plus sqrt(2) x its scatter "
               f"{100 * sens['scatter']:.2g} % (an older table: single runs)")
    return (f"the step's error of {q.name} as measured on {sens.get('scene', 'a scene')}: "
            + vals + how + "; held to the next finer step, first order beyond; a scene "
            "whose contacts err more than that scene's at the same steps gets as much more")


def _replica_statement(mdl: Model, sens: dict | None) -> str:
    head = ("replicas: independent runs of the same set-up whose starts differ by a "
            "perturbation no measurement tells apart (every body moved by ~1e-3 of its "
            "radius, a different seed each), their quantity averaged; a run plan, not a "
            "scene setting (Advice.apply() sets the step only)")
    if not mdl.sigma > 0:
        return head + "; no scatter measured for this quantity: one run (N = 1)"
    sig = float(sens["scatter"]) if sens else mdl.sigma
    dof = sens.get("scatter_dof") if sens else None
    txt = (f"{head}; one run's scatter sigma = {100 * sig:.2g} % as measured on the "
           "calibration scene" + (f" ({dof} degrees of freedom)" if dof else ""))
    if mdl.window_scale != 1.0:
        txt += (f", x {mdl.window_scale:.3g} = {100 * mdl.sigma:.2g} % for this window "
                "(sigma ~ 1/sqrt(window): an assumption, a steady flow)")
    return (txt + f"; N is the smallest with systematic error + {Z_SCATTER:g} sigma / "
            f"sqrt(N) <= tolerance ({Z_SCATTER:g}: about 95 % for a normal scatter), at most "
            f"{MAX_REPLICAS}")


def verify_choice(factory: Callable[[], Any], q: Quantity, choice: Prediction, mdl: Model,
                  run_time: float, window: tuple[float, float] | None,
                  tolerance: float) -> Verification:
    """The pilot runs of :class:`Verification` (two runs of ``run_time`` s each)."""
    s = choice.setting
    out = []
    for dt in (s.dt, 0.5 * s.dt):
        sim = factory()
        apply_setting(sim, Setting(s.impact_model, s.integrator, dt, s.skin, s.resolution))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out.append(run_and_measure(sim, q, sim.time + run_time, window))
        sim.close()
    k = int(np.argmin([mdl.f.contact_time(p) for p in mdl.f.pairs]))
    pair = mdl.f.pairs[k]
    e = pair.restitution if math.isfinite(pair.restitution) else 0.5
    model = pair.model if s.impact_model == "as set" else s.impact_model
    p = mdl.t.local_order(s.integrator, model, e, choice.steps_per_contact)
    q1, q2 = out[0].value, out[1].value
    est = abs(q1 - q2) / max(abs(q2), 1e-300) / (1 - 2.0 ** (-p))
    return Verification((s.dt, 0.5 * s.dt), (q1, q2), p, est, (out[0].cost, out[1].cost),
                        run_time, tolerance, (out[0].cpu_cost, out[1].cpu_cost))
