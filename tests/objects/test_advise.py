"""dpm.advise: the search against its tables, its warnings and refusals, the command, and a
pilot verification (docs/advise.md)."""

from __future__ import annotations

import copy
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dpm
from dpm.advice import Setting, advise
from dpm.advice.tables import DATA, Tables, _envelope, _interp_loglog, load_tables
from dpm.cli import main
from dpm.errors import ParameterError

ROOT = Path(__file__).resolve().parents[2]
BOX_TOML = ROOT / "examples" / "box_settle.toml"


def small_box(n: int = 3, restitution: float = 0.3, radius: float = 1e-3,
              shape: str = "sphere", **shape_kw) -> dpm.Simulation:
    """n^3 glass spheres (or clusters) above the floor of an open box (box_settle's
    materials)."""
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=restitution, friction=0.5)
    side = 2.2 * radius * n * (2.0 if shape != "sphere" else 1.0)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(side, side, 3 * side),
                     open=("+z",))
    pitch = side / n
    xyz = dpm.lattice((0.0, 0.0, 0.0), (side, side, side), pitch)
    assert len(xyz) == n**3
    if shape == "sphere":
        sim.add_particles("sphere", material=glass, radius=radius, positions=xyz)
    else:
        sim.add_particles(shape, material=glass, positions=xyz, **shape_kw)
    return sim


@pytest.fixture(scope="module")
def box() -> dpm.Simulation:
    return small_box()


# ------------------------------------------------------------------------- the tables


def test_shipped_tables_are_there_and_complete():
    t = load_tables()
    assert DATA.exists()
    for integ in ("velocity_verlet", "gear4", "symplectic_euler"):
        assert integ in t.integrators()
    for model in ("hertz_mindlin", "hooke", "walton_braun"):
        assert t.table_model(model) == model
    assert t.table_model("maw_linear_spring") == "hooke"
    assert t.restitutions("velocity_verlet", "hertz_mindlin")[0] <= 0.3
    for key in ("engine_ns_per_contact_step", "integrator_step_factor", "body_ns"):
        assert key in t.cost
    for q in ("settled_height", "angle_of_repose", "discharge_rate"):
        s = t.sensitivity(q)
        assert s is not None and len(s["points"]) >= 2, q
        assert all(p["steps_per_contact"] >= 5 for p in s["points"]), q
        assert 0 <= s["scatter"] < 1 and s["contact"]["model"] == "hertz_mindlin", q
        # the systematic error of replica means and its uncertainty (benchmarks/advise.py)
        assert all("uncertainty" in p and "systematic_error" in p for p in s["points"]), q
        assert s["scatter_dof"] >= 1 and s["reference_replicas"] >= 1, q


def test_envelope_never_grows_with_finer_steps():
    xs, env = _envelope([5, 10, 20, 50], [-0.03, 0.001, 0.008, -0.004])
    assert env == [0.03, 0.008, 0.008, 0.004]
    assert _interp_loglog(xs, env, 4.0) == math.inf           # below the table
    assert _interp_loglog(xs, env, 100.0) == pytest.approx(0.002)  # first order beyond
    t = load_tables()
    vals = [t.contact_error("velocity_verlet", "hertz_mindlin", 0.5, n).value
            for n in (5, 7, 10, 15, 30, 60, 120, 400)]
    assert all(a >= b for a, b in zip(vals, vals[1:], strict=False)), vals


def synthetic(tmp_path: Path, c: float = 0.1, p: float = 2.0) -> str:
    """The shipped tables with every contact error replaced by a known law: restitution
    error c (10/n)^p, no duration or overlap error, no calibration of settled_height (it
    errs as its contacts' restitution)."""
    data = json.loads(DATA.read_text())
    ns = [2, 5, 10, 20, 50, 100, 200]
    for integ in data["contact"].values():
        for model in integ.values():
            for e in model:
                model[e] = {"n": ns, "restitution": [c * (10 / n) ** p for n in ns],
                            "duration": [0.0] * len(ns), "max_overlap": [0.0] * len(ns)}
    data["sensitivity"].pop("settled_height", None)
    path = tmp_path / "synthetic.json"
    path.write_text(json.dumps(data))
    return str(path)


