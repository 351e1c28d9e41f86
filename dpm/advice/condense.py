"""Condense the benchmark results into the advisor's tables (``dpm/data/work_precision.json``).

Run after any of the benchmarks it reads was rerun::

    python -m dpm.advice.condense                    # reads benchmarks/results/
    python -m dpm.advice.condense RESULTS_DIR OUT.json

Read: ``advise_contact_errors.json`` (``benchmarks/advise_tables.py``),
``impact_models.json``, ``integrators.json``, ``shapes_speed_vs_error.json``,
``box_settle.json``, ``hopper_discharge.json`` and, when present, ``advise.json``
(``benchmarks/advise.py``: the quantities' sensitivities). The package reads only the
written file, never ``benchmarks/``.
"""

from __future__ import annotations

import json
import math
import statistics
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .tables import DATA

#: per-body cost of a step [ns]: velocity Verlet's pre-force loop 178 us and its second half
#: kick ~30 us per 10,000 bodies (each loop timed alone)
BODY_NS = 21.0
#: one neighbour-list rebuild per element [ns], dense 10,648-sphere box, 3.2 ms
#: (one search pass into slots sized by the previous list; dilute: 4.8 ms)
REBUILD_NS = 300.0
#: explicit integrators whose measured step costs lie within this factor of velocity
#: Verlet's are counted equal (the timings move by +-30 % on the shared machine)
NOISE = 1.3


def _contact(src: dict) -> dict:
    out: dict = {}
    for integ, models in src["table"].items():
        out[integ] = {}
        for model, by_e in models.items():
            out[integ][model] = {}
            for e, rows in by_e.items():
                ok = [r for r in rows]
                row = {"n": [r["steps_per_contact"] for r in ok]}
                for kind in ("restitution", "duration", "max_overlap"):
                    row[kind] = [_sig(r.get(f"{kind}_err")) if r.get("ok") else None
                                 for r in ok]
                row["worst_restitution"] = [_sig(r.get("worst_restitution_err"))
                                            if r.get("ok") else None for r in ok]
                out[integ][model][e] = row
    return out


def _sig(x: float | None, digits: int = 4) -> float | None:
    """``x`` to ``digits`` significant digits (the tables' own noise is larger)."""
    if x is None or not math.isfinite(x) or x == 0:
        return x
    return float(f"{x:.{digits - 1}e}")


def _elastic(src: dict) -> dict:
    out: dict = {}
    for law in ("hertz", "linear"):
        out[law] = {}
        for integ, t in src["collision"].get(law, {}).items():
            rows = [r for r in t["rows"] if r.get("ok", True)]
            out[law][integ] = {"n": [r["cr"] for r in rows],
                               "v_err": [_sig(r["v_err"]) for r in rows]}
    return out


def _step_factors(src: dict) -> tuple[dict, dict]:
    per: dict[str, list[float]] = {}
    for law in ("hertz", "linear"):
        for integ, t in src["collision"].get(law, {}).items():
            for r in t["rows"]:
                if r["cr"] >= 20 and r.get("ok", True):
                    per.setdefault(integ, []).append(r["cpu"] / r["steps"])
    vv = statistics.median(per["velocity_verlet"])
    raw = {k: statistics.median(v) / vv for k, v in per.items()}
    implicit = {"backward_euler", "newmark_beta", "numerov"}
    used = {k: (v if k in implicit or not (1 / NOISE <= v <= NOISE) else 1.0)
            for k, v in raw.items()}
    return used, raw


def _shapes(src: dict) -> tuple[dict, float]:
    out: dict = {}
    counts, costs = [], []
    for r in src["rows"]:
        s = out.setdefault(r["shape"], {"params": r["params"], "resolution": [], "count": [],
                                        "dev_rms_rel": [], "dev_max_rel": [],
                                        "volume_ratio": [], "r_min_over_r_eq": []})
        s["resolution"].append(r["resolution"])
        s["count"].append(r["count"])
        s["dev_rms_rel"].append(r["dev_rms_rel"])
        s["dev_max_rel"].append(r["dev_max_rel"])
        s["volume_ratio"].append(r["volume_ratio"])
        s["r_min_over_r_eq"].append(r["r_min"] / r["r_eq"])
        if isinstance(r.get("seconds_per_body_step"), float):
            counts.append(r["count"])
            costs.append(r["seconds_per_body_step"] * 1e9)
    # per-element cost [ns] of a small bed of clusters: cost per body-step = body + count
    # x element (least squares through the body cost)
    c = np.asarray(counts, float)
    y = np.asarray(costs, float) - BODY_NS
    element = float(np.sum(c * y) / np.sum(c * c)) if len(c) else 18.0
    return out, element


