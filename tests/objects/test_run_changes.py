"""State changes between runs and the run-time guards (docs/reliability.md, 3 and 4)."""

from __future__ import annotations

import numpy as np
import pytest

import dpm

GLASS = dict(density=2500, young=5e6, poisson=0.45)


def bed(integrator: str = "velocity_verlet", restitution: float = 0.3,
        friction: float = 0.5, dt: float = 2e-5, floor: str = "box",
        **kw) -> tuple[dpm.Simulation, dpm.Material]:
    """48 spheres dropped into an open box (or onto a floor plane)."""
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, -9.81), integrator=integrator, **kw)
    glass = dpm.Material("glass", **GLASS)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=restitution,
                friction=friction)
    if floor == "box":
        sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02),
                         open=("+z",))
    else:
        sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.008), spacing=2.1e-3, jitter=4e-5)
    sim.add_particles("sphere", material=glass, radius=1e-3, positions=xyz)
    return sim, glass


# ----------------------------------------------------------------- dt between runs
def test_dt_change_keeps_time_the_sum_of_the_steps():
    sim, _ = bed()
    sim.run(until=0.01)
    assert sim.step_count == 500 and sim.time == pytest.approx(0.01, abs=1e-15)
    sim.dt = 1e-5
    sim.run(steps=1000)
    assert sim.time == pytest.approx(0.02, rel=1e-12)  # (was 1500 x 1e-5 = 0.015 s)
    sim.run(until=0.025)
    assert sim.step_count == 2000 and sim.time == pytest.approx(0.025, rel=1e-12)
    with pytest.raises(dpm.ParameterError, match="sim.time is the sum of the steps"):
        sim.time = 0.0


@pytest.mark.parametrize("bad", [-1e-5, 0.0, float("nan"), float("inf"), "1e-5", True])
def test_dt_setter_refuses(bad):
    sim, _ = bed()
    with pytest.raises(dpm.ParameterError, match="sim.dt"):
        sim.dt = bad


def test_dt_change_is_checked_again_before_the_next_step():
    sim, _ = bed()
    sim.run(steps=10)
    sim.dt = 1e-3  # far beyond the critical step
    with pytest.raises(dpm.ParameterError, match="time step too large"):
        sim.run(steps=1)
    assert sim.step_count == 10
    sim.dt = 2e-5
    sim.run(steps=1)


def test_output_spacing_in_seconds_survives_a_dt_change(tmp_path):
    sim, _ = bed()
    sim.output(tmp_path / "o.h5", every=2e-3)
    sim.run(until=0.01)           # frames every 100 steps of 2e-5
    sim.dt = 1e-5
    sim.run(until=0.02)           # then every 200 steps of 1e-5
    sim.close()
    times = dpm.load(tmp_path / "o.h5").times
    assert np.allclose(np.diff(times), 2e-3, rtol=1e-9), times


def test_gravity_setter_validates():
    sim, _ = bed()
    sim.gravity = (0, 0, -1.0)
    assert sim.gravity[2] == -1.0
    for bad in ("down", (0, 0), (0, 0, float("nan"))):
        with pytest.raises(dpm.ParameterError, match="gravity"):
            sim.gravity = bad


# ----------------------------------------------------------------- particles added later
def test_particle_added_after_a_run_keeps_history_and_trajectories():
    """A sphere added far above a bed after a run: every tangential spring of the bed is
    kept, no initial-overlap error for the bed's own resting overlaps (a tolerance below
    them), and the bed's trajectories are bit for bit those of the run without it."""
    a, _ = bed(overlap_tolerance=1e-5)
    b, glass = bed(overlap_tolerance=1e-5)
    a.run(steps=3000)
    b.run(steps=3000)
    c = b.contacts
    springs = c.history[:c.count].copy()
    touching = int(np.count_nonzero(c.active[:c.count]))
    assert touching > 20 and np.count_nonzero(np.any(springs != 0, axis=1)) > 20
    assert b.backend.pair_overlaps().max() > 1e-5  # the bed overlaps more than tolerated
    b.add_particles("sphere", material=glass, radius=1e-3, positions=[(0.005, 0.005, 0.018)])
    assert np.array_equal(b.contacts.history[:b.contacts.count], springs)
    a.run(steps=500)
    b.run(steps=500)
    n = len(a.bodies)
    for name in ("position", "velocity", "angular_velocity", "force"):
        assert np.array_equal(getattr(a.bodies, name), getattr(b.bodies, name)[:n]), name
    assert b.bodies.position[n, 2] < 0.018  # the new one falls


def test_new_particle_overlapping_the_bed_is_refused_naming_it():
    sim, glass = bed()
    sim.run(steps=2000)
    top = sim.bodies.position[np.argmax(sim.bodies.position[:, 2])]
    ids = sim.add_particles("sphere", material=glass, radius=1e-3,
                            positions=[top + (0.0005, 0, 0)])
    with pytest.raises(dpm.SceneError, match=f"initial overlap.*{int(ids[0])}"):
        sim.run(steps=1)


# ----------------------------------------------------------------- guards
def test_energy_growth_warns_by_default():
    sim, _ = bed(integrator="taylor", restitution=1.0, friction=0.0, dt_check="warn")
    with pytest.warns(UserWarning, match="energy was created"):
        sim.run(steps=3000)


