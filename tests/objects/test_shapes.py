"""Clustered sub-sphere shapes: mass properties, principal frames, clusters, library."""

import math

import numpy as np
import pytest
import trimesh

import dpm
from dpm.errors import ParameterError
from dpm.shapes import (
    BUILTIN_SHAPES,
    Barrel,
    Block,
    ClusterShape,
    Cylinder,
    Disc,
    DoubleCone,
    Hyperboloid,
    MeshShape,
    Parallelepiped,
    Tetrahedron,
    Torus,
)
from dpm.shapes import library as lib
from dpm.shapes.geometry import (
    ellipsoid_depth,
    matrix_from_quaternion,
    principal_frame,
    quaternion_from_matrix,
    triangle_distance,
)
from dpm.shapes.metrics import parse_spec, report_table, shape_report

NAMES = ["sphere", "ellipsoid", "cylinder", "cube", "block", "parallelepiped", "tetrahedron",
         "cone", "double_cone", "hyperboloid", "barrel", "disc", "torus", "mesh"]

#: non-default parameters, so that no closed form is only checked at one aspect ratio
CASES = {
    "ellipsoid": dict(a=3e-3, b=1.5e-3, c=1e-3),
    "cylinder": dict(r=1.5e-3, l=2e-3),
    "cube": dict(a=1.7e-3),
    "block": dict(a=1e-3, b=4e-3, c=2e-3),
    "parallelepiped": dict(a=3e-3, b=2e-3, c=1.5e-3, alpha=80, beta=65, gamma=110),
    "tetrahedron": dict(a=2.5e-3),
    "cone": dict(r=2e-3, l=1.5e-3),
    "double_cone": dict(r=0.8e-3, l=2e-3),
    "hyperboloid": dict(r1=1.2e-3, r2=0.5e-3, l=2.5e-3),
    "barrel": dict(r1=0.6e-3, r2=1.1e-3, l=2e-3),
    "disc": dict(r1=2.5e-3, r2=0.8e-3, c=0.7e-3),
    "torus": dict(r1=0.4e-3, r2=1.2e-3),
}
#: chord error of the 128-section meshes of curved solids (volume ~ 1 - (2 pi / n)^2 / 6)
CURVED_RTOL = 1.5e-3


def test_registered_names_are_exactly_the_catalogue():
    assert sorted(BUILTIN_SHAPES) == sorted(NAMES)
    assert set(NAMES) <= set(dpm.registry().names("shape"))
    for name, cls in BUILTIN_SHAPES.items():
        assert cls.name == name
        if name != "sphere":
            assert "resolution" in cls.parameters


@pytest.mark.parametrize("name", sorted(CASES))
def test_closed_form_mass_properties_match_trimesh(name):
    shape = BUILTIN_SHAPES[name](**CASES[name])
    mesh = shape.mesh(fine=True)
    assert mesh.is_watertight and mesh.is_volume
    mp = shape.mass_properties()
    polyhedron = name in ("cube", "block", "parallelepiped", "tetrahedron")
    rtol = 1e-9 if polyhedron else CURVED_RTOL
    assert mesh.volume == pytest.approx(mp.volume, rel=rtol)
    # centre of mass at the shape frame's origin
    assert np.all(np.abs(mesh.center_mass) <= 1e-9 * mesh.scale)
    scale = np.abs(mp.tensor).max()
    assert np.abs(mesh.moment_inertia - mp.tensor).max() <= rtol * scale


