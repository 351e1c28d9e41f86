"""Stream insertion through a face (LIGGGHTS' ``fix insert/stream``).

References: the requested count and mass (rate x time, exact or within one body); each
body starts in the slab behind the face (depth r to r + |v.n| every) with its projection
on the face and the carrying velocity; no initial overlaps; a carried body moves at
constant velocity (infinite mass) and, once released at the face, follows free flight
x = x_c + v (t - t_c) + g (t - t_c)^2 / 2 exactly (velocity Verlet is exact at constant
acceleration).
"""

import numpy as np
import pytest

import dpm
from dpm.errors import ParameterError

G = 9.81


def scene(dt=2e-5):
    m = dpm.Material("steel", density=7800.0, young=2e8, poisson=0.3)
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, -G), dt_check="off")
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.guards.escape = "off"  # (no walls: the stream falls freely)
    return sim, m


FACE = dict(corner=(0.0, 0.0, 0.5), edge1=(0.05, 0.0, 0.0), edge2=(0.0, 0.05, 0.0))


def test_bodies_start_behind_the_face_with_the_velocity_and_no_overlap():
    sim, m = scene()
    face = dpm.RectangleFace(**FACE)
    v = np.array([0.2, 0.0, -1.0])
    inlet = sim.add_inlet(face, m, rate=2000.0, radius=(2e-3, 3e-3), velocity=v,
                          every=0.01, seed=4)
    assert np.allclose(inlet.direction, (0, 0, -1))
    assert inlet.extrude_length == pytest.approx(0.01)
    sim.run(steps=1, progress=False)
    b = sim.bodies
    assert inlet.inserted == len(b) == 20  # rate x every, placed in one event
    x0 = b.position - b.velocity * sim.dt  # (carried: constant velocity)
    np.testing.assert_allclose(b.velocity, np.tile([0, 0, -1.0], (len(b), 1)))
    assert np.all(b.invmass == 0) and np.all(b.angular_velocity == 0)
    depth = x0[:, 2] - 0.5
    assert np.all(depth >= b.radius - 1e-12)
    assert np.all(depth <= b.radius + inlet.extrude_length + 1e-12)
    assert np.all(face.on_face(x0))
    d = np.linalg.norm(x0[:, None] - x0[None], axis=2) + np.eye(len(b))
    assert np.all(d >= (b.radius[:, None] + b.radius[None]) * (1 - 1e-12))


def test_count_and_free_flight_after_the_face():
    sim, m = scene()
    face = dpm.RectangleFace(**FACE)
    r, vz = 2e-3, -1.0
    inlet = sim.add_inlet(face, m, rate=500.0, radius=r, velocity=(0, 0, vz), every=0.01,
                          stop=0.1, seed=1)
    sim.run(steps=1, progress=False)  # the first event: what 0 to 0.01 s brings
    first = sim.bodies.id.copy()
    x0 = sim.bodies.position - sim.bodies.velocity * sim.dt
    t_cross = (x0[:, 2] - 0.5) / -vz  # the centre reaches the face
    sim.run(until=0.15, progress=False)
    assert inlet.inserted == 50  # 500/s over 0.1 s, exactly
    assert inlet.inserted_mass == pytest.approx(50 * 4 / 3 * np.pi * r**3 * 7800, rel=1e-12)
    assert len(inlet.carried) == 0 and np.all(sim.bodies.invmass > 0)
    rows = np.searchsorted(sim.bodies.id, first)
    tau = sim.time - t_cross
    face_pt = x0.copy()
    face_pt[:, 2] = 0.5
    expect = face_pt + np.array([0, 0, vz]) * tau[:, None]
    expect[:, 2] -= 0.5 * G * tau**2
    np.testing.assert_allclose(sim.bodies.position[rows], expect, atol=1e-9)
    np.testing.assert_allclose(sim.bodies.velocity[rows, 2], vz - G * tau, atol=1e-9)


def test_mass_rate_within_one_body_and_a_disc_and_mesh_face(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    sim, m = scene()
    disc = dpm.DiscFace(center=(0, 0, 0.5), normal=(0, 0, 1), radius=0.03)
    a = sim.add_inlet(disc, m, mass_rate=0.05, radius=2e-3, velocity=(0, 0, -1.0),
                      every=0.01, stop=0.05, seed=2)
    sq = trimesh.Trimesh(vertices=[[0.1, 0, 0.5], [0.14, 0, 0.5], [0.14, 0.04, 0.5],
                                   [0.1, 0.04, 0.5]], faces=[[0, 1, 2], [0, 2, 3]])
    sq.export(tmp_path / "face.stl")
    mesh_face = dpm.MeshFace(file=str(tmp_path / "face.stl"))
    assert mesh_face.area == pytest.approx(0.0016)
    b = sim.add_inlet(mesh_face, m, rate=300.0, radius=2e-3, velocity=(0, 0, -1.0),
                      every=0.01, stop=0.05, seed=3)
    sim.run(until=0.06, progress=False)
    one = 4 / 3 * np.pi * (2e-3) ** 3 * 7800
    assert abs(a.inserted_mass - 0.05 * 0.05) <= one
    assert b.inserted == 15
    assert np.all(disc.on_face(disc.sample(np.random.default_rng(0), 100, 0.0)))
    pts = mesh_face.sample(np.random.default_rng(0), 100, 0.0)
    assert np.all(mesh_face.contains(pts))
    assert not mesh_face.on_face(np.array([[0.0, 0.0, 0.5]]))[0]


def test_refusals():
    sim, m = scene()
    face = dpm.RectangleFace(**FACE)
    with pytest.raises(ParameterError, match="crosses the face"):
        sim.add_inlet(face, m, rate=100.0, radius=2e-3, velocity=(1.0, 0, 0))
    with pytest.raises(ParameterError, match="thinner than the largest body"):
        sim.add_inlet(face, m, rate=100.0, radius=(2e-3, 5e-3), velocity=(0, 0, -1.0),
                      every=1e-3)
    with pytest.raises(ParameterError, match="is a face"):
        sim.add_outlet(face)
    with pytest.raises(ParameterError, match="not parallel"):
        dpm.RectangleFace((0, 0, 0), (1, 0, 0), (2, 0, 0))
    with pytest.raises(ParameterError, match="not planar"):
        dpm.MeshFace(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]],
                     triangles=[[0, 1, 2], [1, 3, 2]])
    with pytest.raises(ParameterError, match="give file=, or vertices= and triangles="):
        dpm.MeshFace(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(ParameterError, match="normal"):
        dpm.DiscFace((0, 0, 0), (0, 0, 0), 1.0)


def test_a_multisphere_mix_keeps_its_lists():
    """Two radii are a list of the shape, not a range (low, high) to draw from."""
    sim, m = scene()
    inlet = sim.add_inlet(dpm.RectangleFace(**FACE), m, rate=100.0, velocity=(0, 0, -1.0),
                          every=0.02, shape="multisphere",
                          centres=[[0, 0, 0], [3e-3, 0, 0]], radii=[2e-3, 2e-3])
    name, params = inlet.draw()
    assert name == "multisphere" and params["radii"] == [2e-3, 2e-3]
    assert inlet.largest_radius() == pytest.approx(3.5e-3)
