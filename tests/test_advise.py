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

ROOT = Path(__file__).resolve().parent.parent
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
