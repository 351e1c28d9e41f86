"""The advisor's error model, cost model and search (equations in docs/advise.md).

Error of the quantity Q for a set-up (integrator I, impact model m, step dt, shape
resolution rho), the sum of three parts taken as independent upper bounds::

    eps_Q = max_p [ Q_cal(n_p) max(1, E_e(I, m, e_p, n_p) / E_e,cal(n_p))
                    + (d_p/r_p) max(E_T, E_d)(I, m, e_p, n_p) ]
          + max_p (d_p/r_p) max(|T'/T - 1|, |d'/d - 1|, |kappa'/kappa - 1|)      (m not the scene's)
          + S_shape dev_rms(rho)

over the material pairs p that can meet: n_p = T_p/dt steps resolve pair p's contact of
duration T_p at the impact speed v. Q_cal(n) is the quantity's own relative error measured
on a calibration scene of its kind at a few steps per contact n_i against a run at 80
(``benchmarks/advise.py``: the mean of R replicas against the mean of R_ref; the systematic
error plus its standard uncertainty, an upper bound; never the scatter of one run), made a
step function that never grows with n: between n_i and n_i+1 the largest error measured at
n_i or finer, first order beyond the finest up to the reference's 80 (held there), and
below the coarsest scaled by the contacts' restitution error. It carries every way the step
reaches the quantity (dissipation, the tangential spring, the settling dynamics). E_e, E_T,
E_d are the tables' relative errors of one collision's restitution, duration and largest
overlap at n steps for integrator I, model m and the pair's restitution e_p (mean over the
contact's start within a step, made monotone in n: E(n) = max over n' >= n); E_e,cal the
same for the calibration scene's integrator, model and restitution: a scene whose contacts
err more than the calibration's at the same steps gets that much more error, one whose
contacts err less is given no credit for it. d_p/r_p = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5)
/ r is Hertz's largest overlap over the smaller body's radius, the weight with which a
stiffness or duration error moves lengths; T', d', kappa' the duration, overlap and
tangential over normal stiffness of the replacing law against Hertz-Mindlin's; dev_rms the
clustered shape's RMS surface deviation over its equal-volume radius.

Replicas: the quantity of one run scatters by sigma (relative, measured on the calibration
scene; for a time average scaled by sqrt(W_cal / W) to the scene's window W, sigma ~
1/sqrt(window) for a steady flow). The mean of N replicas (independent runs with perturbed
starts) meets the tolerance tol when ``eps_Q + z sigma / sqrt(N) <= tol`` (z = 2, about
95 %): the smallest such N (:func:`replicas_for`), at most ``MAX_REPLICAS``; the cost of a
set-up is N times one run's, and the search trades a finer step against more replicas.

Cost per simulated second (one thread), wall seconds:

    C = t_step / dt,   t_step = f_I [N_b c_b + (N_e - N_b) c_el + (z/2) N_e c_c(m)]
                              + N_e [c_l L(s) + c_r g(s) 2 v_r dt / s]

with c_b, c_el, c_c the per-body, per-element and per-touching-pair costs, f_I the
integrator's cost per step over velocity Verlet's, z touching partners per element, L(s) =
4 phi ((1 + s/(2 r))^3 - 1) the listed non-touching partners per element for skin s
(phi = 0.6), c_r the cost of a rebuild per element, scaled by g(s), the search volume over
that of the default skin, and rebuilt every s/(2 v_r dt) steps (v_r the speed that moves
elements between rebuilds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .scene import (
    HERTZ_ALTERNATIVES,
    IMPLICIT,
    NOT_CANDIDATES,
    SceneFacts,
    alternative_law,
    tangential_ratio,
)
from .tables import Tables

#: skins tried, in units of the smallest element radius (dpm's default: 0.4)
SKINS = (0.2, 0.4, 0.6, 0.8, 1.2, 1.6)
PACKING = 0.6
#: a set-up leaving the scene's own integrator or impact model ranks this much dearer per
#: change: its step module compiles once (about a minute), and differences of a few per
#: cent are below the cost model's accuracy
OTHER_MODULE = 1.05
#: the tunnelling guard stops a run when a body moves more than half its radius in a step;
#: the advice keeps dt under it at twice the impact speed
SPEED_MARGIN = 2.0
#: the mean of N replicas is taken to lie within Z_SCATTER sigma / sqrt(N) of the expected
#: value (about 95 % for a normal scatter)
Z_SCATTER = 2.0
#: the most replicas an advice plans; beyond, the tolerance is out of reach by replicas at
#: the scene's window
MAX_REPLICAS = 64


def replicas_for(tolerance: float, systematic: float, sigma: float,
                 z: float = Z_SCATTER) -> int | None:
    """The smallest number of replicas N >= 1 with ``systematic + z sigma / sqrt(N) <=
    tolerance`` (all relative errors), N = ceil((z sigma / (tolerance - systematic))^2);
    None when the systematic error alone reaches the tolerance (no N helps). No cap."""
    room = tolerance - systematic
    if not room > 0:
        return None
    if not sigma > 0:
        return 1
    x = (z * sigma / room) ** 2
    n = max(1, math.ceil(x))
    if n > 1 and (n - 1) >= x * (1 - 1e-12):  # floating-point ties: the smaller N
        n -= 1
    return n


@dataclass(frozen=True)
class Setting:
    """A set-up: impact model ("as set": the scene's own laws), integrator, step [s], skin
    [m], clustered shapes' resolution (None: the scene's, or spheres only)."""

    impact_model: str
    integrator: str
    dt: float
    skin: float
    resolution: float | None = None

    def describe(self) -> str:
        res = "" if self.resolution is None else f", resolution {self.resolution:g}"
        return (f"{self.impact_model}, {self.integrator}, dt = {self.dt:.4g} s, skin = "
                f"{self.skin:.3g} m{res}")


@dataclass
class Prediction:
    """A set-up with its predicted error (relative, of the quantity) and its parts, its
    predicted cost [wall s per simulated s, one thread], the fewest steps per contact over
    the scene's pairs and what limited dt."""

    setting: Setting
    error: float
    parts: dict[str, float]
    cost: float
    steps_per_contact: float
    limited_by: str
    notes: list[str] = field(default_factory=list)
    #: the cost the search ranks by: ``total_cost``, times OTHER_MODULE for each of
    #: integrator and model that is not the scene's own
    rank_cost: float = math.nan
    #: replicas: independent runs with perturbed starts whose quantity is averaged
    replicas: int = 1
    #: relative run-to-run scatter (standard deviation) of one run's quantity
    sigma: float = 0.0
    #: coverage factor of the replica mean's statistical error (2: about 95 %)
    z: float = Z_SCATTER

    @property
    def statistical_error(self) -> float:
        """z sigma / sqrt(N): the bound on the replica mean's statistical error."""
        return self.z * self.sigma / math.sqrt(self.replicas)

    @property
    def total_error(self) -> float:
        """The systematic error (``error``) plus the statistical one: what the tolerance
        is met by."""
        return self.error + self.statistical_error

    @property
    def total_cost(self) -> float:
        """``cost`` (one run) times the replicas [wall s per simulated s, one thread]."""
        return self.cost * self.replicas