def test_thesis_forms_after_errata():
    pi = math.pi
    r1, r2, l = 0.7, 1.0, 3.0  # barrel: thesis r1 small, r2 big
    i = np.diag(Barrel(r1=r1, r2=r2, l=l).inertia_tensor())
    assert Barrel(r1=r1, r2=r2, l=l).volume() == pytest.approx(
        pi * l * (r1**2 / 5 + 4 * r1 * r2 / 15 + 8 * r2**2 / 15))
    assert i[0] == pytest.approx(pi * l * (r1**4 / 18 + 4 * r1**3 * r2 / 63 + 8 * r1**2 * r2**2
                                           / 105 + 32 * r1 * r2**3 / 315 + 64 * r2**4 / 315))
    assert i[1] == pytest.approx(
        pi * l**3 * (r1**2 / 28 + r1 * r2 / 35 + 2 * r2**2 / 105)
        + pi * l * (r1**4 / 36 + 2 * r1**3 * r2 / 63 + 4 * r1**2 * r2**2 / 105
                    + 16 * r1 * r2**3 / 315 + 32 * r2**4 / 315))
    a, b = 1.0, 0.6  # hyperboloid: thesis r1 big, r2 waist; "b" in Ixx is r2; 1 -> 1/4
    h = Hyperboloid(r1=a, r2=b, l=l)
    i = np.diag(h.inertia_tensor())
    assert h.volume() == pytest.approx(pi / 3 * l * (a**2 + 2 * b**2))
    assert i[0] == pytest.approx(pi * l * b**4 * (4 / 15 + 2 * a**2 / (15 * b**2)
                                                  + a**4 / (10 * b**4)))
    d = b**2 - a**2
    assert i[1] == pytest.approx(pi * l**3 * b**2 * (1 / 12 - d / (20 * b**2))
                                 + pi * l * b**4 * (1 / 4 - d / (6 * b**2) + d**2 / (20 * b**4)))
    r, ll = 0.8, 1.3
    i = np.diag(DoubleCone(r=r, l=ll).inertia_tensor())
    assert i[1] == pytest.approx(pi / 10 * r**2 * ll * (r**2 + 2 * ll**2 / 3))
    t1, t2 = 0.3, 1.1
    i = np.diag(Torus(r1=t1, r2=t2).inertia_tensor())
    assert i[2] == pytest.approx(2 * pi**2 * t1**2 * t2 * (t2**2 + 0.75 * t1**2))
    assert i[0] == pytest.approx(pi**2 * t1**2 * t2 * (5 * t1**2 + 4 * t2**2) / 4)
    assert np.diag(Tetrahedron(a=2.0).inertia_tensor()) == pytest.approx(
        np.full(3, math.sqrt(2) / 240 * 32))
    o, n, c = 2.0, 0.5, 0.4
    i = np.diag(Disc(r1=o, r2=n, c=c).inertia_tensor())
    v = pi * (o**2 - n**2) * c
    assert i[1] == pytest.approx(pi / 4 * (o**4 - n**4) * c + v * c**2 / 12)


@pytest.mark.parametrize("name", sorted(CASES))
def test_inside_test_and_depth_agree_with_the_solid(name):
    shape = BUILTIN_SHAPES[name](**CASES[name])
    rng = np.random.default_rng(3)
    lo, hi = shape.bounds()
    pts = rng.uniform(lo, hi, size=(40000, 3))
    inside = shape.inside(pts)
    box = float(np.prod(np.asarray(hi) - np.asarray(lo)))
    p = inside.mean()
    sigma = box * math.sqrt(p * (1 - p) / len(pts))
    assert abs(p * box - shape.volume()) <= 4 * sigma + CURVED_RTOL * shape.volume()
    # depth of interior points: the distance to the (fine) surface mesh
    mesh = shape.mesh(fine=True)
    q = pts[inside][:150]
    ref = triangle_distance(q, mesh.triangles)
    d = shape.depth(q)
    chord = 2e-3 * float(np.max(np.asarray(hi) - np.asarray(lo)))
    assert np.all(np.abs(d - ref) <= chord)


def test_ellipsoid_depth_against_dense_surface():
    axes = np.array([3.0, 1.5, 1.0])
    rng = np.random.default_rng(0)
    p = rng.uniform(-1, 1, (300, 3)) * axes
    p = p[np.sum((p / axes) ** 2, axis=1) < 1][:100]
    p[:5, 2] = 0.0  # on a symmetry plane
    u = rng.normal(size=(400000, 3))
    s = u / np.linalg.norm(u, axis=1)[:, None] * axes
    from scipy.spatial import cKDTree

    ref, _ = cKDTree(s).query(p)
    d = ellipsoid_depth(p, axes)
    assert np.all(d <= ref + 1e-9)
    assert np.all(ref - d <= 0.02)


def _random_rotation(rng):
    q = rng.normal(size=4)
    return matrix_from_quaternion(q / np.linalg.norm(q))


def test_principal_frame_is_right_handed_and_diagonalises():
    rng = np.random.default_rng(5)
    for _ in range(20):
        rot = _random_rotation(rng)
        t = rot @ np.diag(rng.uniform(1, 5, 3)) @ rot.T
        moments, r = principal_frame(t)
        assert np.linalg.det(r) == pytest.approx(1.0)
        assert np.allclose(r.T @ r, np.eye(3), atol=1e-12)
        assert np.all(np.diff(moments) >= 0)
        assert np.allclose(r.T @ t @ r, np.diag(moments), atol=1e-12 * moments.max())
        q = quaternion_from_matrix(r)
        assert np.allclose(matrix_from_quaternion(q), r, atol=1e-12)
        # deterministic: the same tensor gives the same frame, also after a tiny change
        m2, r2 = principal_frame(t * (1 + 1e-14))
        assert np.allclose(r, r2, atol=1e-8)


