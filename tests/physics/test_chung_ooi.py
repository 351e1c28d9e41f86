"""The validation suite (``dpm validate``): Chung & Ooi (2011) impact benchmarks and analytic
cases, each row against a closed form (``dpm/validation``, ``docs/validation.md``).

The default run takes a quick subset that shares one compiled step (all validation scenes
bind the same laws); the whole suite, at full resolution, is in the slow set.
"""

from __future__ import annotations

import json
import math

import pytest
from scipy.integrate import solve_ivp

from dpm import ParameterError, validation
from dpm.cli import main
from dpm.validation import chung_ooi
from dpm.validation.references import (
    effective_young,
    hertz_impact,
    rigid_sliding,
    sphere_mass,
)

QUICK_CASES = ["co1", "co3", "co4", "co7"]
QUICK_MODELS = ["hertz_mindlin", "linear_spring_dashpot"]


# ------------------------------------------------------------------ the references


def test_hertz_reference_matches_the_ode():
    """The closed forms (largest overlap, force, duration) against m* d'' = -k d^(3/2)
    integrated from d = 0, d' = v (glass spheres of Test 1)."""
    _, rho, young, nu = chung_ooi.GLASS
    r, v = 0.01, 20.0
    meff, reff = sphere_mass(r, rho) / 2, r / 2
    estar = effective_young(young, nu, young, nu)
    ref = hertz_impact(meff, reff, estar, v)
    k = 4.0 / 3.0 * estar * math.sqrt(reff)

    def rhs(_, y):
        return [y[1], -k * max(y[0], 0.0) ** 1.5 / meff]

    def end(_, y):
        return y[0]
    end.terminal, end.direction = True, -1
    sol = solve_ivp(rhs, (0, 10 * ref.duration), [1e-30, v], events=end, rtol=1e-12,
                    atol=1e-18, max_step=ref.duration / 1000, dense_output=True)
    assert sol.t_events[0][0] == pytest.approx(ref.duration, rel=1e-6)
    assert sol.y[0].max() == pytest.approx(ref.max_overlap, rel=1e-6)
    assert k * sol.y[0].max() ** 1.5 == pytest.approx(ref.max_force, rel=1e-6)
    assert sol.y[1][-1] == pytest.approx(-v, rel=1e-6)


def test_rigid_sliding_reference():
    """A sphere on a plane: the tangential impulse mu (1+e) m v_n changes the surface speed
    by 5/2 of the tangential velocity change; sliding lasts if v_t >= 7/2 mu (1+e) v_n."""
    m, r = 2.0, 0.1
    i = 0.4 * m * r * r
    s = rigid_sliding(1.0, 3.0, 0.5, 0.4, m, r, i)
    assert s.normal_impulse == pytest.approx(1.5 * m)
    assert s.dv1 == pytest.approx(-0.4 * 1.5)
    assert s.dsurf1 == pytest.approx(2.5 * s.dv1)
    assert s.margin == pytest.approx(3.0 / (3.5 * 0.4 * 1.5))
    # two equal spheres: each gets half the wall's normal impulse per unit approach speed
    p = rigid_sliding(1.0, -3.0, 0.5, 0.4, m, r, i, m, r, i)
    assert p.normal_impulse == pytest.approx(1.5 * m / 2)
    assert p.dv1 == pytest.approx(0.4 * 1.5 / 2) and p.dv2 == pytest.approx(-p.dv1)
    assert p.margin == pytest.approx(3.0 / (7.0 * 0.4 * 1.5 / 2))


# ------------------------------------------------------------------ the engine


@pytest.fixture(scope="module")
def quick_rows():
    return validation.run(QUICK_CASES, quick=True, models=QUICK_MODELS)


def test_quick_subset_is_within_tolerance(quick_rows):
    failed = [r for r in quick_rows if not r.passed]
    assert not failed, validation.table(failed)
    tests = {r.test.split()[0] for r in quick_rows}
    assert tests == {"CO1", "CO3", "CO4", "CO7"}
    assert {r.model for r in quick_rows} == set(QUICK_MODELS)
    quantities = {(r.test, r.model, r.quantity.split(" (worst")[0]) for r in quick_rows}
    for q in ("largest overlap [m]", "largest force [N]", "contact duration [s]"):
        assert ("CO1 glass", "hertz_mindlin", q) in quantities
    assert ("CO4 alumina", "hertz_mindlin", "change of R w / (mu (1+e) v_n), sliding") \
        in quantities
    assert ("CO7 copper", "linear_spring_dashpot", "angular momentum, all impacts") \
        in quantities


