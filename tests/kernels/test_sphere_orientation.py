"""Simulation(sphere_orientation=False): single spheres keep their orientation, and
nothing else changes, bit for bit (no force depends on a sphere's orientation)."""

import numpy as np
import pytest

import dpm
from dpm.errors import ParameterError


def _scene(orient: bool, cubes: bool = False):
    sim = dpm.Simulation(dt=5e-6, gravity=(0, 0, -9.81), sphere_orientation=orient)
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5,
                rolling_friction=0.02)
    sim.add_boundary("plane", material=glass, point=(0, 0, 0), normal=(0, 0, 1))
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.01), 2.1e-3, jitter=5e-5, seed=3)
    rng = np.random.default_rng(2)
    if cubes:
        sim.add_particles("cube", material=glass, positions=xyz, a=1.4e-3, resolution=0.3,
                          angular_velocities=rng.uniform(-50, 50, (len(xyz), 3)))
    else:
        sim.add_particles("sphere", material=glass, positions=xyz, radius=1e-3,
                          velocities=rng.uniform(-0.1, 0.1, (len(xyz), 3)),
                          angular_velocities=rng.uniform(-50, 50, (len(xyz), 3)))
    return sim


def test_untracked_sphere_orientation_changes_nothing_else():
    runs = []
    for orient in (True, False):
        sim = _scene(orient)
        q0 = sim.bodies.orientation.copy()
        sim.run(steps=3000, progress=False)
        assert sim.backend.diag[6] > 10  # spheres touch the plane and each other
        moved = np.abs(sim.bodies.orientation - q0).max()
        assert (moved > 1e-3) if orient else (moved == 0.0)
        runs.append((sim.bodies.position.copy(), sim.bodies.velocity.copy(),
                     sim.bodies.angular_velocity.copy()))
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a, b)


def test_clustered_bodies_rotate_whatever_the_option():
    sim = _scene(False, cubes=True)
    q0 = sim.bodies.orientation.copy()
    sim.run(steps=200, progress=False)
    assert np.abs(sim.bodies.orientation - q0).max() > 1e-4


def test_option_is_validated():
    with pytest.raises(ParameterError, match="sphere_orientation"):
        dpm.Simulation(dt=1e-5, sphere_orientation="no")
