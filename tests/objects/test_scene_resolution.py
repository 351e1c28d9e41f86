"""Every pair and name a run will meet is resolved before step 1, inlets included; and no
more than can occur is asked for."""

from __future__ import annotations

import numpy as np
import pytest

import dpm

GLASS = dict(density=2500.0, young=5e6, poisson=0.45)
R = 1e-3


def _floor_scene():
    glass = dpm.Material("glass", **GLASS)
    steel = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    sim = dpm.Simulation(dt=1e-6, gravity=(0, 0, -9.81))
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(glass, steel, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_particles("sphere", material=glass, radius=R,
                      positions=[(0, 0, 2 * R), (3 * R, 0, 2 * R)])
    return sim, glass, steel


def test_material_only_an_inlet_brings_needs_its_laws_before_step_1():
    """It used to get zero rows: its particles sank through the floor until an
    UnstableRunError at step 2571 that said 'reduce dt'."""
    sim, glass, steel = _floor_scene()
    rubber = dpm.Material("rubber", density=1100.0, young=1e7, poisson=0.49)
    sim.add_inlet(dpm.BoxRegion((-0.01, -0.01, 0.01), (0.01, 0.01, 0.02)), rubber,
                  rate=1000.0, radius=R, start=1e-3)
    with pytest.raises(dpm.SceneError) as err:
        sim.run(steps=10, progress=False)
    msg = str(err.value)
    assert "no contact law" in msg
    for pair in ("glass-rubber (brought by an inlet)",
                 "rubber (brought by an inlet)-rubber (brought by an inlet)",
                 "rubber (brought by an inlet)-steel (plane)"):
        assert pair in msg, msg
    assert sim.step_count == 0
    # with its laws it runs
    sim.contact(rubber, rubber, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(rubber, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.contact(rubber, steel, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.run(steps=10, progress=False)
    assert sim.step_count == 10


def test_misspelt_inlet_shape_or_parameter_is_found_before_step_1():
    """It used to raise UnknownNameError at the inlet's first insertion (step 1000); then
    in the scene check before step 1; now when the inlet is added."""
    sim, glass, _ = _floor_scene()
    region = dpm.BoxRegion((-0.01, -0.01, 0.01), (0.01, 0.01, 0.02))
    with pytest.raises(dpm.errors.UnknownNameError) as err:
        sim.add_inlet(region, glass, rate=100.0, shape="spere", radius=R, start=1e-3)
    msg = str(err.value)
    assert "'spere'" in msg and "registered:" in msg and "sphere" in msg
    with pytest.raises(dpm.errors.ParameterError, match="radious"):
        sim.add_inlet(region, glass, rate=100.0, radious=(R, 2 * R), start=1e-3)
    assert sim.inlets == [] and sim.step_count == 0


def test_one_free_body_needs_no_law_and_no_contact_limits_its_step():
    sim = dpm.Simulation(dt=1e-4, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", **GLASS)
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0)])
    rep = sim.time_step_report()
    assert rep.contact_time is None and rep.problems() == ([], [])
    sim.run(steps=100, progress=False)  # free fall, no law needed
    t = 100 * 1e-4
    np.testing.assert_allclose(sim.bodies.position[0, 2], -0.5 * 9.81 * t * t, rtol=1e-9)
    # a second body of the same material can meet the first: now the law is needed
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0.1, 0, 0)])
    with pytest.raises(dpm.SceneError, match="glass-glass"):
        sim.run(steps=1, progress=False)
