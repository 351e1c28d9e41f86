"""The Backend protocol: the CPU backend satisfies it, its parts give the bits of its fast
many-steps form, and a backend is chosen by name or passed as an instance."""

from __future__ import annotations

import numpy as np
import pytest

import dpm
from dpm.backends import Backend, CpuBackend, step_by_parts

R = 1e-3


def _scene(device="cpu", n=60):
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -9.81), device=device)
    g = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(g, g, model="hertz_mindlin", restitution=0.4, friction=0.5)
    sim.add_boundary("box", material=g, lower=(0, 0, 0), upper=(0.01, 0.01, 0.03),
                     open=("+z",))
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.01), spacing=2.05 * R, jitter=2e-5, seed=1)[:n]
    rng = np.random.default_rng(0)
    sim.add_particles("sphere", material=g, radius=R, positions=xyz,
                      velocities=rng.uniform(-0.2, 0.2, xyz.shape))
    return sim


def test_cpu_backend_satisfies_the_protocol():
    sim = _scene()
    assert isinstance(sim.backend, CpuBackend) and isinstance(sim.backend, Backend)
    assert "cpu" in dpm.registry().names("backend")


@pytest.mark.parametrize("force_pass", ["auto", "two_pass"])
def test_stepping_by_parts_gives_the_bits_of_the_fast_form(force_pass):
    steps = 1500
    fast = _scene(CpuBackend(force_pass=force_pass))
    fast.run(steps=steps, progress=False)
    parts = _scene(CpuBackend(force_pass=force_pass))
    parts.run(steps=0, progress=False)  # plan, prime the forces
    for _ in range(steps):
        assert step_by_parts(parts.backend, parts.dt) == 0
    assert fast.rebuild_count > 1 and fast.contact_count() > 20
    for name in ("position", "velocity", "angular_velocity", "orientation", "force",
                 "torque"):
        np.testing.assert_array_equal(getattr(parts.bodies, name),
                                      getattr(fast.bodies, name))
    np.testing.assert_array_equal(parts.backend.boundary_loads(),
                                  fast.backend.boundary_loads())
    assert parts.contact_count() == fast.contact_count()


def test_reductions():
    sim = _scene()
    sim.run(steps=200, progress=False)
    k, v = sim.backend.max_speed()
    speeds = np.linalg.norm(sim.bodies.velocity, axis=1)
    assert k == int(np.argmax(speeds)) and v == pytest.approx(speeds.max(), rel=1e-15)
    assert sim.backend.nan_count() == 0
    worst, el = sim.backend.max_overlap()
    assert 0 < worst < 0.1 and 0 <= el < len(sim.elements)
    np.testing.assert_allclose(sim.backend.boundary_loads()[0, :3], sim.boundaries[0].force)


def test_unknown_backend_is_refused_with_the_registered_names():
    with pytest.raises(dpm.UnknownNameError, match="backend 'gpu9'.*cpu"):
        dpm.Simulation(dt=1e-5, device="gpu9")
    with pytest.raises(dpm.ParameterError, match="device="):
        dpm.Simulation(dt=1e-5, device=3)
    with pytest.raises(dpm.ParameterError, match="force_pass"):
        CpuBackend(force_pass="fast")
