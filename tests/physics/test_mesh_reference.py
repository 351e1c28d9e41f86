"""The mesh contact path against a brute-force reference (dpm.testing.mesh_reference) on
meshes whose edges and vertices are touched, over thousands of steps.

The kernels' path (boundary list, face test by dual vectors, distance bound, mesh rules
called only where they have work, history hand-over) must count, at every checked step,
the same contacts as every element against every triangle with trimesh's closest point
and the same rules written over sets. Scenes: an open-top container with an inclined inner
chute plate and a tent-shaped ridge on its floor (concave corners and vertices, convex
ridge and rim edges, the chute's open edges, both sides of the plate); a W-shaped trough
(a convex ridge between two concave folds) with a sphere rolled across the ridge into a
fold. The law and integrator are the meshGran port's (tests/physics/test_meshgran_port.py), so the
step module is shared.
"""

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

import dpm  # noqa: E402
from dpm.testing.mesh_reference import compare  # noqa: E402

R = 0.004


def _quad(a, b, c, d):
    return trimesh.Trimesh(vertices=[a, b, c, d], faces=[[0, 1, 2], [0, 2, 3]],
                           process=False)


def container_with_chute() -> trimesh.Trimesh:
    """Open-top box 0.2 x 0.06 x 0.15 m (shared vertices: concave floor corners, convex
    rim), a tent ridge on the floor and an inclined plate (the inner chute) inside."""
    x1, y1, z1 = 0.2, 0.06, 0.15
    box = trimesh.creation.box(extents=(x1, y1, z1))
    box.apply_translation((x1 / 2, y1 / 2, z1 / 2))
    top = np.flatnonzero(box.face_normals[:, 2] > 0.5)
    box.update_faces(np.setdiff1d(np.arange(len(box.faces)), top))
    box.remove_unreferenced_vertices()
    ridge = trimesh.Trimesh(
        vertices=[(0.07, 0.0, 0.0), (0.10, 0.0, 0.025), (0.13, 0.0, 0.0),
                  (0.07, y1, 0.0), (0.10, y1, 0.025), (0.13, y1, 0.0)],
        faces=[[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]], process=False)
    chute = _quad((0.02, 0.008, 0.12), (0.12, 0.008, 0.085), (0.12, 0.052, 0.085),
                  (0.02, 0.052, 0.12))
    return trimesh.util.concatenate([box, ridge, chute])


def w_trough() -> trimesh.Trimesh:
    """A W profile extruded along y: concave folds at x = -0.03 and 0.03, a convex ridge
    at x = 0."""
    prof = [(-0.1, 0.05), (-0.03, 0.0), (0.0, 0.012), (0.03, 0.0), (0.1, 0.05)]
    parts = [_quad((xa, -0.03, za), (xb, -0.03, zb), (xb, 0.03, zb), (xa, 0.03, za))
             for (xa, za), (xb, zb) in zip(prof[:-1], prof[1:], strict=True)]
    return trimesh.util.concatenate(parts)


