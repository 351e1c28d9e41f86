"""The tumbling screening machine (examples/screening_machine.py, Alkhaldi 2007 ch. 4).

What can be checked exactly:

- the thesis' efficiency (eq. 4.33) and the deck screening fractions from constructed
  exits and arrivals, counted by hand;
- each size's own level from the clearance rule (d < w passes a square hole of width w);
- sieve counts on a constructed particle set: spheres dropped straight onto a model-1
  sieve (eq. 4.20) over hole centres, inside and outside the reduced hole, and over bars,
  pass exactly when the rule says so;
- the machine's quick run: mass balance (fed = exited + in the machine), no particle below
  its own level, every exit classified (slow: it compiles the machine's step module).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import dpm

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "examples"))
import screening_machine as sm  # noqa: E402


def test_efficiency_from_constructed_exits():
    own = np.array([1, 2, 3, 4, 5])
    # exits as (class, level): level 5: 3 sorted (class 4), 1 gangue (class 0);
    # level 3: 2 sorted (class 2), 2 gangue (class 1 and 0); level 1: 4 sorted
    cls = np.array([4, 4, 4, 0, 2, 2, 1, 0, 0, 0, 0, 0])
    lev = np.array([5, 5, 5, 5, 3, 3, 3, 3, 1, 1, 1, 1])
    reached = np.zeros((5, 5), np.int64)
    reached[0, 4], reached[0, 3] = 10, 6    # class 0: 10 on level 5, 6 reached level 4
    reached[1, 4], reached[1, 3] = 4, 1
    f = sm.figures((cls, lev), reached, own, 5)
    assert f["sorted"] == [4, 0, 2, 0, 3]
    assert f["gangue"] == [0, 0, 2, 0, 1]
    # c = 100/M sum s_i/(s_i+g_i), c_1 = 1 (eq. 4.34), other levels without exits 0
    assert f["machine_efficiency"] == pytest.approx(100 / 5 * (1 + 0.5 + 0.75))
    assert sm.machine_efficiency([0, 0, 0, 0, 1], [0, 0, 0, 0, 1]) == pytest.approx(30.0)
    # level 5's floor: classes 0..3 fit it; 14 of them came, 7 reached level 4
    assert f["deck_screening"][3] == pytest.approx(7 / 14)
    assert f["oversize_through"] == 0 and f["unseen"] == 0
    # an oversize exit below its own level is flagged, not counted as sorted
    f = sm.figures((np.array([4]), np.array([2])), reached, own, 5)
    assert f["oversize_through"] == 1 and sum(f["sorted"]) == 0


def test_own_level_of_each_size():
    machine = object.__new__(sm.Machine)
    sizes = np.array([d for _, d in sm.PACKAGE])
    assert machine.own_level(sizes).tolist() == [1, 2, 3, 4, 5]
    # just under the 13 mm hole passes it (rests on the 11 mm deck, level 2); equal to it
    # does not (rests on the 13 mm deck, level 3)
    assert machine.own_level(np.array([12.999e-3, 13e-3])).tolist() == [2, 3]


def test_case_from_strings_names_bad_keys():
    c = sm.Case.from_strings(["rpm=150", "barrel=fixed", "particles=10"])
    assert (c.rpm, c.barrel, c.particles) == (150.0, "fixed", 10)
    with pytest.raises(dpm.ParameterError, match="rpmm=1.*key one of"):
        sm.Case.from_strings(["rpmm=1"])
    with pytest.raises(dpm.ParameterError, match="rpm='fast' is not a float"):
        sm.Case.from_strings(["rpm=fast"])


def test_sieve_counts_on_constructed_set():
    """Model 1 (eq. 4.20): a sphere of radius r < w = hole/2 whose centre lies outside the
    reduced hole of half width w - b, b = zeta (w - r), rests on the plate; one inside it
    enters the hole, where the real hole's rim acts on it. Dropped straight down from
    rest onto a sieve of hole 10 mm, bar 10 mm, zeta = 0.8: a sphere clear of the rim
    (centre offset < w - r) falls through, one just outside the reduced hole and one over
    a bar rest, one wider than the hole never passes."""
    hole, bar, zeta = 10e-3, 10e-3, 0.8
    pitch = hole + bar
    sim = dpm.Simulation(dt=2e-5, gravity=(0.0, 0.0, -9.81))
    rock = dpm.Material("rock", density=2650.0, young=5e7, poisson=0.25)
    sim.contact(rock, rock, model="hertz_mindlin", restitution=0.4, friction=0.5)
    sieve = sim.add_boundary("sieve", material=rock, center=(0.0, 0.0, 0.0),
                             normal=(0.0, 0.0, 1.0), half_extents=(0.2, 0.2), hole=hole,
                             bar=bar, clearance_model="radius", zeta=zeta)
    w = hole / 2
    expect, placed = [], []
    k = 0
    for r in (2e-3, 3.5e-3, 4.5e-3, 5.5e-3):           # the last does not fit a hole
        b = zeta * max(w - r, 0.0)
        reduced = w - b
        # offsets of the centre from a hole centre, in x: centred; off-centre inside the
        # reduced hole and clear of the rim; just outside the reduced hole; and a point
        # over the middle of a bar
        for dx, passes in ((0.0, r < w), (0.9 * max(min(reduced, w - r), 0.0), r < w),
                           (1.1 * reduced, False), (0.5 * pitch, False)):
            cx = (k % 8 - 4) * 2 * pitch + dx    # every other hole: spheres 30 mm apart
            cy = (k // 8 - 2) * 2 * pitch
            placed.append((cx, cy, r + 2e-3, r))
            expect.append(passes)
            k += 1
    for cx, cy, cz, r in placed:
        sim.add_particles("sphere", material=rock, radius=r, positions=[(cx, cy, cz)])
    sim.run(until=0.06)
    below = sieve.below(sim.bodies.position)
    order = np.argsort(sim.bodies.id)
    assert below[order].tolist() == expect
    assert sum(expect) == 6 and len(expect) == 16


@pytest.mark.slow
def test_machine_quick_run_balances():
    case = sm.Case(until=0.6, particles=300, sample=0.01)
    m = sm.Machine(case)
    out = m.run()
    assert out["fed"] > 50
    assert out["fed"] == out["exited"] + out["present"] + out["escaped"]
    assert out["oversize_through"] == 0 and out["unseen"] == 0
    # every particle present sits on a level at or above its own
    lev = m.level_of(m.local(m.sim.bodies.position, m.sim.time))
    own = m.own_level(2.0 * m.sim.bodies.radius)
    assert np.all((lev == 0) | (lev >= own))
    assert math.isfinite(out["machine_efficiency"])


@pytest.mark.slow
def test_study_quick_runs_its_cases_and_draws(tmp_path):
    import json

    import screening_study

    out = tmp_path / "study"
    screening_study.main(["--quick", "--jobs", "1", "--output", str(out)])
    data = json.loads(out.with_suffix(".json").read_text())
    cases = data["results"]["barrel"]
    assert sorted(r["x"] for r in cases) == [1.0, 2.0]   # fixed and oscillating barrel
    for r in cases:
        assert r["fed"] == r["exited"] + r["present"] + r["escaped"]
        assert r["case"]["rpm"] == 150.0 and r["case"]["particles"] == 150
    assert out.with_suffix(".png").stat().st_size > 10_000
