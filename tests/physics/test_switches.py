"""Boundaries switched off and on during a run (dpm.switches): the plug under a bed opens,
the other contacts keep their history, a switch lies where its time says, checkpoints
carry pending switches."""

from __future__ import annotations

import math

import numpy as np
import pytest

import dpm
from dpm.errors import ParameterError, SceneError

G = 9.81
R = 1e-3
DT = 2e-6


def scene(n_side: int = 3, plug_z: float = 0.01):
    """A small bed of frictional spheres resting on a plug plane at ``plug_z`` above a
    floor plane at z = 0; a side wall far away that nothing touches."""
    sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G), integrator="velocity_verlet")
    glass = dpm.Material("glass", density=2500.0, young=1e8, poisson=0.3)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    floor = sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
    plug = sim.add_boundary("plane", material=glass, point=(0, 0, plug_z), normal=(0, 0, 1))
    far = sim.add_boundary("plane", material=glass, point=(1.0, 0, 0), normal=(-1, 0, 0))
    xs = (np.arange(n_side) - (n_side - 1) / 2) * 2.05 * R
    pts = [(x, y, plug_z + R * (1 + 2.05 * k)) for k in range(2) for x in xs for y in xs]
    sim.add_particles("sphere", material=glass, radius=R, positions=pts)
    return sim, floor, plug, far


def state(sim):
    b = sim.bodies
    return np.concatenate([b.position.ravel(), b.velocity.ravel(), b.angular_velocity.ravel()])


def test_switching_a_boundary_nothing_touches_changes_no_bit():
    """Off and on again of a wall no particle reaches: the run is bit for bit the run
    without the switches (the forced list rebuilds keep every history)."""
    a, *_ = scene()
    a.run(steps=3000, progress=False)
    b, _, _, far = scene()
    b.switch_off(far, at=1000 * DT)
    b.switch_on(far, at=2000.5 * DT)
    b.run(steps=3000, progress=False)
    assert np.array_equal(state(a), state(b))
    assert a.rebuild_count < b.rebuild_count  # the switches did rebuild the lists


def test_plug_opens_under_a_settled_bed():
    """The bed rests on the plug (it carries the weight); switched off at t1, the bed falls
    freely: its centre of mass follows z(t) = z1 + v1 t - g t^2 / 2 to rounding (exact for
    the velocity Verlet step), with the plug's load zero; it lands on the floor, which then
    carries the weight."""
    sim, floor, plug, _ = scene()
    sim.run(until=0.02, progress=False)  # settle on the plug
    mg = float(np.sum(sim.bodies.mass)) * G
    np.testing.assert_allclose(plug.force[2], -mg, rtol=1e-3)
    assert np.all(floor.force == 0)
    # the bed at rest: relative positions fixed while it falls (the inner contacts keep
    # their forces and history, so the bed falls as one)
    t1 = sim.time + 100 * DT
    sim.switch_off(plug, at=t1)
    sim.run(steps=100, progress=False)
    assert sim.time == pytest.approx(t1) and not plug.enabled
    assert np.all(plug.force == 0)
    # the step after the switch still takes half a kick of the plug's force of t1 (velocity
    # Verlet: v(t + dt/2) = v(t) + a(t) dt / 2); from its end on, the fall is free
    sim.run(steps=1, progress=False)
    z1 = sim.bodies.position[:, 2].copy()
    v1 = sim.bodies.velocity[:, 2].copy()
    sim.run(steps=2000, progress=False)
    t = 2000 * DT
    # free fall of the whole bed: the centre of mass falls as g t^2 / 2 (internal forces
    # cancel), wherever the single spheres go
    m = sim.bodies.mass
    zc = (m @ sim.bodies.position[:, 2]) / m.sum()
    zc1 = (m @ z1) / m.sum()
    vc1 = (m @ v1) / m.sum()
    assert zc == pytest.approx(zc1 + vc1 * t - G * t * t / 2, abs=1e-12)
    assert np.all(plug.force == 0) and np.all(floor.force == 0)
    sim.run(until=sim.time + 0.1, progress=False)  # down 10 mm, bounce, settle on the floor
    np.testing.assert_allclose(floor.force[2], -mg, rtol=1e-3)
    assert np.all(plug.force == 0)
    assert sim.bodies.position[:, 2].max() < 0.01