def test_step_follows_a_known_error_law(box, tmp_path):
    """With E_e(n) = 0.1 (10/n)^2 (and the quantity erring as that), a tolerance of 0.1 %
    needs n = 100 steps per contact: dt = T/100 (the search's only freedom here)."""
    tables = synthetic(tmp_path)
    a = advise(box, tolerance=0.001, quantity="settled_height", tables=tables,
               integrators=["velocity_verlet"], models=["as set"])
    assert a.feasible
    assert a.choice.steps_per_contact == pytest.approx(100.0, rel=1e-3)
    tc = min(a.facts.contact_time(p) for p in a.facts.pairs)
    assert a.choice.setting.dt == pytest.approx(tc / 100.0, rel=1e-3)
    assert a.choice.error == pytest.approx(0.001, rel=1e-3)
    # 50 %: n >= 4.5 would do; the engine's least steps per contact (5) binds first
    a = advise(box, tolerance=0.5, quantity="settled_height", tables=tables,
               integrators=["velocity_verlet"], models=["as set"], max_rayleigh=1.0)
    assert a.choice.steps_per_contact == pytest.approx(5.05, rel=1e-6)  # 1 % inside
    assert "steps per contact" in a.choice.limited_by


# ------------------------------------------------------------------------- the search


@pytest.mark.parametrize("q", ["settled_height", "angle_of_repose", "discharge_rate"])
def test_tighter_tolerance_never_predicts_a_cheaper_choice(box, q):
    sim = box
    if q == "angle_of_repose":
        sim = drum_scene()
    elif q == "discharge_rate":
        sim = small_box()
        sim.add_outlet(dpm.BoxRegion((-1, -1, -2), (1, 1, -0.01)))
    costs, errors = [], []
    for tol in (0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 0.9):
        a = advise(sim, tolerance=tol, quantity=q)
        assert not a.feasible or a.choice.error <= tol * (1 + 1e-9)
        costs.append(a.choice.rank_cost)  # the cost the search minimises
        errors.append(a.choice.error)
        assert str(a).startswith(f"dpm advise: {q} within")
    assert all(x >= y * (1 - 1e-9) for x, y in zip(costs, costs[1:], strict=False)), costs
    assert costs[0] > costs[-1]  # the tolerance buys something


def drum_scene() -> dpm.Simulation:
    sim = dpm.Simulation(dt=1.5e-5, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500.0, young=5e7, poisson=0.3)
    steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    sim.contact(glass, glass, restitution=0.5, friction=0.4)
    sim.contact(glass, steel, restitution=0.5, friction=0.6)
    sim.add_boundary("tube", material=steel, start=(0, 0, 0), axis=(0, 1, 0), length=0.02,
                     radius=0.03, caps="both", motion=dpm.Rotation(axis=(0, 1, 0), rpm=20))
    pos = dpm.lattice((-0.02, 0.004, -0.025), (0.02, 0.016, -0.01), 4.4e-3)
    sim.add_particles("sphere", material=glass, radius=2e-3, positions=pos)
    return sim


def test_choice_is_cheaper_than_a_fine_default_and_reports_its_parts(box):
    a = advise(box, tolerance=0.05, quantity="settled_height", run_time=0.1)
    c = a.choice
    assert set(c.parts) == {"time_step", "impact_model", "shape"}
    assert c.error == pytest.approx(sum(c.parts.values()))
    assert c.cost > 0 and a.default.cost > 0
    assert a.default.setting.dt == box.dt
    # box_settle's own step resolves a contact with ~23 steps: at 5 % the advice is cheaper
    assert a.speedup > 1.0
    text = str(a)
    for word in ("choice:", "default:", "predicted error", "s per simulated second",
                 "assumptions:", "steps per contact against 80"):
        assert word in text
    assert "hertz_mindlin" in text or "as set" in text


def test_apply_sets_the_choice(box):
    a = advise(box, tolerance=0.05, quantity="settled_height")
    sim = copy.deepcopy(box)
    a.apply(sim)
    assert sim.dt == a.choice.setting.dt and sim.skin == a.choice.setting.skin
    s = Setting("hooke", "gear4", 2e-5, 3e-4)
    from dpm.advice import apply_setting

    apply_setting(sim, s)
    assert sim.integrator.name == "gear4"
    assert {law.name for law in sim._contacts.values()} == {"hooke"}