def bound(point: dict, calibration: dict) -> float:
    """Q_cal at one calibration step: its systematic error plus that error's standard
    uncertainty (tables of ``benchmarks/advise.py`` with replicas). An older table's point
    is the difference of two single runs: its uncertainty is sqrt(2) sigma."""
    if "uncertainty" in point:
        return float(point.get("systematic_error", point["measured_error"])) \
            + float(point["uncertainty"])
    return float(point["measured_error"]) + math.sqrt(2) * float(
        calibration.get("scatter") or 0.0)


class Model:
    """Error and cost model of one scene and quantity (see the module docstring)."""

    def __init__(self, facts: SceneFacts, tables: Tables, calibration: dict | None,
                 coordination: float | None = None, max_rayleigh: float = 0.3,
                 window: float | None = None) -> None:
        self.f = facts
        self.t = tables
        #: the quantity's calibration (None: its error is its contacts' restitution error)
        self.cal = calibration
        #: one run's relative scatter at this scene's window (0: none measured)
        self.sigma = 0.0
        #: sqrt(W_cal / W), the scatter's scaling to this scene's window (1: none)
        self.window_scale = 1.0
        if calibration is not None:
            pts = sorted((float(p["steps_per_contact"]), bound(p, calibration))
                         for p in calibration["points"])
            self.cal_n = [n for n, _ in pts]
            self.cal_err = [max(e for _, e in pts[k:]) for k in range(len(pts))]
            sig = float(calibration.get("scatter") or 0.0)
            w_cal = calibration.get("window")
            if sig > 0 and w_cal and window and window > 0:
                self.window_scale = math.sqrt(float(w_cal) / float(window))
            self.sigma = sig * self.window_scale
        self.z = float(coordination if coordination is not None
                       else tables.cost["coordination"])
        self.max_rayleigh = float(max_rayleigh)
        self._laws: dict[tuple[int, str], Any] = {}

    # ------------------------------------------------------------------ helpers
    def law(self, k: int, model: str) -> Any:
        p = self.f.pairs[k]
        if model in ("as set", p.model):
            return p.law
        key = (k, model)
        if key not in self._laws:
            self._laws[key] = alternative_law(p, model, self.f.impact_speed)
        return self._laws[key]

    def overlap_ratio(self, k: int) -> float:
        p = self.f.pairs[k]
        d = p.hertz_overlap(self.f.impact_speed)
        if not math.isfinite(d):  # laws without elastic constants: their own spring
            kn = float(p.law.params.get("stiffness", math.nan))
            d = self.f.impact_speed * math.sqrt(p.meff / kn)
        return d / p.radius

    def current_resolution(self) -> float | None:
        """The clustered shapes' resolution, found from their elements per body in the
        shape table (the first clustered shape's; None: spheres only)."""
        if not self.f.shapes:
            return None
        s = self.f.shapes[0]
        return self._shape_table(s.name)[0]["inferred"](s.count)

    def _shape_table(self, name: str) -> tuple[dict, list[str]]:
        import numpy as np

        tab = self.t.shape(name)
        notes = []
        if tab is None:
            names = self.t.shape_names()
            notes.append(f"shape {name!r} is not in the shape table ({', '.join(names)}): "
                         "their mean is taken")
            rows = [self.t.shape(n) for n in names]
            tab = {k: list(np.mean([r[k] for r in rows], axis=0))
                   for k in ("resolution", "count", "dev_rms_rel", "r_min_over_r_eq")}
        x = np.asarray(tab["resolution"], float)
        lc = np.log(np.asarray(tab["count"], float))
        lr = np.log(np.asarray(tab["r_min_over_r_eq"], float))
        out = {"x": x,
               "inferred": lambda count: float(np.interp(np.log(count), lc, x)),
               "count": lambda res: float(np.exp(np.interp(res, x, lc))),
               "r_min": lambda res: float(np.exp(np.interp(res, x, lr))),
               "dev": lambda res: float(np.interp(res, x, tab["dev_rms_rel"]))}
        return out, notes

    def shape_scale(self, resolution: float | None) -> tuple[float, float, float, list[str]]:
        """(elements per body over the scene's, smallest element over the scene's, RMS
        surface deviation over the equal-volume radius) of the clustered shapes at
        ``resolution`` (table ratios between it and the scene's inferred resolution)."""
        if not self.f.shapes:
            return 1.0, 1.0, 0.0, []
        cnt, rmin, dev, notes = 1.0, 1.0, 0.0, []
        for s in self.f.shapes:
            tab, n = self._shape_table(s.name)
            notes += n
            now = tab["inferred"](s.count)
            res = now if resolution is None else resolution
            if not tab["x"].min() <= res <= tab["x"].max():
                notes.append(f"resolution {res:g} outside the measured "
                             f"{tab['x'].min():g}-{tab['x'].max():g}")
            cnt = max(cnt, tab["count"](res) / tab["count"](now))
            rmin = min(rmin, tab["r_min"](res) / tab["r_min"](now))
            dev = max(dev, tab["dev"](res))
        return cnt, rmin, dev, list(dict.fromkeys(notes))

    # ------------------------------------------------------------------ error
    def cal_contact_error(self, model: str, e: float, n: float) -> float:
        """E_e,cal(n): the calibration scene's contacts' restitution error (without a
        calibration: velocity Verlet's for this pair)."""
        if self.cal is None:
            return self.t.contact_error("velocity_verlet", model, e, n).value
        c = self.cal["contact"]
        return self.t.contact_error(c["integrator"], c["model"], c["restitution"], n).value

    def quantity_error(self, model: str, e: float, n: float) -> tuple[float, list[str]]:
        """Q_cal(n): the quantity's error at n steps per contact on the calibration scene
        (without one: the pair's restitution error with velocity Verlet)."""
        if self.cal is None:
            return self.cal_contact_error(model, e, n), []
        ns, es = self.cal_n, self.cal_err
        if n < ns[0] * (1 - 1e-6):
            at = self.cal_contact_error(model, e, ns[0])
            scale = self.cal_contact_error(model, e, n) / at if at > 0 else math.inf
            return es[0] * max(1.0, scale), [
                f"{n:.3g} steps per contact: coarser than the calibration's {ns[0]:.3g}"]
        if n >= ns[-1]:
            # first order beyond the finest calibrated step, down to the reference's step
            # (the calibration measures against that run: no claim finer than it)
            n_ref = max(float(self.cal.get("reference_steps", 80.0)), ns[-1])
            return es[-1] * ns[-1] / min(n, n_ref), []
        k = max([i for i in range(len(ns)) if ns[i] <= n * (1 + 1e-6)], default=0)
        return es[k], []

    def error(self, model: str, integrator: str, dt: float, rmin_scale: float = 1.0,
              shape_dev: float = 0.0) -> tuple[float, dict[str, float], float, list[str]]:
        """(eps_Q, its parts, the fewest steps per contact, notes) at ``dt``."""
        notes: list[str] = []
        e_dt, e_model, n_min = 0.0, 0.0, math.inf
        for k, p in enumerate(self.f.pairs):
            law = self.law(k, model)
            T = self.f.contact_time(p, law) * rmin_scale
            n = T / dt
            n_min = min(n_min, n)
            e = p.restitution
            if not math.isfinite(e):
                e = 0.5
                notes.append(f"{p.label}: restitution not given (dissipation): the table of "
                             "e = 0.5 is taken")
            look = {kind: self.t.contact_error(integrator, law.name, e, n, kind)
                    for kind in ("restitution", "duration", "max_overlap")}
            for lk in look.values():
                notes += lk.notes
            q, qn = self.quantity_error(law.name, e, n)
            notes += qn
            e_cal = self.cal_contact_error(law.name, e, n)
            ratio = look["restitution"].value / e_cal if e_cal > 0 else math.inf
            w = self.overlap_ratio(k)
            e_dt = max(e_dt, q * max(1.0, ratio)
                       + w * max(look["duration"].value, look["max_overlap"].value))
            if law is not p.law:
                T0 = self.f.contact_time(p)
                d0 = p.hertz_overlap(self.f.impact_speed)
                if law.name == "maw_linear_spring":
                    d1 = d0  # built to reach Hertz's largest overlap at v
                else:  # hooke: k = 4/3 E* R*
                    from ..material import effective_young

                    kn = 4 / 3 * effective_young(p.a, p.b) * p.reff
                    d1 = self.f.impact_speed * math.sqrt(p.meff / kn)
                kap = tangential_ratio(p, law.name) / tangential_ratio(p, p.model)
                e_model = max(e_model, w * max(abs(T / rmin_scale / T0 - 1),
                                               abs(d1 / d0 - 1), abs(kap - 1)))
        parts = {"time_step": e_dt, "impact_model": e_model, "shape": shape_dev}
        return e_dt + e_model + shape_dev, parts, n_min, list(dict.fromkeys(notes))

    # ------------------------------------------------------------------ cost
    def cost(self, model: str, integrator: str, dt: float, skin: float,
             count_scale: float = 1.0, rmin_scale: float = 1.0) -> tuple[float, list[str]]:
        """Wall seconds per simulated second, one thread."""
        c = self.t.cost
        f = self.f
        ne = f.elements * count_scale
        nb = f.bodies
        models = {p.model for p in f.pairs} if model == "as set" else {model}
        cc, notes = 0.0, []
        for m in models:
            x, n = self.t.contact_ns(m)
            cc = max(cc, x)
            notes += n
        fi, n = self.t.step_factor(integrator)
        notes += n
        r = f.r_min * rmin_scale
        per_step = fi * (nb * c["body_ns"] + (ne - nb) * c["element_ns"]
                         + 0.5 * self.z * ne * cc)
        listed = 4 * PACKING * ((1 + skin / (2 * r)) ** 3 - 1)
        v_r = c["rebuild_speed_factor"] * f.impact_speed
        grow = ((2 * r + skin) / (2.4 * r)) ** 3
        per_step += ne * (c["listed_pair_ns"] * listed
                          + c["rebuild_ns_per_element"] * grow * 2 * v_r * dt / skin)
        return per_step * 1e-9 / dt, notes

    # ------------------------------------------------------------------ search
    def caps(self, integrator: str, model: str, rmin_scale: float) -> list[tuple[float, str]]:
        """Largest steps the engine and the guards allow: (dt, why)."""
        from ..plugins import registry

        n_min = registry().lookup("integrator", integrator).min_steps_per_contact
        t_min = min(self.f.contact_time(p, self.law(k, model)) * rmin_scale
                    for k, p in enumerate(self.f.pairs))
        # 1 % inside the engine's limit: its own check must not refuse the rounded step
        out = [(t_min / (1.01 * n_min), f"{n_min:g} steps per contact (the engine's least "
                                        f"for {integrator})")]
        if self.f.rayleigh is not None:
            out.append((self.max_rayleigh * self.f.rayleigh * rmin_scale,
                        f"{self.max_rayleigh:g} x the Rayleigh time step"))
        out.append((self.f.r_min * rmin_scale / (2 * SPEED_MARGIN * self.f.impact_speed),
                    "the tunnelling guard at twice the impact speed"))
        return out

    def finest_dt(self, model: str, rmin_scale: float) -> float:
        """The finest step the tables reach for every pair (4 x their finest step)."""
        t_max = max(self.f.contact_time(p, self.law(k, model)) * rmin_scale
                    for k, p in enumerate(self.f.pairs))
        return t_max / (3.99 * self.t.measured_steps()[1])

    def best_dt(self, model: str, integrator: str, budget: float, rmin_scale: float
                ) -> tuple[float, str]:
        """The largest dt whose time-step and model error stays within ``budget``."""
        dt_cap, why = min(self.caps(integrator, model, rmin_scale))
        if self.error(model, integrator, dt_cap, rmin_scale)[0] <= budget:
            return dt_cap, why
        lo = self.finest_dt(model, rmin_scale)  # the tables' reach, every pair
        if lo >= dt_cap or self.error(model, integrator, lo, rmin_scale)[0] > budget:
            return math.nan, "no step reaches the tolerance"
        hi = dt_cap
        for _ in range(60):
            mid = math.sqrt(lo * hi)
            if self.error(model, integrator, mid, rmin_scale)[0] <= budget:
                lo = mid
            else:
                hi = mid
            if hi / lo < 1 + 1e-6:
                break
        return lo, "the tolerance"

    def predict(self, setting: Setting, limited_by: str = "as set") -> Prediction:
        cnt, rs, dev, notes = self.shape_scale(setting.resolution)
        err, parts, n, n2 = self.error(setting.impact_model, setting.integrator, setting.dt,
                                       rs, self.S_shape * dev)
        cost, n3 = self.cost(setting.impact_model, setting.integrator, setting.dt,
                             setting.skin, cnt, rs)
        return Prediction(setting, err, parts, cost, n, limited_by,
                          list(dict.fromkeys(notes + n2 + n3)))

    S_shape = 1.0

    def candidates(self, integrators: list[str] | None, models: list[str] | None
                   ) -> tuple[list[str], list[str], list[float | None]]:
        f = self.f
        if integrators is None:
            integrators = [i for i in self.t.integrators() if i not in NOT_CANDIDATES
                           and (i not in IMPLICIT or f.implicit_ok)]
        own = {p.model for p in f.pairs}
        if models is None:
            models = ["as set"]
            if own == {"hertz_mindlin"}:
                models += list(HERTZ_ALTERNATIVES)
        resolutions: list[float | None] = [None]
        if f.shapes:
            now = self.current_resolution()
            x = self._shape_table(f.shapes[0].name)[0]["x"]
            resolutions = sorted({now, *(float(r) for r in x)})
        return integrators, models, resolutions

    def replicas(self, tolerance: float, systematic: float) -> int | None:
        """Replicas this scene's scatter needs for ``tolerance`` at a systematic error
        (:func:`replicas_for`; None: the systematic error alone reaches the tolerance)."""
        return replicas_for(tolerance, systematic, self.sigma)

    def with_replicas(self, p: Prediction, tolerance: float) -> Prediction:
        """``p`` given the replicas it needs for ``tolerance`` (MAX_REPLICAS where it needs
        more or no number suffices: it then does not meet the tolerance)."""
        n = self.replicas(tolerance, p.error)
        p.sigma = self.sigma
        p.replicas = n if n is not None and n <= MAX_REPLICAS else MAX_REPLICAS
        return p

    def _per_run_cost(self, model: str, integrator: str, dt: float, count_scale: float,
                      rmin_scale: float) -> float:
        return min(self.cost(model, integrator, dt, sk * self.f.r_min * rmin_scale,
                             count_scale, rmin_scale)[0] for sk in SKINS)

    def plan(self, model: str, integrator: str, budget: float, count_scale: float = 1.0,
             rmin_scale: float = 1.0) -> tuple[float, int, str]:
        """(dt, N, why): the step and replicas of the lowest total cost (N runs) whose
        time-step and model error plus z sigma / sqrt(N) stays within ``budget``; every N
        from 1 to MAX_REPLICAS is tried (a finer step against more replicas). dt is NaN
        when none is within reach."""
        if not self.sigma > 0:
            dt, why = self.best_dt(model, integrator, budget, rmin_scale)
            return dt, 1, why
        dt_cap = min(self.caps(integrator, model, rmin_scale))[0]
        floor = self._per_run_cost(model, integrator, dt_cap, count_scale, rmin_scale)
        best: tuple[float, float, int, str] = (math.inf, math.nan, 0, "")
        for n in range(1, MAX_REPLICAS + 1):
            if n * floor >= best[0]:  # no step is cheaper per run than the coarsest
                break
            room = budget - Z_SCATTER * self.sigma / math.sqrt(n)
            if room <= 0:
                continue
            dt, why = self.best_dt(model, integrator, room, rmin_scale)
            if not math.isfinite(dt):
                continue
            eps = self.error(model, integrator, dt, rmin_scale)[0]
            need = min(n, replicas_for(budget, eps, self.sigma) or n)
            total = need * self._per_run_cost(model, integrator, dt, count_scale, rmin_scale)
            if total < best[0]:
                best = (total, dt, need, why)
            if dt >= dt_cap * (1 - 1e-12):  # more replicas cannot coarsen the step further
                break
        return best[1], best[2], best[3]

    def search(self, tolerance: float, integrators: list[str] | None = None,
               models: list[str] | None = None) -> list[Prediction]:
        """Every candidate's cheapest set-up and replicas meeting ``tolerance`` (lowest
        total cost of all replicas), cheapest first (those that cannot: last, by their
        error bound with MAX_REPLICAS)."""
        ints, mods, ress = self.candidates(integrators, models)
        out = []
        for res in ress:
            cnt, rs, dev, _ = self.shape_scale(res)
            for integ in ints:
                for model in mods:
                    budget = tolerance - self.S_shape * dev
                    dt, n, why = (self.plan(model, integ, budget, cnt, rs) if budget > 0
                                  else (math.nan, 0,
                                        "the shape error alone exceeds the tolerance"))
                    if not math.isfinite(dt):  # out of reach: its finest step in the tables
                        dt, n, why = self.finest_dt(model, rs), 0, \
                            "out of reach (the finest step)"
                    best = None
                    for sk in SKINS:
                        s = Setting(model, integ, dt, sk * self.f.r_min * rs, res)
                        p = self.predict(s, why)
                        if best is None or p.cost < best.cost:
                            best = p
                    if n:
                        best.sigma, best.replicas = self.sigma, n
                    else:
                        self.with_replicas(best, tolerance)
                    out.append(best)
        own_i = self.f.integrator
        for p in out:
            p.rank_cost = p.total_cost \
                * (OTHER_MODULE if p.setting.integrator != own_i else 1.0) \
                * (OTHER_MODULE if p.setting.impact_model != "as set" else 1.0)
        ok = [p for p in out if p.total_error <= tolerance * (1 + 1e-9)]
        bad = [p for p in out if p not in ok]
        ok.sort(key=lambda p: (p.rank_cost, p.setting.integrator != own_i,
                               p.setting.impact_model != "as set"))
        bad.sort(key=lambda p: p.total_error)
        return ok + bad