def _scene(mesh: trimesh.Trimesh, side: str = "both"):
    sim = dpm.Simulation(dt=5e-5, gravity=(0.0, 0.0, -9.81), sphere_orientation=False)
    m = dpm.Material("beads", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(m, m, model="maw_linear_spring", restitution=0.7, friction=0.05,
                impact_velocity=2.0, tangential_stiffness_ratio=1.0)
    sim.add_boundary("mesh", material=m, vertices=np.asarray(mesh.vertices),
                     faces=np.asarray(mesh.faces), side=side)
    return sim, m


def _run_checked(sim, steps: int, every: int, counts: dict) -> list:
    bad = []
    for _ in range(steps // every):
        sim.run(steps=every, progress=False)
        found = compare(sim, counts=counts)
        bad += [(sim.step_count, *b) for b in found]
    return bad


def test_container_with_inner_chute_against_brute_force():
    """80 spheres thrown into the container over the chute, 8,000 steps, checked every 4
    steps: the kernels count exactly the reference's contacts (distances and closest
    points to 1e-9), edge and vertex contacts included."""
    sim, m = _scene(container_with_chute())
    rng = np.random.default_rng(3)
    pos = np.column_stack([rng.uniform(0.015, 0.185, 80), rng.uniform(0.006, 0.054, 80),
                           rng.uniform(0.13, 0.22, 80)])
    keep = [0]
    for k in range(1, 80):  # no initial overlaps
        if np.all(np.linalg.norm(pos[keep] - pos[k], axis=1) > 2.2 * R):
            keep.append(k)
    vel = np.column_stack([rng.uniform(-0.4, 0.4, (len(keep), 2)), np.zeros(len(keep))])
    sim.add_particles("sphere", material=m, radius=R, positions=pos[keep], velocities=vel)
    counts: dict = {}
    bad = _run_checked(sim, 8000, 4, counts)
    assert not bad, bad[:3]
    # the scene touches what it is meant to: faces, and edges or vertices that count
    assert counts.get("face", 0) > 1000 and counts.get("edge or vertex", 0) > 50, counts


def test_sphere_across_ridge_into_fold_against_brute_force():
    """A sphere rolled from the left wing of the W trough over the convex ridge and into
    the right fold, with a second sphere dropped onto the ridge's top edge, every step
    checked for 6,000 steps; and the check can fail: against flags that mark every edge
    and vertex inactive, the same run disagrees."""
    sim, m = _scene(w_trough())
    sim.add_particles("sphere", material=m, radius=R,
                      positions=[(-0.06, 0.0, 0.0271 + R), (0.0, 0.01, 0.05)],
                      velocities=[(1.0, 0.0, 0.0), (0.0, 0.0, 0.0)])
    counts: dict = {}
    bad = _run_checked(sim, 6000, 1, counts)
    assert not bad, bad[:3]
    assert counts.get("edge or vertex", 0) > 20, counts
    # the comparison sees a wrong rule: all features inactive in the reference
    sim2, m2 = _scene(w_trough())
    sim2.add_particles("sphere", material=m2, radius=R, positions=[(0.0, 0.01, 0.05)],
                       velocities=[(0.0, 0.0, 0.0)])
    mismatches = 0
    for _ in range(300):
        sim2.run(steps=10, progress=False)
        tri_flags = np.zeros(len(sim2.walls.ids), np.int64)
        mismatches += len(compare(sim2, flags=tri_flags))
    assert mismatches > 0


def test_fold_hit_from_behind():
    """A two-sided mesh touched from behind: a sphere thrown up at the W trough's fold
    from below (the fold is concave from the front, convex from behind) bounces off the
    fold's edge. Before the back side had its own feature flags, the edge contact was left
    to the faces, neither of which the centre lay over: the sphere went in to its centre
    (overlap 1 r). Undamped bound of the overlap at 0.5 m/s: v sqrt(m/k); every step is
    checked against the brute-force reference."""
    sim, m = _scene(w_trough())
    sim.gravity = (0.0, 0.0, 0.0)
    sim.add_particles("sphere", material=m, radius=R, positions=[(-0.03, 0.0, -0.02)],
                      velocities=[(0.0, 0.0, 0.5)])
    counts: dict = {}
    top = -1.0
    for _ in range(1200):
        sim.run(steps=1, progress=False)
        top = max(top, float(sim.bodies.position[0, 2]))
        assert not compare(sim, counts=counts)
    mass = float(sim.bodies.mass[0])
    kn = sim._contacts[(0, 0)].stiffness(m, m, mass, R, 2.0)
    bound = 0.5 * np.sqrt(mass / kn)
    assert counts.get("edge or vertex", 0) > 10
    assert -R < top <= -R + 1.01 * bound, (top, -R + bound)
    assert sim.bodies.velocity[0, 2] < 0.0  # it came back down
