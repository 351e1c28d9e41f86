"""Sums kept whole across call ends (issue #55, item 8): a boundary's work is one running
sum in the kernels, so neither periodic checkpoints nor extra call ends (``run`` split into
pieces, frames) change ``Boundary.work`` by a single bit.

The scene is the small box of tests/io/test_output_ownership.py with a turning paddle in
the bed (the same law and integrator; one boundary kind more).
"""

from __future__ import annotations

import numpy as np
import trimesh

import dpm


def scene() -> dpm.Simulation:
    sim = dpm.Simulation(dt=2e-5, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02),
                     open=("+z",))
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.004), spacing=2.1e-3, jitter=4e-5)
    # a paddle in the bed (the spheres where it stands left out)
    lo, hi = np.array([0.002, 0.0045, 0.0005]), np.array([0.008, 0.0055, 0.0035])
    gap = np.maximum(np.maximum(lo - xyz, xyz - hi), 0.0)
    xyz = xyz[np.linalg.norm(gap, axis=1) > 1.05e-3]
    sim.add_particles("sphere", material=glass, radius=1e-3, positions=xyz)
    paddle = trimesh.creation.box(extents=hi - lo)
    paddle.apply_translation((lo + hi) / 2)
    sim.add_boundary("mesh", material=glass, vertices=paddle.vertices, faces=paddle.faces,
                     motion=dpm.Rotation(axis=(0, 0, 1), center=(0.005, 0.005, 0.0),
                                         rpm=600))
    return sim


def test_boundary_work_does_not_depend_on_call_ends_or_checkpoints(tmp_path):
    one = scene()
    one.run(steps=300, progress=False)
    split = scene()
    split.output(tmp_path / "run.h5", every_steps=7)
    split.checkpoint_every(tmp_path / "run.ckpt.h5", every_steps=23, keep=1)
    for n in (1, 50, 99, 150):
        split.run(steps=n, progress=False)
    split.close()
    assert split.step_count == one.step_count == 300
    work = [bd.work for bd in one.boundaries]
    assert abs(work[1]) > 0.0  # (the paddle drives the spheres)
    assert [bd.work for bd in split.boundaries] == work  # every bit
    # and restarted from its last checkpoint (step 299), the same to the end
    again = dpm.restart(tmp_path / "run.ckpt.h5", output=None)
    again.run(steps=300 - again.step_count, progress=False)
    assert [bd.work for bd in again.boundaries] == work
    np.testing.assert_array_equal(again.bodies.position, one.bodies.position)