def test_switch_on_again_between_runs():
    sim, floor, plug, _ = scene()
    sim.switch_off(plug)                 # before the first run: the bed starts falling
    assert not plug.enabled
    sim.run(steps=200, progress=False)
    assert np.all(plug.force == 0)
    assert sim.bodies.velocity[:, 2].max() < 0
    sim.switch_on(plug)                  # between runs: the spheres are just below it now
    assert plug.enabled
    sim.run(steps=10, progress=False)
    assert plug.force[2] < 0             # it catches them (they are behind its face by
    # less than their radius: a one-sided plane pushes them back up)


def test_inlet_places_particles_across_a_switched_off_wall():
    """An inlet region that lies behind a plane: refused while the plane is on, filled when
    it is off."""
    def build(off):
        sim = dpm.Simulation(dt=DT, gravity=(0, 0, -G))
        glass = dpm.Material("glass", density=2500.0, young=1e8, poisson=0.3)
        sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
        sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
        roof = sim.add_boundary("plane", material=glass, point=(0, 0, 0.01), normal=(0, 0, 1))
        if off:
            sim.switch_off(roof)
        sim.add_inlet(dpm.BoxRegion((0, 0, 0.001), (0.01, 0.01, 0.009)), glass, rate=2e5,
                      radius=R)
        return sim
    with pytest.raises(SceneError, match="lies inside every boundary"):
        build(False).run(steps=10, progress=False)
    sim = build(True)
    sim.run(steps=10, progress=False)
    assert len(sim.bodies) > 0 and sim.bodies.position[:, 2].max() < 0.01


def test_checkpoint_carries_a_pending_switch(tmp_path):
    a, _, plug_a, _ = scene()
    a.switch_off(plug_a, at=1500 * DT)
    a.run(steps=1000, progress=False)
    path = a.checkpoint(tmp_path / "c.h5")
    a.run(steps=1000, progress=False)
    b = dpm.restart(path)
    assert b.boundaries[1].enabled and len(b.operations.switches.pending) == 1
    b.run(steps=1000, progress=False)
    assert not b.boundaries[1].enabled
    assert np.array_equal(state(a), state(b))


def test_a_switch_keeps_its_time_when_dt_changes():
    sim, _, plug, _ = scene()
    sim.switch_off(plug, at=0.004)
    sim.run(until=0.002, progress=False)
    sim.dt = DT / 2
    sim.run(until=0.0039, progress=False)
    assert plug.enabled
    sim.run(until=0.0041, progress=False)
    assert not plug.enabled


@pytest.mark.parametrize("kwargs, match", [
    (dict(boundary=7), "is not a boundary of this simulation"),
    (dict(boundary="plug"), "is not a boundary of this simulation"),
    (dict(at=-1.0), "lies before the simulation's time"),
    (dict(at=math.nan), "must be a finite time"),
    (dict(at="soon"), "must be a finite time"),
])
def test_bad_switches_are_named(kwargs, match):
    sim, _, plug, _ = scene()
    kwargs.setdefault("boundary", plug)
    with pytest.raises(ParameterError, match=match):
        sim.switch_off(kwargs.pop("boundary"), **kwargs)


def test_scene_file_switches_a_boundary(tmp_path):
    """``switch_off`` / ``switch_on`` keys of a [[boundaries]] table schedule the switches;
    a misspelt key is named."""
    from dpm.io.scene import load_scene

    text = """
[simulation]
dt = 2e-6
gravity = [0.0, 0.0, -9.81]
[materials.glass]
density = 2500.0
young = 1e8
poisson = 0.3
[[contacts]]
materials = ["glass", "glass"]
model = "hertz_mindlin"
restitution = 0.5
friction = 0.5
[[boundaries]]
kind = "plane"
material = "glass"
[[boundaries]]
kind = "plane"
material = "glass"
point = [0.0, 0.0, 0.01]
switch_off = 0.001
switch_on = 0.002
[[particles]]
shape = "sphere"
material = "glass"
radius = 1e-3
positions = [[0.0, 0.0, 0.011]]
"""
    f = tmp_path / "s.toml"
    f.write_text(text)
    sim, _ = load_scene(f, output=False)
    pending = sim.operations.switches.pending
    assert [(s.on, s.time) for s in pending] == [(False, 0.001), (True, 0.002)]
    sim.run(until=0.0015, progress=False)
    assert not sim.boundaries[1].enabled
    f.write_text(text.replace("switch_on", "switch_onn"))
    with pytest.raises(ParameterError, match="switch_onn"):
        load_scene(f, output=False)
