"""Owned and ghost ranges: the last ``bodies.ghosts`` rows are copies of bodies owned by
another process (an MPI backend's halo). Their elements take part in the contacts, they are
not integrated, and their force rows hold what they received, to be handed back."""

from __future__ import annotations

import numpy as np
import pytest

import dpm
from dpm.backends import CpuBackend, step_by_parts

R = 1e-3


def _pair(force_pass: str):
    sim = dpm.Simulation(dt=1e-6, gravity=(0, 0, 0), device=CpuBackend(threads=1,
                                                                        force_pass=force_pass))
    g = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(g, g, model="hertz_mindlin", restitution=0.5, friction=0.3)
    sim.add_particles("sphere", material=g, radius=R,
                      positions=[(0, 0, 0), (2.001 * R, 0.3 * R, 0), (0, 5 * R, 0)],
                      velocities=[(0.2, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, -0.1, 0.0)])
    sim.run(steps=0, progress=False)
    return sim


@pytest.mark.parametrize("force_pass", ["auto", "two_pass"])
def test_ghosts_are_not_integrated_and_collect_what_they_receive(force_pass):
    sim = _pair(force_pass)
    sim.bodies.ghosts = 1  # row 2 is a ghost: far from the others, it must not move
    sim.bodies.position[2] = (2.001 * R, -2.4 * R, 0)  # touching nothing yet
    x_ghost = sim.bodies.position[2].copy()
    v_ghost = sim.bodies.velocity[2].copy()
    # rows 0 and 1 collide; then body 1 is moved into contact with the ghost
    sim.run(steps=400, progress=False)
    np.testing.assert_array_equal(sim.bodies.position[2], x_ghost)
    np.testing.assert_array_equal(sim.bodies.velocity[2], v_ghost)
    assert sim.bodies.velocity[0, 0] < 0.2  # the owned bodies did collide
    assert sim.bodies.velocity[1, 0] > 0.0
    # a ghost touching an owned body: its force row is the exact opposite of the owned one's
    sim.bodies.ghosts = 2  # rows 1 and 2 ghosts now
    sim.bodies.position[1] = sim.bodies.position[0] + (1.99 * R, 0, 0)
    sim.bodies.velocity[1] = 0.0
    sim.backend.rebuild()
    for _ in range(5):
        assert step_by_parts(sim.backend, sim.dt) == 0
    f0, f1 = sim.bodies.force[0], sim.bodies.force[1]
    assert f0[0] < 0.0
    np.testing.assert_array_equal(f1, -f0)


def test_ghost_rows_stay_last_when_permuting():
    sim = _pair("auto")
    sim.bodies.ghosts = 1
    with pytest.raises(dpm.ParameterError, match="ghost"):
        sim.permute([2, 0, 1])
    sim.permute([1, 0, 2])
    assert list(sim.bodies.id) == [1, 0, 2]
