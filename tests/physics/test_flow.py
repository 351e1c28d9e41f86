"""Inlets, outlets, particle removal and periodic faces.

References: mass conservation (inserted = removed + remaining, to round-off), free fall
(residence time of a sphere falling from rest through a height h is sqrt(2 h / g)),
momentum conservation of a periodic gas, the same collision across a periodic face and in
the middle of the box, and the contact history of untouched pairs across a removal.
"""

import math

import numpy as np
import pytest

import dpm

G = 9.81


def material():
    return dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)


def base(dt=2e-5, gravity=(0.0, 0.0, -G)):
    m = material()
    sim = dpm.Simulation(dt=dt, gravity=gravity, dt_check="off")
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return sim, m


def test_outlet_mass_balance_and_records(tmp_path):
    """Removed mass + remaining mass = inserted mass; the HDF5 file keeps the records."""
    sim, m = base()
    sim.add_boundary("box", material=m, lower=(-0.03, -0.03, 0.0), upper=(0.03, 0.03, 0.3),
                     open=("+z",))
    inlet = sim.add_inlet(dpm.BoxRegion((-0.025, -0.025, 0.15), (0.025, 0.025, 0.25)), m,
                          rate=3000.0, radius=(2e-3, 3e-3), every=5e-3, stop=0.1, seed=3)
    outlet = sim.add_outlet(dpm.BoxRegion((-0.03, -0.03, -1.0), (0.0, 0.03, 0.04)))
    sim.output(tmp_path / "flow.h5", every=0.05)
    sim.run(until=0.35, progress=False)
    sim.close()
    assert inlet.inserted == pytest.approx(3000 * 0.1, abs=1)
    assert outlet.count > 20  # the scene must actually remove particles
    total = outlet.removed_mass + float(sim.bodies.mass.sum())
    assert total == pytest.approx(inlet.inserted_mass, rel=1e-12)
    r = dpm.load(tmp_path / "flow.h5")
    assert len(r.removed["id"]) == outlet.count
    np.testing.assert_array_equal(np.sort(r.removed["id"]), np.sort(outlet.records["id"]))
    assert np.all(r.removed["residence_time"] > 0)
    # radii drawn within the distribution, ids never reused
    radii = np.concatenate([sim.bodies.radius, r.frame(-1)["radius"]])
    assert radii.min() >= 2e-3 and radii.max() <= 3e-3
    all_ids = np.concatenate([sim.bodies.id, outlet.records["id"]])
    assert len(np.unique(all_ids)) == len(all_ids) == inlet.inserted


def test_residence_time_of_free_fall():
    """A sphere dropped from rest at height h reaches an outlet at z < 0 after
    sqrt(2 h / g); recorded to within one outlet interval."""
    sim, m = base(dt=1e-5)
    h = 0.2
    every = 2e-4
    sim.add_particles("sphere", material=m, radius=1e-3, positions=[[0.0, 0.0, h]])
    outlet = sim.add_outlet(dpm.BoxRegion((-1, -1, -1), (1, 1, 0.0)), every=every)
    sim.run(until=0.25, progress=False)
    t_fall = math.sqrt(2 * h / G)
    rec = outlet.records
    assert len(rec["id"]) == 1 and len(sim.bodies) == 0
    assert t_fall <= rec["residence_time"][0] < t_fall + every + 1e-12
    assert rec["velocity"][0, 2] == pytest.approx(-G * rec["time"][0], rel=1e-9)


def test_inlet_places_without_overlap_and_respects_rate():
    sim, m = base(gravity=(0.0, 0.0, 0.0))
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.05, 0.05, 0.05))
    inlet = sim.add_inlet(dpm.BoxRegion((0.0, 0.0, 0.0), (0.05, 0.05, 0.05)), m, rate=20000.0,
                          radius=2e-3, every=1e-3, stop=0.01, seed=1)
    sim.run(steps=1, progress=False)
    b = sim.bodies
    d = np.linalg.norm(b.position[:, None] - b.position[None], axis=2)
    np.fill_diagonal(d, 1.0)
    assert d.min() >= 4e-3 * (1 - 1e-12)  # no two spheres overlap
    assert np.all(b.position >= 2e-3 - 1e-12) and np.all(b.position <= 0.048 + 1e-12)
    assert len(b) == pytest.approx(20000 * 1e-3, abs=1)  # the first interval
    sim.run(until=0.02, progress=False)
    assert inlet.inserted == pytest.approx(20000 * 0.01, abs=1)


