"""Clustered shapes in the engine: a torus resting in a corner, a cylinder rolling down an
incline at the analytic acceleration of a solid cylinder."""

import math

import numpy as np
import pytest

import dpm

G = 9.81


def _material():
    return dpm.Material("glass", density=2500, young=5e6, poisson=0.45)


def test_torus_rests_in_a_corner_on_several_elements():
    m = _material()
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -G))
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    floor = sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    wall = sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(1, 0, 1e-9))
    tilt = math.radians(60)  # ring plane tilted: it falls against the wall
    q = [math.cos(tilt / 2), 0.0, math.sin(tilt / 2), 0.0]
    sim.add_particles("torus", material=m, r1=0.5e-3, r2=1.5e-3, positions=[[2.2e-3, 0, 2.2e-3]],
                      orientations=[q])
    sim.run(until=0.25, progress=False)
    weight = sim.bodies.mass[0] * G
    total = floor.force + wall.force
    np.testing.assert_allclose(total, [0, 0, -weight], atol=1e-2 * weight)
    assert int(sim.backend.diag[6]) >= 2  # leaning: elements touch the floor and the wall
    assert wall.force[0] < -1e-3 * weight  # the wall carries part of the load
    # it may still creep along the wall (a leaning ring can roll sideways), but slowly
    assert np.linalg.norm(sim.bodies.velocity[0]) < 1e-2


def test_torus_falls_flat_and_lies_on_its_ring():
    m = _material()
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -G))
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    floor = sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(1, 0, 0))
    tilt = math.radians(8)
    q = [math.cos(tilt / 2), math.sin(tilt / 2), 0.0, 0.0]
    sim.add_particles("torus", material=m, r1=0.5e-3, r2=1.5e-3, positions=[[2.5e-3, 0, 1e-3]],
                      orientations=[q])
    sim.run(until=0.2, progress=False)
    weight = sim.bodies.mass[0] * G
    np.testing.assert_allclose(floor.force, [0, 0, -weight], atol=1e-2 * weight)
    assert int(sim.backend.diag[6]) >= 3  # lies on several elements of its ring
    axis = dpm.measures.to_body(sim.bodies.orientation * [1, -1, -1, -1],
                                   np.array([[0.0, 0.0, 1.0]]))[0]
    assert abs(axis[2]) > 0.999  # the ring's symmetry axis is vertical


@pytest.mark.parametrize("resolution, tol", [(0.6, 0.03), (1.0, 0.02)])
def test_cylinder_rolls_down_an_incline_like_a_solid_cylinder(resolution, tol):
    """Rolling without slipping: a = 2/3 g sin(theta), so v = sqrt(4 g h / 3).

    The cluster's mass and inertia are the solid's (I = m r^2 / 2 about the axis); what
    differs is its bumpy surface: the elements' envelope deviates from the cylinder by a
    few per cent of r (dpm shapes cylinder), so the rolling radius and the contact
    point oscillate as it rolls and the damping takes a little energy at each bump. The
    tolerance is the surface RMS deviation at that resolution (2.2 % at 0.6, 0.5 % at 1.0)
    rounded up.
    """
    m = _material()
    theta = math.radians(15)
    sim = dpm.Simulation(dt=2e-6, gravity=(G * math.sin(theta), 0, -G * math.cos(theta)))
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.8)
    sim.add_boundary("plane", material=m)
    r = 1e-3
    axis_y = [math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)]  # shape x axis -> world y
    sim.add_particles("cylinder", material=m, r=r, l=3e-3, resolution=resolution,
                      positions=[[0, 0, r]], orientations=[axis_y])
    sim.run(until=0.01, progress=False)  # settle onto the plane and start rolling
    t0, x0 = sim.time, sim.bodies.position[0, 0]
    v0 = sim.bodies.velocity[0, 0]
    sim.run(until=0.06, progress=False)
    dt_run = sim.time - t0
    a = 2 * (sim.bodies.position[0, 0] - x0 - v0 * dt_run) / dt_run**2
    expected = 2 / 3 * G * math.sin(theta)
    assert a == pytest.approx(expected, rel=tol)
    # rolling, not sliding: omega r matches v (sliding would give a = g sin(theta))
    w = sim.bodies.angular_velocity[0, 1]
    assert w * r == pytest.approx(sim.bodies.velocity[0, 0], rel=0.05)