# ------------------------------------------------------------------------- warnings


def test_out_of_range_warnings(box):
    a = advise(small_box(restitution=0.05), tolerance=0.05, quantity="settled_height")
    assert any("outside the measured" in w for w in a.warnings), a.warnings
    assert any("bodies: the cost model is calibrated" in w for w in a.warnings)
    a = advise(box, tolerance=1e-9, quantity="settled_height")
    assert not a.feasible
    assert any("no set-up reaches" in w for w in a.warnings)
    a = advise(box, tolerance=0.01, quantity="settled_height", impact_speed=50.0)
    # at 50 m/s the tunnelling guard, not the contacts, limits the step
    assert "tunnelling" in a.choice.limited_by or a.choice.steps_per_contact >= 5


def test_clusters_get_a_resolution_and_their_warnings():
    sim = small_box(n=2, shape="ellipsoid", a=2e-3, b=1e-3, resolution=0.3)
    a = advise(sim, tolerance=0.2, quantity="settled_height")
    assert a.choice.setting.resolution is not None
    assert a.choice.parts["shape"] > 0
    assert any("not in the shape table" in w for w in a.warnings)
    assert any("clustered shapes" in w for w in a.warnings)
    tight = advise(sim, tolerance=0.05, quantity="settled_height")
    assert tight.choice.parts["shape"] <= a.choice.parts["shape"]
    assert tight.choice.cost >= a.choice.cost


# ------------------------------------------------------------------------- refusals


@pytest.mark.parametrize("kw, name", [
    ({"quantity": "packing_fraction"}, "quantity"),
    ({"tolerance": 0.0}, "tolerance"), ({"tolerance": 1.0}, "tolerance"),
    ({"tolerance": -0.01}, "tolerance"), ({"tolerance": float("nan")}, "tolerance"),
    ({"tolerance": "0.01"}, "tolerance"), ({"tolerance": True}, "tolerance"),
    ({"run_time": -1.0}, "run_time"), ({"window": (0.5, 0.1)}, "window"),
    ({"impact_speed": 0.0}, "impact_speed"), ({"max_rayleigh": 2.0}, "max_rayleigh"),
    ({"verify": True}, "run_time"),
    ({"quantity": "angle_of_repose"}, "drum"), ({"quantity": "discharge_rate"}, "outlet"),
])
def test_bad_input_is_refused_by_name(box, kw, name):
    args = {"tolerance": 0.01, "quantity": "settled_height", **kw}
    with pytest.raises(ParameterError) as err:
        advise(box, **args)
    msg = str(err.value)
    assert name in msg
    if name in ("quantity", "tolerance"):
        assert "allowed" in msg and repr(args[name]) in msg


def test_no_gravity_no_settled_height():
    sim = small_box()
    sim.gravity = (0, 0, 0)
    with pytest.raises(ParameterError, match="gravity"):
        advise(sim, tolerance=0.01, quantity="settled_height")


def test_lazy_export():
    code = ("import sys, dpm; assert 'dpm.advice' not in sys.modules; "
            "from dpm.advice import advise; assert dpm.advise is advise; "
            "assert 'advise' in dpm.__all__")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


# ------------------------------------------------------------------------- the command


def test_cli_on_box_settle_toml(capsys):
    assert main(["advise", str(BOX_TOML), "--tolerance", "0.05", "--quantity",
                 "settled_height"]) == 0
    out = capsys.readouterr().out
    assert "dpm advise: settled_height within 5 %" in out
    assert "for 0.1 s" in out  # the scene's [run] until
    assert "replicas: " in out and "independent runs with perturbed starts" in out
    assert main(["advise", str(BOX_TOML), "--tolerance", "0.01", "--quantity", "height"]) == 0
    assert main(["advise", str(BOX_TOML), "--quantity", "porosity"]) == 2
    err = capsys.readouterr().err
    assert "quantity='porosity'" in err and "settled_height" in err
    assert main(["advise", str(BOX_TOML), "--tolerance", "1.5"]) == 2
    assert "tolerance=1.5" in capsys.readouterr().err


