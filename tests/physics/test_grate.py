"""The moving grate (#20, Samiei 2012 ch. 4): the reciprocating bar motion against its closed
form, the residence time distribution of a plug flow, and the grate's mass balance."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import dpm
from dpm import analysis as an
from dpm.motion import frames

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "grate.py"


def closed_form(t: float, A: float, v: float, tp: float, phase: float = 0.0
                ) -> tuple[float, float]:
    """(s, ds/dt) of the stroke written out case by case, one time at a time."""
    ts = A / v
    T = 2 * ts + 2 * tp
    tau = math.fmod(t + phase, T)
    if tau < 0:
        tau += T
    if tau < ts:
        return v * tau, v
    if tau < ts + tp:
        return A, 0.0
    if tau < 2 * ts + tp:
        return A - v * (tau - ts - tp), -v
    return 0.0, 0.0


def test_reciprocating_closed_form_at_many_times():
    A, v, tp = 0.03, 0.0035, 1.0
    e = np.array([math.cos(0.3), 0.0, -math.sin(0.3)])
    m = dpm.Reciprocating(stroke=tuple(A * e), speed=v, pause=tp)
    ts = A / v
    T = 2 * ts + 2 * tp
    assert m.period == pytest.approx(T)
    # random times over three cycles, plus the turning points and the pauses' ends
    t = np.concatenate([np.random.default_rng(4).uniform(0, 3 * T, 500),
                        [0.0, ts, ts + 0.5 * tp, ts + tp, 2 * ts + tp, 2 * ts + 1.5 * tp,
                         T, T + ts, 2 * T + 2 * ts + tp]])
    r, o = m.pose(t)
    vel, w = m.rates(t)
    for k, tk in enumerate(t):
        s, ds = closed_form(tk, A, v, tp)
        assert np.allclose(o[k], s * e, atol=1e-12), tk
        assert np.allclose(vel[k], ds * e, atol=1e-12), tk
    assert np.allclose(r, np.eye(3)[None]) and np.all(w == 0.0)
    # the pauses: at rest at both ends
    s, ds = m.displacement(np.array([ts + 0.5 * tp, 2 * ts + 1.5 * tp]))
    assert np.allclose(s, [A, 0.0]) and np.all(ds == 0.0)
    # the displacement is continuous and its rate is its derivative away from the corners
    tt = np.linspace(0.01, T - 0.01, 2001)
    s, ds = m.displacement(tt)
    assert np.max(np.abs(np.diff(s))) <= v * (tt[1] - tt[0]) * (1 + 1e-9)
    corners = np.array([0.0, ts, ts + tp, 2 * ts + tp, T])
    h = 1e-6
    mid = np.min(np.abs(tt[:, None] - corners[None]), axis=1) > 2 * h
    sp, _ = m.displacement(tt + h)
    sm, _ = m.displacement(tt - h)
    assert np.allclose(((sp - sm) / (2 * h))[mid], ds[mid], atol=1e-9)
    # the frame rows the kernels see
    f = frames(m, t[:3])
    assert np.allclose(f[:, 0:3], o[:3]) and np.allclose(f[:, 12:15], vel[:3])


def test_reciprocating_phase_and_without_pause():
    A, v = 0.02, 0.01
    m = dpm.Reciprocating(stroke=(0.0, A, 0.0), speed=v, pause=0.0, phase=0.7)
    t = np.linspace(-3.0, 9.0, 301)
    _, o = m.pose(t)
    want = np.array([closed_form(x, A, v, 0.0, 0.7)[0] for x in t])
    assert np.allclose(o[:, 1], want, atol=1e-12)
    # without pauses it is TriangularOscillation of period 2 A / v
    tri = dpm.TriangularOscillation(amplitude=(0.0, A, 0.0), period=2 * A / v)
    m0 = dpm.Reciprocating(stroke=(0.0, A, 0.0), speed=v)
    assert np.allclose(m0.pose(t)[1], tri.pose(t)[1], atol=1e-12)


def test_reciprocating_registered_and_bad_input():
    assert dpm.registry().lookup("motion", "reciprocating", "test") is dpm.Reciprocating
    with pytest.raises(dpm.ParameterError, match="speed"):
        dpm.Reciprocating(stroke=(0.03, 0, 0), speed=0.0)
    with pytest.raises(dpm.ParameterError, match="pause"):
        dpm.Reciprocating(stroke=(0.03, 0, 0), speed=0.01, pause=-1.0)
    with pytest.raises(dpm.ParameterError, match="stroke"):
        dpm.Reciprocating(stroke=(0.0, 0.0, 0.0), speed=0.01)


def test_plug_flow_rtd_is_a_delta_and_a_step():
    """All bodies stay the same time t0: E(t) is one bin holding all the weight, F(t) a
    unit step at t0 and the mean (eq. 3.58) is t0, mass-weighted or not."""
    t0 = 123.4
    n = 50
    rng = np.random.default_rng(2)
    rec = {"id": np.arange(n), "time": t0 + np.sort(rng.uniform(0, 100, n)),
           "mass": rng.uniform(1e-3, 3e-3, n), "residence_time": np.full(n, t0)}
    for weighted in (False, True):
        rtd = an.residence_times(rec, mass_weighted=weighted)
        assert rtd.mean == pytest.approx(t0, rel=1e-14)
        assert rtd.variance == pytest.approx(0.0, abs=1e-20)
        assert np.array_equal(rtd.F([0.0, t0 - 1e-9, t0, t0 + 1.0, 1e6]), [0, 0, 1, 1, 1])
        edges, dens = rtd.E(bins=20, range=(100.0, 150.0))
        width = edges[1] - edges[0]
        k = int((t0 - 100.0) // width)
        assert dens[k] * width == pytest.approx(1.0)  # all of E in the bin of t0
        assert np.all(np.delete(dens, k) == 0.0)
    # mass-related mean of a two-time sample: sum m t / sum m (eq. 3.58)
    rec2 = {"id": np.arange(2), "time": np.array([5.0, 9.0]), "mass": np.array([1.0, 3.0]),
            "residence_time": np.array([2.0, 6.0])}
    assert an.residence_times(rec2, mass_weighted=True).mean == pytest.approx(5.0)
    assert an.residence_times(rec2).mean == pytest.approx(4.0)


def _example():
    spec = importlib.util.spec_from_file_location("grate_example", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["grate_example"] = mod  # (its dataclass looks its module up)
    spec.loader.exec_module(mod)
    return mod


def test_grate_geometry_tiles():
    """The bars overlap like tiles with the steps of the module docstring, and the moving
    bars' stroke never uncovers the bar below."""
    g = _example()
    fw, bw = g.Geometry("forward"), g.Geometry("backward")
    for geo in (fw, bw):  # the same bars at 20 deg to the grate line: steps of one bar height
        assert geo.step == pytest.approx(g.BAR_HEIGHT)
        assert geo.exposed == pytest.approx(g.BAR_HEIGHT / math.tan(math.radians(20.0)))
    # forward: the bar tops rise toward the downstream noses; backward: they fall from the
    # upstream noses; the noses are the tops' highest points
    assert fw.top_end[0, 2] > fw.top_start[0, 2] and bw.top_start[0, 2] > bw.top_end[0, 2]
    for geo, grate in ((fw, "forward"), (bw, "backward")):
        slope = -(geo.nose[-1, 2] - geo.nose[0, 2]) / (geo.nose[-1, 0] - geo.nose[0, 0])
        assert math.degrees(math.atan(slope)) == pytest.approx(g.GRATES[grate][0])
        assert geo.exposed + g.STROKE < g.BAR_LENGTH
        assert int(geo.moving.sum()) == 6 and geo.moving[0] and not geo.moving[1]