def test_principal_frame_of_symmetric_shapes_keeps_the_shape_axes():
    # long cylinder along x: smallest moment about x, y and z kept
    assert np.allclose(Cylinder(r=1e-3, l=5e-3).mass_properties().rotation, np.eye(3))
    # flat disc along x: axial moment largest -> principal axes (y, z, x)
    rot = Disc().mass_properties().rotation
    assert np.allclose(rot, np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]]))
    assert np.allclose(Tetrahedron().mass_properties().rotation, np.eye(3))
    # an oblique parallelepiped: a true rotation that diagonalises the tensor
    mp = Parallelepiped(**CASES["parallelepiped"]).mass_properties()
    assert not np.allclose(mp.rotation, np.eye(3), atol=1e-3)
    assert np.allclose(mp.rotation.T @ mp.tensor @ mp.rotation, np.diag(mp.moments),
                       atol=1e-9 * mp.moments.max())


@pytest.mark.parametrize("name", ["block", "parallelepiped", "torus", "cone", "hyperboloid"])
def test_build_batch_elements_inside_and_in_the_principal_frame(name):
    shape = BUILTIN_SHAPES[name](**CASES[name], resolution=0.2)
    batch = shape.build(3, density=2500.0)
    mp = shape.mass_properties()
    cl = shape.cluster()
    m = len(cl)
    assert batch.element_count.tolist() == [m] * 3
    assert batch.element_offset.shape == (3 * m, 3) and batch.element_radius.shape == (3 * m,)
    assert np.allclose(batch.mass, 2500.0 * mp.volume)
    assert np.allclose(batch.inertia, 2500.0 * mp.moments[None, :])
    q = batch.principal_rotation[0]
    assert np.linalg.norm(q) == pytest.approx(1.0)
    rot = matrix_from_quaternion(q)
    shape_frame = batch.element_offset[:m] @ rot.T  # offset_shape = R(q) offset_principal
    assert np.allclose(shape_frame, cl.centres, atol=1e-15)
    # every element inside the ideal solid (inscribed) and no smaller than r_min
    assert np.all(shape.depth(cl.centres) >= cl.radii * (1 - 1e-9))
    assert cl.radii.min() >= cl.min_radius * (1 - 1e-9)
    bound = np.max(np.linalg.norm(batch.element_offset[:m], axis=1) + cl.radii)
    assert np.allclose(batch.bounding_radius, bound)


def test_cluster_is_deterministic_and_cached():
    a = Torus(resolution=0.25).cluster()
    b = Torus(resolution=0.25).cluster()
    assert np.array_equal(a.centres, b.centres) and np.array_equal(a.radii, b.radii)
    s = Torus(resolution=0.25)
    assert s.cluster() is s.cluster()


@pytest.mark.parametrize("name", ["cylinder", "torus", "tetrahedron"])
def test_cluster_converges_to_the_solid(name):
    reports = [shape_report(BUILTIN_SHAPES[name](resolution=res), samples=1500,
                            volume_samples=40000) for res in (0.1, 0.4, 0.8)]
    counts = [r["count"] for r in reports]
    vol = [r["volume_ratio"] for r in reports]
    rms = [r["dev_rms"] / r["r_eq"] for r in reports]
    rmin = [r["r_min"] for r in reports]
    assert counts[0] < counts[1] < counts[2]
    assert vol[0] < vol[1] < vol[2] <= 1.0 + 3 * reports[2]["volume_ratio_err"]
    assert vol[2] >= 0.95
    assert rms[0] > rms[1] > rms[2]
    assert rms[2] < 0.015
    assert rmin[0] >= rmin[2]


@pytest.mark.parametrize("call, words", [
    (lambda: Cylinder(r=-1e-3), ["r=-0.001", "(0, inf)"]),
    (lambda: Cylinder(resolution=0.0), ["resolution=0", "(0, 1]"]),
    (lambda: Cylinder(resolution=1.5), ["resolution=1.5", "(0, 1]"]),
    (lambda: Block(a=1e-3, b=1e-3, c=float("nan")), ["c=nan", "NaN"]),
    (lambda: Disc(r1=1e-3, r2=2e-3), ["r2=0.002", "[0, r1=0.001)"]),
    (lambda: Torus(r1=2e-3, r2=1e-3), ["r1=0.002", "(0, r2=0.001)"]),
    (lambda: Hyperboloid(r1=0.5e-3, r2=1e-3), ["r2=0.001", "(0, r1=0.0005]"]),
    (lambda: Barrel(r1=2e-3, r2=1e-3), ["r1=0.002", "(0, r2=0.001]"]),
    (lambda: Parallelepiped(alpha=170, beta=20, gamma=90), ["alpha=170", "beta=20", "> 0"]),
    (lambda: Parallelepiped(gamma=180), ["gamma=180", "(0, 180)"]),
    (lambda: Cylinder(radius=1e-3), ["unknown parameter radius", "allowed: l, r, resolution"]),
    (lambda: MeshShape(), ["exactly one of path"]),
])
def test_parameters_are_validated(call, words):
    with pytest.raises(ParameterError) as err:
        call()
    for w in words:
        assert w in str(err.value)