def _sensitivity(src: dict) -> dict:
    out = {}
    for q, s in src.get("calibration", {}).items():
        out[q] = {k: s[k] for k in ("points", "contact", "scatter", "scatter_dof",
                                    "scatter_method", "replicas", "reference_replicas",
                                    "window", "bodies", "scene") if k in s}
        if "uncertainty" in str(s.get("points")):
            out[q]["reference_steps"] = src.get("n_ref", 80.0)
    return out


def condense(results: Path, out: Path | None = None) -> dict[str, Any]:
    """Read the benchmark results in ``results`` and write the advisor's tables to ``out``
    (default: the package's ``dpm/data/work_precision.json``); return them."""
    results = Path(results)

    def read(name: str) -> dict:
        return json.loads((results / name).read_text())

    contact_src = read("advise_contact_errors.json")
    impact = read("impact_models.json")
    integ = read("integrators.json")
    shapes_src = read("shapes_speed_vs_error.json")
    box = read("box_settle.json")
    hopper = read("hopper_discharge.json")
    factors, raw = _step_factors(integ)
    shapes, element_ns = _shapes(shapes_src)
    engine = {m["label"]: m["engine_ns_per_contact_step"] for m in impact["models"]
              if "(" not in m["label"]}
    skin = contact_src.get("skin_cost", {})
    data: dict[str, Any] = {
        "format": 1,
        "regenerate": "python benchmarks/advise_tables.py && python -m dpm.advice.condense",
        "sources": {
            "contact": "benchmarks/results/advise_contact_errors.json "
                       "(benchmarks/advise_tables.py)",
            "elastic": "benchmarks/results/integrators.json (collision study)",
            "cost": "benchmarks/results/impact_models.json, integrators.json, box_settle.json, "
                    "hopper_discharge.json, shapes_speed_vs_error.json; per-body and "
                    "rebuild costs measured on box_settle (BODY_NS, REBUILD_NS)",
            "shapes": "benchmarks/results/shapes_speed_vs_error.json",
            "sensitivity": "benchmarks/results/advise.json (benchmarks/advise.py)",
        },
        "contact_scene": contact_src["scene"],
        "equivalent": contact_src.get("equivalent", {}),
        "contact": _contact(contact_src),
        "elastic": _elastic(integ),
        "cost": {
            "engine_ns_per_contact_step": engine,
            "integrator_step_factor": factors,
            "integrator_step_factor_measured": raw,
            "body_ns": BODY_NS,
            "element_ns": element_ns,
            "rebuild_ns_per_element": skin.get("rebuild_ns_per_element", REBUILD_NS),
            "listed_pair_ns": skin.get("listed_pair_ns", 4.0),
            "skin_cost_measured": bool(skin),
            #: speed that sets the rebuild rate, over the time-step check's impact speed:
            #: box_settle 0.2, rotating_drum 0.34, the silo while settling 0.3 (rebuilds
            #: counted in their first 0.02-0.1 s at the examples' steps)
            "rebuild_speed_factor": 0.3,
            #: touching pairs per sphere, settled box_settle (24,000 of 41,000 listed pairs
            #: for 10,000 spheres): coordination 4.8
            "coordination": 4.8,
            "calibration": {
                "box_settle_ns_per_particle_step": 1e9 / box["dpm"]["particle_steps_per_s"],
                "box_settle_particles": box["dpm"]["particles"],
                "silo_ns_per_particle_step": 1e9 / hopper["dpm"]["particle_steps_per_s"],
                "silo_particles": hopper["dpm"]["bodies"],
            },
        },
        "shapes": shapes,
        "sensitivity": {},
    }
    if (results / "advise.json").exists():
        data["sensitivity"] = _sensitivity(read("advise.json"))
    out = Path(out) if out is not None else DATA
    out.parent.mkdir(parents=True, exist_ok=True)
    data = _finite(data)
    out.write_text(json.dumps(data, indent=None, separators=(",", ":"), allow_nan=False)
                   .replace('},"', '},\n"') + "\n")
    return data


def _finite(x: Any) -> Any:
    """NaN and infinities as null (JSON has neither)."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_finite(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    here = Path(__file__).resolve().parents[2] / "benchmarks" / "results"
    results = Path(args[0]) if args else here
    out = Path(args[1]) if len(args) > 1 else None
    condense(results, out)
    print(f"wrote {out or DATA}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