def test_cli_writes_json(tmp_path):
    out = tmp_path / "advice.json"
    assert main(["advise", str(BOX_TOML), "--tolerance", "0.02", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["quantity"] == "settled_height" and d["tolerance"] == 0.02
    assert d["choice"]["error"] <= 0.02
    assert isinstance(d["replicas"], int) and d["replicas"] >= 1
    assert d["choice"]["replicas"] == d["replicas"]
    assert d["choice"]["total_error"] <= 0.02 * (1 + 1e-9)


# ------------------------------------------------------------------------- verification


def test_pilot_verification_of_a_small_bed():
    """Two pilot runs (27 spheres falling onto the floor, 0.03 s each, at dt and dt/2): the
    Richardson estimate is finite, the values are a bed's height, the costs measured."""
    sim = small_box()
    a = advise(sim, tolerance=0.05, quantity="settled_height", verify=True, run_time=0.03)
    v = a.verification
    assert v is not None
    assert v.dt[1] == pytest.approx(0.5 * v.dt[0])
    assert v.dt[0] == a.choice.setting.dt
    for q in v.values:
        assert 1e-3 < q < 6e-3  # above the floor, within the three layers' height
    assert np.isfinite(v.estimate) and v.estimate >= 0
    assert 1.0 <= v.order <= 3.0
    assert all(c > 0 for c in v.cost)
    assert "verification:" in str(a) and "Richardson" in str(a)
    assert sim.step_count == 0  # the pilots ran on copies


def test_condense_reproduces_the_shipped_contact_tables(tmp_path):
    from dpm.advice.condense import condense

    results = ROOT / "benchmarks" / "results"
    if not (results / "advise_contact_errors.json").exists():
        pytest.skip("benchmarks/results not in this checkout")
    data = condense(results, tmp_path / "wp.json")
    shipped = json.loads(DATA.read_text())
    assert data["contact"] == shipped["contact"]
    assert Tables(data).integrators() == load_tables().integrators()


# ------------------------------------------------------------------------- replicas


def test_replica_count_formula():
    from dpm.advice.model import replicas_for

    # N = ceil((z sigma / (tol - eps_sys))^2), z = 2
    assert replicas_for(0.05, 0.01, 0.04) == 4            # (0.08 / 0.04)^2 = 4 exactly
    assert replicas_for(0.05, 0.01, 0.041) == 5
    assert replicas_for(0.01, 0.002, 0.01) == math.ceil((0.02 / 0.008) ** 2)  # 7
    # it grows as the square of sigma and of 1 / (tol - eps_sys)
    assert replicas_for(0.05, 0.0, 0.02) == 1
    assert replicas_for(0.05, 0.0, 0.1) == 16
    assert replicas_for(0.05, 0.025, 0.1) == 64
    assert replicas_for(0.01, 0.0, 0.005, z=3.0) == 3       # (0.015 / 0.01)^2 = 2.25
    # negligible scatter: one run; the systematic error alone at or above tol: no N helps
    assert replicas_for(0.01, 0.009, 0.0) == 1
    assert replicas_for(0.01, 0.009, 1e-9) == 1
    assert replicas_for(0.01, 0.01, 0.001) is None
    assert replicas_for(0.01, 0.02, 0.0) is None


def calibrated(tmp_path: Path, points: list[tuple[float, float, float]], scatter: float,
               quantity: str = "settled_height", **extra) -> str:
    """The shipped tables with ``quantity`` calibrated by (steps per contact, systematic
    error, its uncertainty) points and the scatter of one run (the format of
    benchmarks/advise.py with replicas)."""
    data = json.loads(DATA.read_text())
    sens = data["sensitivity"][quantity]
    sens.update({"points": [{"steps_per_contact": n, "measured_error": e,
                             "systematic_error": e, "uncertainty": u, "replicas": 4}
                            for n, e, u in points],
                 "scatter": scatter, "scatter_dof": 12, "reference_replicas": 4,
                 "window": None, **extra})
    path = tmp_path / f"calibrated_{quantity}.json"
    path.write_text(json.dumps(data))
    return str(path)


def test_systematic_error_does_not_absorb_the_scatter_of_one_run(box, tmp_path):
    """sigma large (4 %), the step's systematic error small (0.2 % +- 0.1 %): 5 % needs the
    coarsest step with a few replicas, not a fine step with one run (which is what adding
    sqrt(2) sigma to every calibration point prescribed)."""
    pts = [(6.0, 0.002, 0.001), (9.0, 0.001, 0.001), (12.0, 0.001, 0.001),
           (18.0, 0.0005, 0.001)]
    tables = calibrated(tmp_path, pts, scatter=0.04)
    a = advise(box, tolerance=0.05, quantity="settled_height", tables=tables,
               integrators=["velocity_verlet"], models=["as set"])
    c = a.choice
    assert a.feasible and a.replicas == c.replicas > 1
    assert c.steps_per_contact < 10                 # coarse: at the engine's or Rayleigh cap
    assert c.error < 0.01                           # the step error, not the scatter
    assert c.sigma == pytest.approx(0.04)
    assert c.statistical_error == pytest.approx(2 * 0.04 / math.sqrt(c.replicas))
    assert c.total_error <= 0.05 * (1 + 1e-9)
    from dpm.advice.model import replicas_for
    assert c.replicas == replicas_for(0.05, c.error, 0.04)
    # Q_cal is the systematic error plus its uncertainty at each step, never sigma
    from dpm.advice.model import Model
    from dpm.advice.scene import scene_facts

    t = load_tables(tables)
    m = Model(scene_facts(box), t, t.sensitivity("settled_height"))
    assert m.cal_err == pytest.approx([0.003, 0.002, 0.002, 0.0015])
    # the search traded the step against replicas: a finer step with one run costs more
    one = [p for p in a.candidates if p.replicas == 1]
    assert all(p.total_cost >= c.total_cost for p in one)
    text = str(a)
    assert f"replicas: {c.replicas}" in text and "statistical" in text


def test_older_tables_load_with_their_single_run_errors(box, tmp_path):
    """A table without uncertainties (single runs, before replicas): Q_cal = the measured
    difference plus sqrt(2) sigma, as it was advised then."""
    data = json.loads(DATA.read_text())
    data["sensitivity"]["settled_height"] = {
        "points": [{"steps_per_contact": 6.0, "measured_error": 0.03},
                   {"steps_per_contact": 12.0, "measured_error": 0.001}],
        "contact": {"integrator": "velocity_verlet", "model": "hertz_mindlin",
                    "restitution": 0.3, "pair": "glass-glass"},
        "scatter": 0.001, "bodies": 1000, "scene": "box_settle (old)"}
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    from dpm.advice.model import Model
    from dpm.advice.scene import scene_facts

    t = load_tables(path)
    m = Model(scene_facts(box), t, t.sensitivity("settled_height"))
    s2 = math.sqrt(2) * 0.001
    assert m.cal_err == pytest.approx([0.03 + s2, 0.001 + s2])
    a = advise(box, tolerance=0.01, quantity="settled_height", tables=str(path))
    assert a.feasible and a.replicas >= 1
    assert "an older table" in str(a)


def test_new_table_fields_load(tmp_path):
    tables = calibrated(tmp_path, [(6.0, 0.01, 0.002), (12.0, 0.001, 0.002)], 0.01,
                        window=0.5, scatter_method="pooled")
    s = load_tables(tables).sensitivity("settled_height")
    assert s["scatter_dof"] == 12 and s["reference_replicas"] == 4 and s["window"] == 0.5
    assert s["points"][0]["uncertainty"] == 0.002 and s["points"][0]["replicas"] == 4
    # condense carries the new fields from benchmarks/results/advise.json
    from dpm.advice.condense import _sensitivity

    src = {"calibration": {"angle_of_repose": {
        "points": [], "scatter": 0.005, "scatter_dof": 10, "replicas": 3,
        "reference_replicas": 3, "window": 0.5, "runs": {"x1": []}, "scatter_method": "m",
        "contact": {}, "bodies": 843, "scene": "drum"}}}
    out = _sensitivity(src)["angle_of_repose"]
    assert out["scatter_dof"] == 10 and out["window"] == 0.5 and "runs" not in out


def test_default_cost_is_at_the_same_tolerance(box, tmp_path):
    """The default's cost for comparison: its own step with the replicas it needs for the
    same tolerance."""
    from dpm.advice.model import replicas_for

    pts = [(6.0, 0.002, 0.001), (12.0, 0.001, 0.001), (18.0, 0.0005, 0.001)]
    tables = calibrated(tmp_path, pts, scatter=0.02)
    for tol in (0.01, 0.02):
        a = advise(box, tolerance=tol, quantity="settled_height", tables=tables)
        d = a.default
        assert a.default_feasible
        assert d.replicas == replicas_for(tol, d.error, 0.02) > 1
        assert d.total_cost == pytest.approx(d.cost * d.replicas)
        assert a.speedup == pytest.approx(d.total_cost / a.choice.total_cost)
        assert f"needs {d.replicas} replicas for the same tolerance" in str(a)


def test_out_of_reach_by_replicas_says_so(tmp_path):
    """sigma 20 % of one run over a 0.5 s window, 1 %: more than 64 replicas; the advice
    says the tolerance is out of reach at this window and how much longer a window would
    do (sigma ~ 1/sqrt(window))."""
    from dpm.advice.model import MAX_REPLICAS, replicas_for

    pts = [(6.0, 0.001, 0.001), (12.0, 0.0005, 0.001)]
    tables = calibrated(tmp_path, pts, scatter=0.2, quantity="angle_of_repose", window=0.5)
    sim = drum_scene()
    a = advise(sim, tolerance=0.01, quantity="angle_of_repose", run_time=1.0, tables=tables)
    assert not a.feasible
    assert a.replicas == MAX_REPLICAS
    assert a.replicas_needed == replicas_for(0.01, a.choice.error, 0.2) > MAX_REPLICAS
    assert a.window_factor == pytest.approx(a.replicas_needed / MAX_REPLICAS)
    assert any("out of reach by replicas at this window" in w and "times as long" in w
               and "1/sqrt(window)" in w for w in a.warnings), a.warnings
    assert f"NOT REACHED with up to {MAX_REPLICAS} replicas" in str(a)
    # the scatter scales with the window: twice the calibration's window, sigma / sqrt(2)
    b = advise(sim, tolerance=0.01, quantity="angle_of_repose", window=(0.0, 1.0),
               tables=tables)
    assert b.scatter == pytest.approx(0.2 / math.sqrt(2))
    assert "1/sqrt(window)" in " ".join(b.assumptions)
    # a final state (no window): nothing to lengthen
    tables = calibrated(tmp_path, pts, scatter=0.2)
    c = advise(small_box(), tolerance=0.01, quantity="settled_height", tables=tables)
    assert not c.feasible and c.window_factor is None
    assert any("no window to lengthen" in w for w in c.warnings)


def test_negligible_scatter_gives_one_run(box, tmp_path):
    tables = calibrated(tmp_path, [(6.0, 0.03, 0.0), (12.0, 0.001, 0.0)], scatter=0.0)
    a = advise(box, tolerance=0.01, quantity="settled_height", tables=tables)
    assert a.replicas == 1 and a.choice.statistical_error == 0.0
    assert a.default.replicas == 1


def test_step_error_is_held_at_the_reference_step(box, tmp_path):
    """First order beyond the finest calibrated step, but no claim finer than the
    calibration's reference (80 steps per contact): held there."""
    from dpm.advice.model import Model
    from dpm.advice.scene import scene_facts

    tables = calibrated(tmp_path, [(6.0, 0.01, 0.002), (20.0, 0.004, 0.002)], 0.01,
                        reference_steps=80.0)
    t = load_tables(tables)
    m = Model(scene_facts(box), t, t.sensitivity("settled_height"))
    at = {n: m.quantity_error("hertz_mindlin", 0.3, n)[0] for n in (20.0, 40.0, 80.0, 400.0)}
    assert at[20.0] == pytest.approx(0.006)
    assert at[40.0] == pytest.approx(0.003)       # first order
    assert at[80.0] == pytest.approx(0.0015)
    assert at[400.0] == pytest.approx(0.0015)     # held at the reference's step