def test_energy_growth_stops_the_run(tmp_path):
    """Taylor at e = 1 creates energy (first order, not symplectic): the guard stops with
    the balance and writes the failing state; the symplectic integrators do not trip it."""
    sim, _ = bed(integrator="taylor", restitution=1.0, friction=0.0, dt_check="warn")
    sim.guards.energy = "stop"  # (the default warns)
    sim.output(tmp_path / "t.h5", every_steps=200)
    with pytest.raises(dpm.UnstableRunError, match="energy was created") as err:
        sim.run(steps=20000)
    assert sim.step_count < 5000
    assert "t.failed.h5" in str(err.value)
    run = dpm.load(tmp_path / "t.h5")
    assert run.steps[-1] == sim.step_count  # the failing state is the last frame
    back = dpm.restart(tmp_path / "t.failed.h5")
    assert back.step_count == sim.step_count


@pytest.mark.parametrize("integrator", ["velocity_verlet", "symplectic_euler"])
def test_energy_guard_quiet_for_conservative_runs(integrator):
    sim, _ = bed(integrator=integrator, restitution=1.0, friction=0.0, dt_check="warn")
    sim.guards.energy = "stop"
    sim.run(steps=5000)
    bal = sim.energy.balance(sim)
    assert bal["dissipated"] > -0.05 * sim.energy.scale


def test_escaping_particle_is_removed_and_recorded():
    sim, glass = bed(floor="plane", dt=1e-5)
    (fast,) = sim.add_particles("sphere", material=glass, radius=1e-3,
                                positions=[(0.005, 0.005, 0.015)], velocities=[(40, 0, 0)])
    with pytest.warns(UserWarning, match="left the scene"):
        sim.run(steps=3000)
    assert sim.escaped.count == 1 and sim.escaped.records["id"][0] == fast
    assert fast not in sim.bodies.id
    assert sim.rebuild_count < 400  # (not one rebuild per step for the rest of the run)


def test_escape_guard_stop_and_settings():
    sim, glass = bed(floor="plane", dt=1e-5)
    sim.add_particles("sphere", material=glass, radius=1e-3,
                      positions=[(0.005, 0.005, 0.015)], velocities=[(40, 0, 0)])
    sim.guards.escape = "stop"
    with pytest.raises(dpm.UnstableRunError, match="left the scene"):
        sim.run(steps=3000)
    with pytest.raises(dpm.ParameterError, match="sim.guards.escape='never'"):
        sim.guards.escape = "never"
    with pytest.raises(dpm.ParameterError, match="energy_growth"):
        sim.guards.energy_growth = -1


def test_nonfinite_state_is_named():
    sim, _ = bed()
    sim.run(steps=10)
    sim.bodies.angular_velocity[3, 1] = np.inf
    with pytest.raises(dpm.UnstableRunError,
                       match="angular_velocity became NaN or inf for particle id.s. 3"):
        sim.run(steps=10)


# ----------------------------------------------------------------- soak
@pytest.mark.slow
def test_soak_flowing_scene(tmp_path):
    """A vibrated box fed by an inlet and drained by an outlet, 10^6 steps with periodic
    checkpoints: the particle count balances at every check (inserted = present + removed
    + escaped) and the dissipated energy never decreases by more than 2 % of the run's
    energy scale between checks (energy in = boundary work + inserted energy)."""
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81), integrator="velocity_verlet")
    glass = dpm.Material("glass", **GLASS)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.4)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.016, 0.016, 0.03),
                     open=("+z",), motion=dpm.Oscillation(amplitude=(0, 0, 3e-4), frequency=40))
    sim.add_inlet(dpm.BoxRegion((0.002, 0.002, 0.02), (0.014, 0.014, 0.028)), glass,
                  rate=300, radius=(0.9e-3, 1.1e-3), seed=5)
    sim.add_outlet(dpm.BoxRegion((0.0, 0.0, -0.01), (0.006, 0.006, 0.004)), every=1e-3)
    xyz = dpm.lattice((0.001, 0.001, 0.001), (0.015, 0.015, 0.004), spacing=2.3e-3,
                      jitter=4e-5)
    first = len(sim.add_particles("sphere", material=glass, radius=1e-3, positions=xyz))
    sim.checkpoint_every(tmp_path / "soak.ckpt.h5", every_steps=100_000, keep=2)
    sim.guards.energy = "stop"
    d_prev = 0.0
    for _ in range(10):
        sim.run(steps=100_000, progress=False)
        inlet, outlet = sim.inlets[0], sim.outlets[0]
        assert first + inlet.inserted == len(sim.bodies) + outlet.count + sim.escaped.count
        bal = sim.energy.balance(sim)
        scale = max(sim.energy.kinetic_max, abs(bal["work"]), bal["inserted"])
        assert bal["dissipated"] >= d_prev - 0.02 * scale, bal
        d_prev = bal["dissipated"]
    assert sim.step_count == 1_000_000 and outlet.count > 100 and bal["work"] > 0
    assert dpm.restart(tmp_path / "soak.ckpt.h5").step_count == 1_000_000


def test_many_particles_with_one_radius_each_are_accepted():
    """(The memory check before a large add_particles must not build the shape with the
    parameters of one body: per-particle radii of 1,500 bodies.)"""
    sim = dpm.Simulation(dt=1e-5)
    glass = dpm.Material("glass", **GLASS)
    xyz = dpm.lattice((0, 0, 0), (0.05, 0.05, 0.05), spacing=4e-3)[:1500]
    ids = sim.add_particles("sphere", material=glass, positions=xyz,
                            radius=np.linspace(1e-3, 1.5e-3, len(xyz)))
    assert len(ids) == len(xyz) == 1500 and sim.bodies.radius[-1] == 1.5e-3