def _rock(seed=7):
    m = trimesh.creation.icosphere(subdivisions=3)
    rng = np.random.default_rng(seed)
    v = m.vertices
    dirs = rng.normal(size=(10, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    amp = rng.uniform(-0.2, 0.2, 10)
    f = 1 + sum(a * np.exp(-((v @ d - 1) ** 2) / 0.3) for a, d in zip(amp, dirs, strict=True))
    return trimesh.Trimesh(v * f[:, None] * np.array([1.3, 1.0, 0.8]), m.faces)


def test_mesh_shape_from_stl_has_trimesh_mass_properties(tmp_path):
    rock = _rock()
    rot = np.eye(4)
    rot[:3, :3] = _random_rotation(np.random.default_rng(2))
    rock.apply_transform(rot)
    rock.apply_translation([5.0, -2.0, 1.0])
    path = tmp_path / "rock.stl"
    rock.export(path)
    ref = trimesh.load(path, force="mesh")
    shape = MeshShape(path=str(path), scale=1e-3, resolution=0.2)
    mp = shape.mass_properties()
    assert mp.volume == pytest.approx(ref.volume * 1e-9, rel=1e-9)
    assert np.allclose(mp.centre, ref.center_mass * 1e-3, rtol=0, atol=1e-12)
    assert np.allclose(mp.tensor, ref.moment_inertia * 1e-15, rtol=0,
                       atol=1e-9 * np.abs(ref.moment_inertia).max() * 1e-15)
    cl = shape.cluster()
    assert np.all(shape.depth(cl.centres) >= cl.radii * (1 - 1e-9))
    assert np.all(shape.inside(cl.centres))
    # the same solid as a MeshShape and as a built-in: the same mass properties
    box = trimesh.creation.box(extents=(3.0, 2.0, 1.0))
    box.apply_translation([1.0, 2.0, 3.0])
    box.export(tmp_path / "box.obj")
    mb = MeshShape(path=str(tmp_path / "box.obj"), scale=1e-3).mass_properties()
    ref_b = Block(a=3e-3, b=2e-3, c=1e-3).mass_properties()
    assert mb.volume == pytest.approx(ref_b.volume, rel=1e-9)
    assert np.allclose(mb.centre, [1e-3, 2e-3, 3e-3], atol=1e-15)
    assert np.allclose(mb.moments, ref_b.moments, rtol=1e-9)


def test_mesh_shape_refuses_open_meshes(tmp_path):
    m = trimesh.creation.box()
    m.update_faces(np.arange(len(m.faces) - 1))
    m.export(tmp_path / "open.stl")
    with pytest.raises(ParameterError, match="watertight"):
        MeshShape(path=str(tmp_path / "open.stl"))
    with pytest.raises(ParameterError, match="cannot be read"):
        MeshShape(path=str(tmp_path / "missing.stl"))


def test_library_round_trip(tmp_path):
    for shape in (Parallelepiped(resolution=0.2), MeshShape(mesh=_rock(), scale=1e-3,
                                                             resolution=0.2)):
        path = lib.save(shape, tmp_path / f"{shape.name}.json", description="test")
        assert path.with_suffix(".stl").is_file()
        back = lib.load(path)
        a, b = shape.build(2, 1000.0), back.build(2, 1000.0)
        for field in ("mass", "inertia", "element_count", "element_offset", "element_radius",
                      "bounding_radius", "principal_rotation"):
            assert np.allclose(getattr(a, field), getattr(b, field), rtol=1e-12, atol=0), field
        assert np.allclose(back.cluster().centres, shape.cluster().centres, atol=1e-15)
        assert np.allclose(back.mass_properties().tensor, shape.mass_properties().tensor)
        # the ideal solid behind a library file is still there for the metrics
        assert back.depth(back.cluster().centres) == pytest.approx(shape.cluster().radii,
                                                                   rel=1e-3, abs=1e-8)
    with pytest.raises(ParameterError, match="no library file"):
        lib.load(tmp_path / "nothing.json")


def test_repository_library_loads_and_runs():
    assert {"rock", "pellet"} <= set(lib.names())
    rock = lib.load("rock")
    assert isinstance(rock, ClusterShape)
    assert rock.doc["report"]["count"] == len(rock.cluster())
    sim = dpm.Simulation(dt=1e-6, gravity=(0, 0, -9.81), integrator="velocity_verlet")
    m = dpm.Material("stone", density=2600, young=5e7, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5,
                rolling_friction=0.0)
    ids = sim.add_particles(rock, material=m, positions=[[0, 0, 0.01], [0.01, 0, 0.01]])
    assert len(ids) == 2
    assert np.allclose(sim.bodies.mass, 2600 * rock.mass_properties().volume)
    assert len(sim.elements) == 2 * len(rock.cluster())


def test_add_particles_by_registered_name():
    sim = dpm.Simulation(dt=1e-6, gravity=(0, 0, -9.81), integrator="velocity_verlet")
    m = dpm.Material("glass", density=2500, young=5e7, poisson=0.3)
    sim.add_particles("block", material=m, a=3e-3, b=2e-3, c=1e-3, resolution=0.2,
                      positions=[[0, 0, 0.01]])
    assert sim.bodies.mass[0] == pytest.approx(2500 * 6e-9)
    assert np.allclose(np.sort(sim.bodies.inertia[0]),
                       np.sort(2500 * 6e-9 / 12 * np.array([5e-6, 10e-6, 13e-6])))
    with pytest.raises(ParameterError, match="resolution=2"):
        sim.add_particles("cube", material=m, resolution=2, positions=[[0, 0, 0.02]])


def test_report_table_and_specs():
    assert parse_spec("block:a=4e-3, b=2e-3") == ("block", {"a": 4e-3, "b": 2e-3})
    text = report_table(["cube:a=1e-3", "rock"], [0.1, 0.2], samples=500)
    lines = text.splitlines()
    assert lines[0].startswith("| shape") and "spheres" in lines[0]
    rows = [x for x in lines[2:] if x.startswith("|")]
    assert len(rows) == 3  # cube at two resolutions, the library rock once
    assert "cube(a=0.001)" in rows[0] and "rock" in rows[2]
    with pytest.raises(ParameterError, match="neither a registered shape"):
        report_table(["no_such_shape"], [0.1])


def test_library_grains_by_name_in_a_script_a_scene_file_and_an_inlet(tmp_path):
    """A grain is a shape name ("rock"): the same bodies as library.load("rock"); in a
    scene file (shape = "rock", or shape = "library" with path = "cylinder": the built-in
    name wins); an inlet's pickled grain class loads again (checkpoints)."""
    import pickle

    from dpm.io.scene import load_scene

    rock = lib.load("rock")
    m = dpm.Material("stone", density=2600, young=5e7, poisson=0.3)
    sim = dpm.Simulation(dt=1e-6)
    sim.add_particles("rock", material=m, positions=[[0, 0, 0]])
    assert sim.bodies.mass[0] == pytest.approx(2600 * rock.mass_properties().volume)
    assert len(sim.elements) == len(rock.cluster()) and sim.shape_names == ["rock"]
    assert sim._registry.lookup("shape", "cylinder") is dpm.shapes.Cylinder
    (tmp_path / "g.toml").write_text(
        '[simulation]\ndt = 1e-6\n[materials.stone]\ndensity = 2600\nyoung = 5e7\n'
        'poisson = 0.3\n[[contacts]]\nmaterials = ["stone", "stone"]\n'
        '[[particles]]\nshape = "rock"\nmaterial = "stone"\npositions = [[0, 0, 0]]\n'
        '[[particles]]\nshape = "library"\npath = "cylinder"\nmaterial = "stone"\n'
        'positions = [[0.05, 0, 0]]\n')
    scene, _ = load_scene(tmp_path / "g.toml", output=False)
    assert scene.shape_names == ["rock", "library:cylinder"]
    assert len(scene.elements) == len(rock.cluster()) + len(lib.load("cylinder").cluster())
    (tmp_path / "bad.toml").write_text(
        (tmp_path / "g.toml").read_text().replace('shape = "rock"', 'shape = "rokc"'))
    with pytest.raises(ParameterError, match=r"unknown shape 'rokc'.*library grains: .*rock"):
        load_scene(tmp_path / "bad.toml", output=False)
    inlet = sim.add_inlet(dpm.BoxRegion((0, 0, 0.1), (0.1, 0.1, 0.2)), m, rate=10,
                          shape="rock")
    assert pickle.loads(pickle.dumps(inlet)).resolved[0][0] is lib.shape_class("rock")