def incline_scene():
    m = material()
    sim = dpm.Simulation(dt=1e-5, gravity=(0.0, 0.0, -G), dt_check="off")
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5,
                rolling_friction=0.6)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0.3, 0, 1.0))
    sim.add_particles("sphere", material=m, radius=2e-3,
                      positions=[[0.0, 0.0, 0.0021], [0.1, 0.0, 0.05]])
    return sim


def test_removal_keeps_contact_history_of_others():
    """Removing a far-away body leaves the contact history of the others as it was: the
    tangential spring of a sphere resting on an incline is the same row after the
    removal, and its trajectory is that of a run without the removal."""
    sim = incline_scene()
    ref = incline_scene()
    sim.run(until=0.05, progress=False)
    ref.run(until=0.05, progress=False)
    wc = sim.wall_contacts
    k = int(np.flatnonzero(wc.active[:wc.count])[0])
    hist = wc.history[k].copy()
    assert np.linalg.norm(hist[:3]) > 0  # a tangential spring holds it
    sim.remove_particles([1])
    assert len(sim.bodies) == 1 and sim.bodies.id[0] == 0
    wc = sim.wall_contacts
    k = int(np.flatnonzero(wc.active[:wc.count])[0])
    np.testing.assert_array_equal(wc.history[k], hist)
    sim.run(until=0.08, progress=False)
    ref.run(until=0.08, progress=False)
    np.testing.assert_allclose(sim.bodies.position[0], ref.bodies.position[0], rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(sim.bodies.velocity[0], ref.bodies.velocity[0], rtol=0,
                               atol=1e-12)


def test_periodic_gas_conserves_count_and_momentum():
    sim, m = base(dt=2e-6, gravity=(0.0, 0.0, 0.0))
    for axis in "xyz":
        sim.set_periodic(axis, 0.0, 0.02)
    g = np.arange(5) * 0.004 + 0.001
    pos = np.array(np.meshgrid(g, g, g)).reshape(3, -1).T
    vel = np.random.default_rng(1).normal(0.0, 0.5, pos.shape)
    sim.add_particles("sphere", material=m, radius=1.5e-3, positions=pos, velocities=vel)
    p0 = sim.momentum().copy()
    sim.run(steps=10000, progress=False)
    assert len(sim.bodies) == 125
    scale = float(np.sum(sim.bodies.mass * np.linalg.norm(vel, axis=1)))
    assert np.all(np.abs(sim.momentum() - p0) < 1e-12 * scale)
    assert np.all(sim.bodies.position >= 0.0) and np.all(sim.bodies.position < 0.02)
    assert sim.rebuild_count > 1


def head_on(x0, period):
    """Two spheres colliding head-on along x around x0; returns their final velocities."""
    sim, m = base(dt=1e-6, gravity=(0.0, 0.0, 0.0))
    if period:
        sim.set_periodic("x", 0.0, 0.05)
    r = 2e-3
    sim.add_particles("sphere", material=m, radius=r,
                      positions=[[x0 - 1.5 * r, 0.01, 0.01], [x0 + 1.5 * r, 0.01, 0.01]],
                      velocities=[[0.5, 0.1, 0.0], [-0.5, 0.0, 0.0]])
    sim.run(steps=3000, progress=False)
    return sim.bodies.velocity.copy(), sim.bodies.angular_velocity.copy()


def test_collision_across_periodic_face_equals_collision_inside():
    v_in, w_in = head_on(0.025, period=True)
    v_face, w_face = head_on(0.0, period=True)  # the pair straddles x = 0 = 0.05
    assert abs(v_in[0, 0] + 0.5 * 0.5) < 0.3  # they did collide (restitution 0.5)
    np.testing.assert_allclose(v_face, v_in, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(w_face, w_in, rtol=1e-9, atol=1e-12)


def test_flow_and_periodic_errors_name_the_parameter():
    sim, m = base()
    region = dpm.BoxRegion((0, 0, 0), (1, 1, 1))
    with pytest.raises(dpm.ParameterError, match="exactly one of rate"):
        sim.add_inlet(region, m, radius=1e-3)
    with pytest.raises(dpm.ParameterError, match=r"rate=-1 is outside \(0, inf\)"):
        sim.add_inlet(region, m, rate=-1.0, radius=1e-3)
    with pytest.raises(dpm.ParameterError, match="region=.*must be a dpm region"):
        sim.add_outlet((0, 0, 0))
    with pytest.raises(dpm.ParameterError, match="remove='below'"):
        sim.add_outlet(region, remove="below")
    with pytest.raises(dpm.ParameterError, match="axis='w'"):
        sim.set_periodic("w", 0.0, 1.0)
    with pytest.raises(dpm.ParameterError, match="must exceed"):
        sim.set_periodic("x", 1.0, 0.0)
    sim.set_periodic("x", 0.0, 0.004)
    sim.add_particles("sphere", material=m, radius=1e-3, positions=[[0.002, 0.0, 0.0]])
    with pytest.raises(dpm.ParameterError, match="period along x is 0.004 m; it must be"):
        sim.run(steps=1, progress=False)


def test_inlet_starting_later_fills_an_empty_scene(tmp_path):
    """An empty scene whose inlet starts at 0.05 s waits (time advances, nothing to
    compute) and runs from the first insertion; the first body arrives at the start of the
    first interval that owes a whole one and falls freely from there:
    z(t) = z0 - g (t - t_in)^2 / 2."""
    sim, m = base(dt=1e-5)
    inlet = sim.add_inlet(dpm.BoxRegion((0.0, 0.0, 0.1), (0.01, 0.01, 0.11)), m, rate=1000.0,
                          radius=1e-3, every=1e-3, start=0.05, stop=0.051, seed=3)
    sim.output(tmp_path / "late.h5", every=0.01)
    sim.run(until=0.02, progress=False)  # ends before the start: no bodies, no file yet
    assert len(sim.bodies) == 0 and sim.time == pytest.approx(0.02)
    assert not (tmp_path / "late.h5").exists()
    sim.run(until=0.1, progress=False)
    assert inlet.inserted == 1 and len(sim.bodies) == 1
    t_in = 0.05  # the first interval that owes a whole body: [0.05, 0.051]
    z0 = sim.bodies.position[0, 2] + 0.5 * G * (0.1 - t_in) ** 2
    assert 0.1 + 1e-3 <= z0 <= 0.11 - 1e-3  # it started inside the region at rest
    run = dpm.load(tmp_path / "late.h5")
    assert run.times[0] == pytest.approx(t_in, abs=1e-9)
    assert run.times[-1] == pytest.approx(0.1, abs=1e-9)


def test_inlet_count_is_exact_over_many_intervals():
    """500 bodies at 500/s over [0.2, 1.2] s in intervals of 1e-3 s: 500, not 499 (the
    interval sums of 1.2 - 0.2 are a hair under 1)."""
    sim, m = base(dt=1e-3, gravity=(0.0, 0.0, 0.0))
    inlet = sim.add_inlet(dpm.BoxRegion((0.0, 0.0, 0.0), (0.5, 0.5, 0.5)), m, rate=500.0,
                          radius=1e-3, every=1e-3, start=0.2, stop=1.2, seed=2)
    for t in np.arange(0.0, 1.5, 1e-3):
        inlet.owed(t)  # polled as often as the runs do
    assert inlet.owed(1.5) == 500.0
    assert inlet.owed(0.7) == pytest.approx(250.0)