@pytest.mark.slow
def test_grate_quick_run_mass_balance(tmp_path):
    """The example's --quick run (backward grate, wood, 45 fast bar cycles): every body fed
    (initial bed and inlet) is either discharged or on the grate, by ids, the masses add
    up, the feed is the width-scaled rate (eq. 4.1) and the tracers' RTD is a distribution
    (F rises from 0 to 1, E integrates to 1, the mean lies inside the samples)."""
    g = _example()
    summary = g.main(["--quick", "--output", str(tmp_path)])
    for f in ("grate_quick.json", "grate_quick.png", "grate_quick_bed.png"):
        assert (tmp_path / f).stat().st_size > 0
    r = summary["quick"]["runs"][0]
    b = r["mass_balance"]
    assert b["exact"]
    assert b["fed"] == b["discharged"] + b["escaped"] + b["on_grate"]
    assert b["discharged"] > 0 and b["escaped"] == 0
    assert b["fed_mass_kg"] == pytest.approx(b["discharged_mass_kg"] + b["on_grate_mass_kg"],
                                             rel=1e-12)
    assert r["mass_flow_sim_kg_s"] == pytest.approx(
        40.0 / 3600 * r["width_m"] / g.GRATE_WIDTH * g.SPEED_UP)
    t = np.asarray(r["residence_samples"])
    w = np.asarray(r["residence_weights"])
    assert r["tracers_out"] >= 3 and len(t) == r["tracers_out"]
    rtd = an.ResidenceTimes(t, w, r["mean_residence_s"], r["std_residence_s"] ** 2)
    assert rtd.F(0.0) == 0.0 and rtd.F(t.max()) == pytest.approx(1.0)
    edges, dens = rtd.E(bins=10)
    assert np.sum(dens * np.diff(edges)) == pytest.approx(1.0)
    assert t.min() <= r["mean_residence_s"] <= t.max()
    assert r["mean_residence_s"] == pytest.approx(np.sum(w * t) / np.sum(w))
