"""Bad input is refused before any step, with a message that names the parameter and value.

Object-level checks raise :class:`dpm.ParameterError` (or its subclass
:class:`dpm.UnknownNameError` for registered names) where the object is built; scene-level
checks raise :class:`dpm.SceneError` at ``sim.run`` before the first step; a run that goes
unstable stops with :class:`dpm.UnstableRunError`.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import dpm

GLASS = dict(density=2500.0, young=5e6, poisson=0.45)
STEEL = dict(density=7800.0, young=2e8, poisson=0.3)
R = 1e-3


@pytest.fixture
def glass():
    return dpm.Material("glass", **GLASS)


@pytest.fixture
def steel():
    return dpm.Material("steel", **STEEL)


@pytest.fixture
def sim(glass):
    s = dpm.Simulation(dt=1e-6)
    s.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return s


def assert_not_started(sim, positions=None):
    """Nothing was stepped: step count and time are zero, positions untouched."""
    assert sim.step_count == 0
    assert sim.time == 0.0
    if positions is not None:
        np.testing.assert_array_equal(sim.bodies.position, positions)


# ------------------------------------------------------------------------- materials


@pytest.mark.parametrize("name, value", [
    ("density", 0.0), ("density", -2500.0), ("young", 0.0), ("young", -5e6),
])
def test_material_refuses_non_positive(name, value):
    kw = dict(GLASS, **{name: value})
    with pytest.raises(dpm.ParameterError,
                       match=re.escape(f"{name}={value:g} is outside (0, inf)")):
        dpm.Material("m", **kw)


@pytest.mark.parametrize("nu", [-1.0, 0.5, -1.5, 0.7])
def test_material_refuses_poisson_outside_open_interval(nu):
    with pytest.raises(dpm.ParameterError, match=rf"poisson={nu:g} is outside \(-1, 0\.5\)"):
        dpm.Material("m", density=2500, young=5e6, poisson=nu)


@pytest.mark.parametrize("nu", [-0.999, 0.0, 0.499])
def test_material_accepts_poisson_inside(nu):
    assert dpm.Material("m", density=2500, young=5e6, poisson=nu).poisson == nu


@pytest.mark.parametrize("name", ["density", "young", "poisson"])
def test_material_refuses_nan(name):
    kw = dict(GLASS, **{name: math.nan})
    with pytest.raises(dpm.ParameterError, match=rf"{name}=nan is NaN"):
        dpm.Material("m", **kw)


def test_material_refuses_unknown_parameter():
    with pytest.raises((TypeError, dpm.ParameterError), match="youngs"):
        dpm.Material("m", density=2500, youngs=5e6)


# ------------------------------------------------------------------------- simulation


@pytest.mark.parametrize("dt", [0.0, -1e-6])
def test_simulation_refuses_non_positive_dt(dt):
    with pytest.raises(dpm.ParameterError, match=rf"dt={dt:g} is outside \(0, inf\)"):
        dpm.Simulation(dt=dt)


def test_simulation_refuses_nan_dt_and_gravity():
    with pytest.raises(dpm.ParameterError, match="dt=nan is NaN"):
        dpm.Simulation(dt=math.nan)
    with pytest.raises(dpm.ParameterError, match="gravity=.*nan.* contains NaN"):
        dpm.Simulation(dt=1e-6, gravity=(0.0, 0.0, math.nan))
    with pytest.raises(dpm.ParameterError, match="gravity=.* must be a 3-vector"):
        dpm.Simulation(dt=1e-6, gravity=(0.0, -9.81))


def test_unknown_integrator_lists_registered_names():
    with pytest.raises(dpm.UnknownNameError, match="leapfrog") as info:
        dpm.Simulation(dt=1e-6, integrator="leapfrog")
    msg = str(info.value)
    assert "integrator" in msg
    assert "velocity_verlet" in msg and "symplectic_euler" in msg
    assert isinstance(info.value, dpm.ParameterError)


def test_unknown_dt_check_refused():
    with pytest.raises(dpm.ParameterError, match="dt_check='sometimes'"):
        dpm.Simulation(dt=1e-6, dt_check="sometimes")


def test_simulation_refuses_unknown_parameter():
    with pytest.raises((TypeError, dpm.ParameterError), match="timestep"):
        dpm.Simulation(dt=1e-6, timestep=1e-6)


# ------------------------------------------------------------------------- contact laws


def test_unknown_model_lists_registered_names(glass):
    s = dpm.Simulation(dt=1e-6)
    with pytest.raises(dpm.UnknownNameError, match="'hertz'") as info:
        s.contact(glass, glass, model="hertz", restitution=0.5)
    msg = str(info.value)
    assert "impact model" in msg
    assert "hertz_mindlin" in msg and "linear_spring_dashpot" in msg
    assert isinstance(info.value, dpm.ParameterError)


@pytest.mark.parametrize("e", [0.0, -0.5, 1.01, 2.0])
@pytest.mark.parametrize("model", ["hertz_mindlin", "linear_spring_dashpot"])
def test_restitution_outside_0_1_refused(glass, model, e):
    s = dpm.Simulation(dt=1e-6)
    kw = {"stiffness": 1e3} if model == "linear_spring_dashpot" else {}
    with pytest.raises(dpm.ParameterError, match=rf"restitution={e:g} is outside \(0, 1\]"):
        s.contact(glass, glass, model=model, restitution=e, **kw)


@pytest.mark.parametrize("model", ["hertz_mindlin", "linear_spring_dashpot"])
def test_restitution_one_accepted(glass, model):
    s = dpm.Simulation(dt=1e-6)
    kw = {"stiffness": 1e3} if model == "linear_spring_dashpot" else {}
    s.contact(glass, glass, model=model, restitution=1.0, **kw)


def test_contact_refuses_nan_and_negative_parameters(glass):
    s = dpm.Simulation(dt=1e-6)
    with pytest.raises(dpm.ParameterError, match="restitution=nan is NaN"):
        s.contact(glass, glass, restitution=math.nan)
    with pytest.raises(dpm.ParameterError, match=r"friction=-0.1 is outside \[0, inf\)"):
        s.contact(glass, glass, friction=-0.1)
    with pytest.raises(dpm.ParameterError, match=r"stiffness=0 is outside \(0, inf\)"):
        s.contact(glass, glass, model="linear_spring_dashpot", stiffness=0.0)
    with pytest.raises(dpm.ParameterError, match="stiffness=nan is NaN"):
        s.contact(glass, glass, model="linear_spring_dashpot", stiffness=math.nan)
    with pytest.raises(dpm.ParameterError, match="stiffness is required"):
        s.contact(glass, glass, model="linear_spring_dashpot")


def test_contact_refuses_unknown_parameter(glass):
    s = dpm.Simulation(dt=1e-6)
    with pytest.raises(dpm.ParameterError,
                       match=r"unknown parameter restitutoin=0.5; allowed: .*restitution"):
        s.contact(glass, glass, model="hertz_mindlin", restitutoin=0.5)


def test_hertz_needs_elastic_constants():
    s = dpm.Simulation(dt=1e-6)
    soft = dpm.Material("soft", density=1000.0)
    with pytest.raises(dpm.ParameterError, match=r"needs young and poisson.*soft\.young"):
        s.contact(soft, soft, model="hertz_mindlin")


# ------------------------------------------------------------------------- boundaries


def test_boundary_refuses_unknown_kind_and_parameter(glass):
    s = dpm.Simulation(dt=1e-6)
    with pytest.raises(dpm.UnknownNameError, match=r"'cylinder'.*registered: .*box.*plane"):
        s.add_boundary("cylinder", material=glass)
    with pytest.raises(dpm.ParameterError, match=r"unknown parameter nromal=.*allowed: .*normal"):
        s.add_boundary("plane", material=glass, nromal=(0, 0, 1))
    with pytest.raises(dpm.ParameterError, match=r"normal=.* must not be zero"):
        s.add_boundary("plane", material=glass, normal=(0, 0, 0))
    with pytest.raises(dpm.ParameterError, match=r"point=.*nan.* contains NaN"):
        s.add_boundary("plane", material=glass, point=(0, math.nan, 0))
    with pytest.raises(dpm.ParameterError, match=r"upper=.* must exceed lower"):
        s.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(1, 0, 1))


# ------------------------------------------------------------------------- particles


@pytest.mark.parametrize("radius", [0.0, -1e-3])
def test_particles_refuse_non_positive_radius(sim, glass, radius):
    with pytest.raises(dpm.ParameterError, match=rf"radius={radius:g} is outside \(0, inf\)"):
        sim.add_particles("sphere", material=glass, radius=radius, positions=[(0, 0, 0)])
    assert len(sim.bodies) == 0


def test_particles_refuse_bad_radius_in_array(sim, glass):
    with pytest.raises(dpm.ParameterError, match=r"radius=-0.002 \(item 1\) is outside"):
        sim.add_particles("sphere", material=glass, radius=[1e-3, -2e-3],
                          positions=[(0, 0, 0), (1, 0, 0)])
    with pytest.raises(dpm.ParameterError, match=r"radius=.*nan.* is NaN"):
        sim.add_particles("sphere", material=glass, radius=[1e-3, math.nan],
                          positions=[(0, 0, 0), (1, 0, 0)])
    assert len(sim.bodies) == 0


@pytest.mark.parametrize("field", ["positions", "velocities", "angular_velocities"])
@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_particles_refuse_nan_and_inf(sim, glass, field, bad):
    arrays = {"positions": np.zeros((3, 3)), "velocities": np.zeros((3, 3)),
              "angular_velocities": np.zeros((3, 3))}
    arrays["positions"][:, 0] = [0.0, 0.01, 0.02]
    arrays[field][2, 1] = bad
    with pytest.raises(dpm.ParameterError, match=rf"{field} contains NaN or inf \(row 2\)"):
        sim.add_particles("sphere", material=glass, radius=R, **arrays)
    assert len(sim.bodies) == 0


def test_particles_refuse_wrong_shapes_and_unknown_parameters(sim, glass):
    with pytest.raises(dpm.ParameterError, match=r"positions has shape \(2, 2\)"):
        sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0), (1, 1)])
    with pytest.raises(dpm.ParameterError, match=r"velocities has shape \(1, 3\)"):
        sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0), (1, 0, 0)],
                          velocities=[(0, 0, 0)])
    with pytest.raises(dpm.ParameterError, match=r"unknown parameter radiuss=.*allowed: radius"):
        sim.add_particles("sphere", material=glass, radius=R, radiuss=R, positions=[(0, 0, 0)])
    with pytest.raises(dpm.UnknownNameError, match=r"'dodecahedron'.*registered: .*sphere"):
        sim.add_particles("dodecahedron", material=glass, radius=R, positions=[(0, 0, 0)])
    with pytest.raises(dpm.ParameterError, match="orientations has a zero quaternion"):
        sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0)],
                          orientations=[(0, 0, 0, 0)])
    assert len(sim.bodies) == 0


def test_nan_written_into_state_refused_at_run(sim, glass):
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0), (0.01, 0, 0)])
    sim.bodies.velocity[1, 2] = math.nan
    with pytest.raises(dpm.SceneError, match=r"velocity is NaN or inf for particle id\(s\) 1"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim)


# ------------------------------------------------------------------------- scene checks


def test_initial_overlap_beyond_tolerance_refused(sim, glass):
    x = np.array([(0.0, 0.0, 0.0), (1.9e-3, 0.0, 0.0), (0.01, 0.0, 0.0)])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.SceneError,
                       match=r"initial overlap.*particles 0 and 1 overlap by 0\.1 of the radius"):
        sim.run(steps=10, progress=False)
    assert_not_started(sim, x)


def test_initial_overlap_within_tolerance_accepted(glass):
    sim = dpm.Simulation(dt=1e-6, overlap_tolerance=0.01)
    sim.contact(glass, glass, restitution=0.5)
    sim.add_particles("sphere", material=glass, radius=R,
                      positions=[(0, 0, 0), (2 * R - 0.005 * R, 0, 0)])
    sim.run(steps=1, progress=False)
    assert sim.step_count == 1


def test_initial_overlap_tolerance_is_a_parameter(glass):
    sim = dpm.Simulation(dt=1e-6, overlap_tolerance=0.001)
    sim.contact(glass, glass, restitution=0.5)
    x = np.array([(0.0, 0.0, 0.0), (2 * R - 0.005 * R, 0.0, 0.0)])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.SceneError, match=r"overlap_tolerance=0\.001.*0\.005 of the radius"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim, x)


def test_initial_wall_overlap_beyond_tolerance_refused(sim, glass):
    sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
    x = np.array([(0.0, 0.0, 0.5 * R)])  # centre inside, half the sphere in the wall
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.SceneError, match="overlap"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim, x)


def test_particle_outside_plane_refused(sim, glass):
    sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
    x = np.array([(0.0, 0.0, 0.01), (0.0, 0.01, -0.01), (0.01, 0.0, 0.01)])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.SceneError,
                       match=r"1 particle\(s\) lie outside boundary 0 \(plane\): id\(s\) 1"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim, x)


def test_particle_outside_box_refused(sim, glass):
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.01))
    x = np.array([(0.005, 0.005, 0.005), (0.005, 0.02, 0.005), (-0.003, 0.005, 0.005)])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.SceneError,
                       match=r"2 particle\(s\) lie outside boundary 0 \(box\): id\(s\) 1, 2"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim, x)


def test_missing_contact_law_between_particle_materials(sim, glass, steel):
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0)])
    # (two steel bodies: one alone could not meet another of its material)
    sim.add_particles("sphere", material=steel, radius=R, positions=[(0.01, 0, 0),
                                                                      (0.02, 0, 0)])
    with pytest.raises(dpm.SceneError, match=r"no contact law for material pair\(s\) "
                                             r"glass-steel, steel-steel; set them with "
                                             r"sim\.contact"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim)
    # once the laws are given, the same scene runs
    sim.contact(glass, steel, restitution=0.5)
    sim.contact(steel, steel, restitution=0.5)
    sim.run(steps=2, progress=False)
    assert sim.step_count == 2


def test_missing_contact_law_with_a_wall(sim, glass, steel):
    sim.add_boundary("plane", material=steel, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0.01)])
    with pytest.raises(dpm.SceneError, match=r"no contact law .*glass-steel \(plane\)"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim)


def test_empty_scene_refused(sim):
    with pytest.raises(dpm.SceneError, match="no particles"):
        sim.run(steps=1, progress=False)
    assert_not_started(sim)


def test_run_arguments_checked(sim, glass):
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0)])
    with pytest.raises(dpm.ParameterError, match="exactly one of steps or until"):
        sim.run(progress=False)
    with pytest.raises(dpm.ParameterError, match="exactly one of steps or until"):
        sim.run(steps=1, until=1.0, progress=False)
    with pytest.raises(dpm.ParameterError, match=r"steps=-1 is outside \[0, inf\)"):
        sim.run(steps=-1, progress=False)
    assert_not_started(sim)


# ------------------------------------------------------------------------- time step


def _rayleigh(radius, density, young, poisson):
    """Rayleigh-wave time step pi R sqrt(rho/G) / (0.1631 nu + 0.8766) (Li et al. 2005)."""
    shear = young / (2 * (1 + poisson))
    return math.pi * radius * math.sqrt(density / shear) / (0.1631 * poisson + 0.8766)


def _cutoff_linear_contact_time(e, meff, k):
    """Contact time of the cut-off linear spring-dashpot with restitution e (own solve)."""
    from scipy.optimize import brentq

    def closed(z):
        w = math.sqrt(1 - z * z)
        tc = (math.pi - 2 * math.atan(z / w)) / w
        return tc, math.exp(-z * tc)

    zeta = brentq(lambda z: math.log(closed(z)[1]) - math.log(e), 1e-12, 1 - 1e-12,
                  xtol=1e-15)
    return closed(zeta)[0] / math.sqrt(k / meff)


def test_dt_above_rayleigh_refused(glass):
    rayleigh = _rayleigh(R, **GLASS)
    dt = 2.0 * rayleigh
    sim = dpm.Simulation(dt=dt)
    sim.contact(glass, glass, restitution=0.5)
    x = np.array([(0.0, 0.0, 0.0)])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.ParameterError, match="time step too large") as info:
        sim.run(steps=1, progress=False)
    msg = str(info.value)
    assert f"dt={dt:g} s is 2.00 of the Rayleigh time step {rayleigh:.3g} s" in msg
    assert "dt_check='warn'" in msg
    assert_not_started(sim, x)


def test_dt_above_contact_time_refused(glass):
    k, e = 1e3, 0.5
    m = 4 / 3 * math.pi * R**3 * GLASS["density"]
    tc = _cutoff_linear_contact_time(e, m / 2, k)
    dt = tc / 2  # 2 steps per contact (at least 5 are required)
    sim = dpm.Simulation(dt=dt)
    sim.contact(glass, glass, model="linear_spring_dashpot", stiffness=k, restitution=e)
    x = np.array([(0.0, 0.0, 0.0), (0.01, 0.0, 0.0)])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.ParameterError, match="time step too large") as info:
        sim.run(steps=1, progress=False)
    msg = str(info.value)
    assert re.search(rf"shortest contact \(glass-glass, {tc:.3g} s .*\) with 2(\.0*)? steps", msg)
    assert f"critical dt = {tc / 5:.3g} s" in msg
    assert "Rayleigh" not in msg  # the linear law has no elastic constants to check
    assert_not_started(sim, x)


def test_dt_check_warn_runs_with_a_warning(glass):
    rayleigh = _rayleigh(R, **GLASS)
    sim = dpm.Simulation(dt=0.5 * rayleigh, dt_check="warn")
    sim.contact(glass, glass, restitution=0.5)
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0)])
    with pytest.warns(UserWarning, match=rf"0\.50 of the Rayleigh time step {rayleigh:.3g} s"):
        sim.run(steps=3, progress=False)
    assert sim.step_count == 3


def test_unstable_run_stops_with_error_not_nan(glass):
    """dt_check='off' and dt ~ 8 Rayleigh steps: a stack in a box explodes. The run stops
    with UnstableRunError naming the step and the time-step numbers; the state stays
    finite and the step count is a finite number smaller than asked."""
    sim = dpm.Simulation(dt=1e-3, gravity=(0, 0, -9.81), dt_check="off")
    sim.contact(glass, glass, restitution=0.9)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.01))
    grid = np.arange(3) * 2.2e-3 + 1.5e-3
    x = np.array([(i, j, k) for i in grid for j in grid for k in grid])
    sim.add_particles("sphere", material=glass, radius=R, positions=x)
    with pytest.raises(dpm.UnstableRunError,
                       match=r"unstable run at step \d+ .*dt = 0\.001 s.*Rayleigh step") as info:
        sim.run(steps=100_000, progress=False)
    assert isinstance(sim.step_count, int)
    assert 0 < sim.step_count < 100_000
    assert f"at step {sim.step_count} " in str(info.value)
    assert np.all(np.isfinite(sim.bodies.position))
    assert np.all(np.isfinite(sim.bodies.velocity))
    assert math.isfinite(sim.time)


def test_unstable_head_on_collision_stops(glass):
    """A stiff linear contact stepped 45 times coarser than its duration."""
    sim = dpm.Simulation(dt=1e-3, dt_check="off")
    sim.contact(glass, glass, model="linear_spring_dashpot", stiffness=1e5, restitution=0.9)
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0, 0, 0), (2.001e-3, 0, 0)],
                      velocities=[(0.5, 0, 0), (-0.5, 0, 0)])
    with pytest.raises(dpm.UnstableRunError, match="unstable run at step"):
        sim.run(steps=1000, progress=False)
    assert 0 < sim.step_count < 1000
    assert np.all(np.isfinite(sim.bodies.position))


@pytest.mark.parametrize("block", [2, 1 << 16])
def test_speed_check_names_the_fastest_body_in_any_block(glass, monkeypatch, block):
    """After each kernel call the fastest body is found block by block; a body that moves
    more than half its radius per step stops the run with its id and the largest safe dt."""
    from dpm import diagnosis

    monkeypatch.setattr(diagnosis, "SPEED_BLOCK", block)
    sim = dpm.Simulation(dt=1e-4, gravity=(0, 0, 0), dt_check="off")
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.3)
    pos = [(0, 0, 0), (0.01, 0, 0), (0.02, 0, 0), (0.03, 0, 0), (0.04, 0, 0)]
    vel = np.zeros((5, 3))
    vel[1, 1] = 2.0  # 0.2 mm per step: slower than half a radius
    vel[3, 2] = -9.0  # 0.9 mm per step against a 1 mm radius: the fastest, in block 2
    ids = sim.add_particles("sphere", material=glass, radius=1e-3, positions=pos,
                            velocities=vel)
    with pytest.raises(dpm.UnstableRunError, match=rf"particle {ids[3]} moves 0\.0009 m"):
        sim.run(steps=1, progress=False)
