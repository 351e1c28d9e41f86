"""The measured tables the advisor reads (``dpm/data/work_precision.json``).

The file is written by :mod:`dpm.advice.condense` from the benchmark results (never read
from ``benchmarks/`` at run time). What it holds and where each figure comes from:

- ``contact``: the error of one head-on collision against steps per contact n, per
  integrator, impact model and restitution (``benchmarks/advise_tables.py``: the mean over
  eight phases of the contact's start within a step, and the worst phase), relative to the
  model's analytic solution: restitution, contact duration, largest overlap;
- ``elastic``: the rebound-velocity error of an elastic collision for every integrator
  (``benchmarks/integrators.py``, collision study), for integrators without a ``contact``
  table;
- ``cost``: ns per contact per step of each model in the engine
  (``benchmarks/impact_models.py``), each integrator's cost per step relative to velocity
  Verlet (``benchmarks/integrators.py``), the per-body, per-element, listed-pair and
  rebuild costs, the measured speeds of box_settle and the silo;
- ``shapes``: sphere count, surface deviation, volume ratio and smallest element of the
  clustered cylinder, torus and tetrahedron against resolution
  (``benchmarks/shapes_speed_vs_error.py``);
- ``sensitivity``: per quantity, its calibration (``benchmarks/advise.py``): the systematic
  error at a few steps per contact against a reference at 80 (means of replicas) with its
  standard uncertainty, the contact law of the calibration scene, and the run-to-run
  scatter sigma of one run with its degrees of freedom and averaging window.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

DATA = Path(__file__).resolve().parent.parent / "data" / "work_precision.json"

#: error kinds of the contact tables
KINDS = ("restitution", "duration", "max_overlap")


@dataclass
class Lookup:
    """A looked-up error: its value and the notes on how it was found (out of the
    measured range, another model's or integrator's table, extrapolated)."""

    value: float
    notes: list[str] = field(default_factory=list)


def _envelope(n: list[float], err: list[float | None]) -> tuple[list[float], list[float]]:
    """E(n) = max over n' >= n of |err(n')| (unmeasured or failed rows: infinite), so that
    a finer step never predicts a larger error (the measured errors change sign)."""
    order = sorted(range(len(n)), key=lambda k: n[k])
    xs = [float(n[k]) for k in order]
    ys = [math.inf if err[k] is None else abs(float(err[k])) for k in order]
    env = ys[:]
    for k in range(len(env) - 2, -1, -1):
        env[k] = max(env[k], env[k + 1])
    return xs, env


def _interp_loglog(xs: list[float], ys: list[float], x: float) -> float:
    """Linear in log-log between the grid points (zero and infinite values handled)."""
    if x <= xs[0]:
        return ys[0] if x == xs[0] else math.inf
    if x >= xs[-1]:
        # beyond the finest measured step: first order from the last point (conservative
        # for every model here, which converge at order 1 to 3), up to 4 times it
        return ys[-1] * xs[-1] / x if x <= 4 * xs[-1] else math.inf
    for k in range(len(xs) - 1):
        a, b = xs[k], xs[k + 1]
        if a <= x <= b:
            ya, yb = ys[k], ys[k + 1]
            if math.isinf(ya) or math.isinf(yb):
                return math.inf if x < b else yb
            if ya <= 0 or yb <= 0:
                return max(ya, yb)
            w = math.log(x / a) / math.log(b / a)
            return math.exp((1 - w) * math.log(ya) + w * math.log(yb))
    return ys[-1]


class Tables:
    """The condensed tables with their look-ups (see the module docstring)."""

    def __init__(self, data: dict[str, Any], path: Path | None = None) -> None:
        self.data = data
        self.path = path
        self._env: dict[tuple, tuple[list[float], list[float]]] = {}

    # ------------------------------------------------------------------ contact errors
    @property
    def equivalent(self) -> dict[str, str]:
        """Models measured through another's table (the same dimensionless problem)."""
        return dict(self.data.get("equivalent", {}))

    def table_model(self, model: str) -> str | None:
        """The model whose table stands for ``model`` (None: none measured)."""
        models = {m for t in self.data["contact"].values() for m in t}
        if model in models:
            return model
        eq = self.equivalent.get(model)
        return eq if eq in models else None

    def integrators(self) -> list[str]:
        return list(self.data["contact"])

    def restitutions(self, integrator: str, model: str) -> list[float]:
        return sorted(float(e) for e in self.data["contact"][integrator][model])

    def measured_steps(self) -> tuple[float, float]:
        ns = [n for t in self.data["contact"].values() for m in t.values()
              for row in m.values() for n in row["n"]]
        return min(ns), max(ns)

    def _curve(self, integrator: str, model: str, e: str, kind: str):
        key = (integrator, model, e, kind)
        if key not in self._env:
            row = self.data["contact"][integrator][model][e]
            self._env[key] = _envelope(row["n"], row[kind])
        return self._env[key]

    def contact_error(self, integrator: str, model: str, restitution: float, n: float,
                      kind: str = "restitution") -> Lookup:
        """The absolute relative error of ``kind`` for one collision of ``model`` at ``restitution``
        resolved by ``n`` steps (the monotone envelope of the table; between two measured
        restitutions the larger of the two)."""
        notes: list[str] = []
        tm = self.table_model(model)
        if tm is None:
            # a model without a table: the worst measured model at this integrator
            worst = 0.0
            for m in {m for t in self.data["contact"].values() for m in t}:
                worst = max(worst, self.contact_error(integrator, m, restitution, n,
                                                      kind).value)
            notes.append(f"no table for the impact model {model!r}: the worst measured "
                         "model's error is taken")
            return Lookup(worst, notes)
        if tm != model:
            notes.append(f"{model} read from the table of {tm} (same dimensionless "
                         "collision)" if model in self.equivalent else "")
            notes = [x for x in notes if x]
        if integrator not in self.data["contact"] or tm not in self.data["contact"][integrator]:
            base = self.contact_error("velocity_verlet", tm, restitution, n, kind)
            ratio = self.elastic_ratio(integrator, n, tm)
            notes += base.notes + [f"no collision table for {integrator}: velocity Verlet's "
                                   f"error x {ratio:.3g} (the ratio of their elastic "
                                   "collision errors, benchmarks/integrators.py)"]
            return Lookup(base.value * ratio, notes)
        es = self.restitutions(integrator, tm)
        e = float(restitution)
        if e < es[0] or e > es[-1]:
            notes.append(f"restitution {e:g} outside the measured {es[0]:g}-{es[-1]:g}: the "
                         "nearest table is taken")
        lo = max([x for x in es if x <= e] or [es[0]])
        hi = min([x for x in es if x >= e] or [es[-1]])
        vals = []
        for x in {lo, hi}:
            xs, env = self._curve(integrator, tm, f"{x:g}", kind)
            if n < xs[0]:
                notes.append(f"{n:.3g} steps per contact is below the measured {xs[0]:g}")
            vals.append(_interp_loglog(xs, env, n))
        xs_ = self._curve(integrator, tm, f"{lo:g}", kind)[0]
        if n > xs_[-1]:
            notes.append(f"{n:.3g} steps per contact is above the measured {xs_[-1]:g} "
                         "(first order assumed beyond, up to 4 times it)")
        return Lookup(max(vals), notes)

    def local_order(self, integrator: str, model: str, restitution: float, n: float) -> float:
        """Observed order p of the restitution error between n and 2n (for the Richardson
        estimate), clipped to [1, 3]."""
        a = self.contact_error(integrator, model, restitution, n).value
        b = self.contact_error(integrator, model, restitution, 2 * n).value
        if not (a > 0 and b > 0) or math.isinf(a) or math.isinf(b) or b >= a:
            return 1.0
        return min(3.0, max(1.0, math.log2(a / b)))

    def elastic_ratio(self, integrator: str, n: float, model: str) -> float:
        """Error of ``integrator`` over velocity Verlet's on an elastic collision at n
        steps (the Hertz table for Hertz-type models, the linear one otherwise)."""
        law = "hertz" if "hertz" in model or model == "linear_cohesion" else "linear"
        tab = self.data.get("elastic", {}).get(law, {})
        if integrator not in tab or "velocity_verlet" not in tab:
            return math.inf
        xs, ei = _envelope(tab[integrator]["n"], tab[integrator]["v_err"])
        xv, ev = _envelope(tab["velocity_verlet"]["n"], tab["velocity_verlet"]["v_err"])
        a, b = _interp_loglog(xs, ei, n), _interp_loglog(xv, ev, n)
        return a / b if b > 0 else math.inf

    # ------------------------------------------------------------------ cost
    @property
    def cost(self) -> dict[str, Any]:
        return self.data["cost"]

    def contact_ns(self, model: str) -> tuple[float, list[str]]:
        """ns per touching pair per step of ``model`` without the per-body part."""
        ns = self.cost["engine_ns_per_contact_step"]
        body = self.cost["body_ns"]
        m = model if model in ns else self.equivalent.get(model)
        if m in ns:
            return ns[m] - body / 3.0, []
        worst = max(ns.values())
        return worst - body / 3.0, [f"no cost measured for {model!r}: the dearest model's"]

    def step_factor(self, integrator: str) -> tuple[float, list[str]]:
        f = self.cost["integrator_step_factor"]
        if integrator in f:
            return float(f[integrator]), []
        return 1.0, [f"no cost measured for the integrator {integrator!r}: velocity Verlet's"]

    # ------------------------------------------------------------------ shapes
    def shape(self, name: str) -> dict[str, list[float]] | None:
        return self.data.get("shapes", {}).get(name)

    def shape_names(self) -> list[str]:
        return sorted(self.data.get("shapes", {}))

    # ------------------------------------------------------------------ sensitivities
    def sensitivity(self, quantity: str) -> dict[str, Any] | None:
        return self.data.get("sensitivity", {}).get(quantity)


@lru_cache(maxsize=4)
def _load(path: str, mtime: float) -> Tables:
    return Tables(json.loads(Path(path).read_text()), Path(path))


def load_tables(path: str | Path | None = None) -> Tables:
    """The tables of ``path`` (default: the shipped ``dpm/data/work_precision.json``);
    read again when the file changed."""
    p = Path(path) if path is not None else DATA
    if not p.exists():
        from ..errors import DpmError

        raise DpmError(f"{p}: the advisor's tables are missing (python -m "
                       "dpm.advice.condense writes them from benchmarks/results)")
    return _load(str(p), p.stat().st_mtime)