def test_a_wrong_friction_is_caught(monkeypatch):
    """The laws get 0.8 mu while the references use mu: the sliding rows fail."""
    real = chung_ooi.params

    def wrong(model, e, mu, *args):
        return real(model, e, 0.8 * mu, *args)

    monkeypatch.setattr(chung_ooi, "params", wrong)
    rows = chung_ooi.co4(True, ["hertz_mindlin"])
    sliding = [r for r in rows if "sliding" in r.quantity]
    assert sliding and not any(r.passed for r in sliding)
    assert all(r.passed for r in rows if r.quantity.startswith("restitution"))


def test_cli_writes_tables_and_exit_status(tmp_path, capsys, monkeypatch):
    md, js = tmp_path / "v.md", tmp_path / "v.json"
    rc = main(["validate", "--quick", "--case", "co3", "--model", "hooke",
               "--markdown", str(md), "--json", str(js)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "CO3 alumina" in out and "2 of 2 rows within tolerance" in out
    assert md.read_text().startswith("| test | model | quantity |")
    rows = json.loads(js.read_text())
    assert len(rows) == 2 and all(r["passed"] for r in rows)
    # a row outside its tolerance: exit status 1
    monkeypatch.setattr(chung_ooi, "TOL_E", 1e-12)
    assert main(["validate", "--quick", "--case", "co3", "--model", "hooke"]) == 1
    assert "FAILED" in capsys.readouterr().out


def test_unknown_case_or_model_refused(capsys):
    with pytest.raises(ParameterError, match=r"model='hertz' is not validated here; "
                                             r"allowed: .*hertz_mindlin"):
        validation.run(models=["hertz"])
    with pytest.raises(ParameterError, match=r"case='co9' is unknown; allowed: co1"):
        validation.run(["co9"])
    assert main(["validate", "--case", "co9"]) == 2
    assert "case='co9'" in capsys.readouterr().err
    with pytest.raises(ParameterError, match=r"no case of \['flip'\] applies to "
                                             r"models=\['hertz_mindlin'\]"):
        validation.run(["flip"], models=["hertz_mindlin"])


def test_tangential_dashpot_takes_energy_from_the_slip():
    """A linear spring-dashpot (e = 0.98) at 10 degrees in CO4: at first touch the normal
    force is the dashpot's c v_n and the tangential dashpot's c_t v_t exceeds mu c v_n, so
    the contact slides from the first step, then sticks and reverses the slip. Without
    the tangential dashpot the slip reverses at abs(e_t) = 0.99, the undamped
    oscillator's; the dashpot must take energy from it (e_t = -0.92). The former sliding
    reset s = -F_t/k_t loaded the spring with the dashpot's share of the Coulomb force and
    sent the slip back faster than it came (e_t = -1.31, docs/validation.md, Findings)."""
    from dpm.validation.impacts import Impact, run_group

    r, v, a = 0.0025, 3.9, math.radians(10.0)
    imp = Impact("wall", r, v * math.cos(a), vt1=v * math.sin(a))
    ratios = []
    for zeta_t in (None, 0.0):
        sp = chung_ooi.species(chung_ooi.ALUMINA, "hooke", 0.98, 0.092, v, r, False)
        if zeta_t is not None:
            sp.params["tangential_damping_ratio"] = zeta_t
        o = run_group([sp], [imp])[0]
        ratios.append((o.vt1 + o.surf1) / imp.vt1)
    assert ratios[0] == pytest.approx(-0.92, abs=0.02)
    assert ratios[1] == pytest.approx(-1.0, abs=0.02)
    assert abs(ratios[0]) < abs(ratios[1]) - 0.03


@pytest.mark.slow
def test_whole_suite_is_within_tolerance():
    """Every case, every model that applies, at full resolution (what docs/validation.md
    shows): every row within its tolerance, none a known failure."""
    rows = validation.run()
    failed = [r for r in rows if not r.passed]
    assert not failed, validation.table(failed)
    assert {r.test.split()[0] for r in rows} >= {f"CO{k}" for k in range(1, 9)}
    assert {"sandwich", "rolling"} <= {r.test.split()[0] for r in rows}


def test_no_slip_reference_limits():
    """Without a tangential spring (G* -> 0) the slip is unchanged; the contact point at
    R - d/2 instead of R changes the answer by about d_max/R."""
    from dpm.validation.references import effective_shear, mindlin_no_slip

    _, rho, young, nu = chung_ooi.STEEL
    m, r = sphere_mass(1e-5, rho), 1e-5
    es = effective_young(young, nu)
    assert mindlin_no_slip(m, r, es, 1e-12 * es, 5.0) == pytest.approx(1.0, abs=1e-9)
    at_r = mindlin_no_slip(m, r, es, effective_shear(young, nu), 5.0, arm=0.0)
    half = mindlin_no_slip(m, r, es, effective_shear(young, nu), 5.0)
    assert 0.9 < half < at_r < 1.0
