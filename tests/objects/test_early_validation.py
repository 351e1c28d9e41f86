"""Hostile input is refused before any step runs, with a message that names the parameter,
the value given and what is allowed: infinity, strings and booleans where numbers are
wanted, non-integer counts, inlet typos and ranges, inlet regions that cannot receive a
particle, particles on the wrong side of a closed mesh, unreadable meshes, requests that
cannot fit in memory, and malformed scene files. None of these tests runs a step."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

import dpm
from dpm import _memory
from dpm.errors import ParameterError, SceneError
from dpm.flow import Inlet
from dpm.scene_check import validate_scene
from dpm.scene_file import read_scene

GLASS = dict(density=2500.0, young=5e6, poisson=0.45)
R = 1e-3


@pytest.fixture
def glass():
    return dpm.Material("glass", **GLASS)


@pytest.fixture
def sim(glass):
    s = dpm.Simulation(dt=1e-6, gravity=(0, 0, -9.81))
    s.contact(glass, glass, model="hertz_mindlin", restitution=0.5, friction=0.5)
    return s


REGION = dpm.BoxRegion((0, 0, 0), (0.01, 0.01, 0.01))


# 1. infinity ------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["density", "young", "poisson"])
@pytest.mark.parametrize("value", [math.inf, -math.inf])
def test_material_refuses_infinity(name, value):
    kw = dict(GLASS, **{name: value})
    with pytest.raises(ParameterError, match=rf"{name}=-?inf is not finite"):
        dpm.Material("glass", **kw)


def test_infinite_radius_friction_dt_refused(sim, glass):
    with pytest.raises(ParameterError, match="radius=inf is not finite"):
        sim.add_particles("sphere", material=glass, positions=[(0, 0, 0)], radius=math.inf)
    with pytest.raises(ParameterError, match="friction=inf is not finite"):
        sim.contact(glass, glass, restitution=0.5, friction=math.inf)
    with pytest.raises(ParameterError, match="dt=inf"):
        dpm.Simulation(dt=math.inf)
    with pytest.raises(ParameterError, match="until=inf"):
        sim.run(until=math.inf)


def test_inlet_stop_may_be_infinite_but_not_nan(glass):
    assert Inlet(REGION, glass, rate=10.0, radius=R).stop == math.inf
    with pytest.raises(ParameterError, match="stop=nan is NaN"):
        Inlet(REGION, glass, rate=10.0, radius=R, stop=math.nan)
    with pytest.raises(ParameterError, match="start=inf is not finite"):
        Inlet(REGION, glass, rate=10.0, radius=R, start=math.inf)


# 2. no silent conversions -----------------------------------------------------------------
def test_strings_and_booleans_are_not_numbers(sim, glass):
    with pytest.raises(ParameterError, match=r"radius='1e-3' is not a number"):
        sim.add_particles("sphere", material=glass, positions=[(0, 0, 0)], radius="1e-3")
    with pytest.raises(ParameterError, match=r"radius=True is not a number"):
        sim.add_particles("sphere", material=glass, positions=[(0, 0, 0)], radius=True)
    with pytest.raises(ParameterError, match=r"density='2500' is not a number"):
        dpm.Material("g", density="2500")
    with pytest.raises(ParameterError, match=r"positions=.*must be numbers"):
        sim.add_particles("sphere", material=glass, positions=[(0, 0, "1")], radius=R)
    with pytest.raises(ParameterError, match=r"velocities=.*must be numbers"):
        sim.add_particles("sphere", material=glass, positions=[(0, 0, 0)],
                          velocities=[(True, 0, 0)], radius=R)
    assert len(sim.bodies) == 0


def test_counts_must_be_integers(sim, glass):
    sim.add_particles("sphere", material=glass, positions=[(0, 0, 0)], radius=R)
    with pytest.raises(ParameterError, match=r"steps=1.7 is not an integer"):
        sim.run(steps=1.7)
    with pytest.raises(ParameterError, match=r"steps=True is not an integer"):
        sim.run(steps=True)
    with pytest.raises(ParameterError, match=r"steps='10' is not an integer"):
        sim.run(steps="10")
    with pytest.raises(ParameterError, match=r"threads=1.5 is not an integer"):
        dpm.Simulation(dt=1e-6, threads=1.5)
    with pytest.raises(ParameterError, match=r"seed=0.5 is not an integer"):
        Inlet(REGION, glass, rate=10.0, radius=R, seed=0.5)
    with pytest.raises(ParameterError, match=r"max_attempts=0 is outside"):
        Inlet(REGION, glass, rate=10.0, radius=R, max_attempts=0)
    assert sim.step_count == 0


def test_numpy_numbers_are_numbers(sim, glass):
    sim.add_particles("sphere", material=glass, positions=np.zeros((1, 3), np.float32),
                      radius=np.float64(R))
    sim.add_particles("sphere", material=glass, positions=[(0.01, 0, 0), (0.02, 0, 0)],
                      radius=np.array([R, R]))
    dpm.Material("g", density=np.int64(2500), young=np.float32(5e6))
    assert len(sim.bodies) == 3


# 3. vectors -------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", ["down", (0, 0), (0, 0, "x"), None, {"z": -9.81},
                                 (True, False, True), [[0, 0, 1]]])
def test_gravity_must_be_a_3_vector_of_numbers(bad):
    if bad is None:
        dpm.Simulation(dt=1e-6, gravity=None)  # None: the default
        return
    with pytest.raises(ParameterError, match=r"gravity=.* must be a 3-vector of numbers "
                                             r"\[m/s2\]"):
        dpm.Simulation(dt=1e-6, gravity=bad)


def test_gravity_down_message():
    with pytest.raises(ParameterError) as err:
        dpm.Simulation(dt=1e-6, gravity="down")
    assert str(err.value) == "Simulation(): gravity='down' must be a 3-vector of numbers [m/s2]"


# 4. inlets --------------------------------------------------------------------------------
def test_inlet_typos_found_at_construction(sim, glass):
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) radious=0.001; "
                                             r"allowed: .* shape's radius"):
        sim.add_inlet(REGION, glass, rate=10.0, radious=R)
    with pytest.raises(ParameterError, match=r"unknown parameter\(s\) sed=3; allowed: .*seed"):
        sim.add_inlet(REGION, glass, rate=10.0, radius=R, sed=3)
    with pytest.raises(ParameterError, match=r"shapes\[1\]: unknown shape 'sphrere'"):
        sim.add_inlet(REGION, glass, rate=10.0, shapes=[{"shape": "sphere", "radius": R},
                                                         {"shape": "sphrere", "radius": R}])
    assert sim.inlets == []


def test_inlet_ranges_checked_at_both_ends_naming_the_range(glass):
    with pytest.raises(ParameterError) as err:
        Inlet(REGION, glass, rate=10.0, radius=(-1e-3, 2e-3))
    msg = str(err.value)
    assert msg.startswith("Inlet(): shapes[0] radius=(-0.001, 0.002): ") and "outside" in msg
    with pytest.raises(ParameterError, match=r"radius=\(0.002, 0.001\): the low end 0.002 "
                                             r"exceeds the high end 0.001"):
        Inlet(REGION, glass, rate=10.0, radius=(2e-3, 1e-3))
    with pytest.raises(ParameterError, match=r"radius=\(0.001, inf\).*high end.*not finite"):
        Inlet(REGION, glass, rate=10.0, radius=(1e-3, math.inf))
    with pytest.raises(ParameterError, match=r"radius=\(0.001, 'b'\): a range"):
        Inlet(REGION, glass, rate=10.0, radius=(1e-3, "b"))


@pytest.mark.parametrize("kw, match", [
    (dict(rate=-1.0), r"rate=-1 is outside \(0, inf\)"),
    (dict(rate="10"), r"rate='10' is not a number"),
    (dict(mass_rate=math.nan), r"mass_rate=nan is NaN"),
    (dict(rate=10.0, every=0.0), r"every=0 is outside"),
    (dict(rate=10.0, velocity="up"), r"velocity='up' must be a 3-vector"),
    (dict(rate=10.0, random_orientation=1), r"random_orientation=1; allowed: True or False"),
    (dict(rate=10.0, start=1.0, stop=0.5), r"stop=0.5 must be after start=1.0"),
    (dict(rate=1.0, mass_rate=1.0), r"exactly one of rate"),
])
def test_inlet_arguments_validated(glass, kw, match):
    with pytest.raises(ParameterError, match=match):
        Inlet(REGION, glass, radius=R, **kw)


@pytest.mark.parametrize("fraction", [-0.5, math.nan, "1", True])
def test_inlet_fraction_refused(glass, fraction):
    with pytest.raises(ParameterError, match=r"shapes\[0\] fraction="):
        Inlet(REGION, glass, rate=10.0,
              shapes=[{"shape": "sphere", "fraction": fraction, "radius": R}])


# 5. inlet regions that cannot receive a particle -------------------------------------------
def test_region_too_small_for_the_particle(glass):
    with pytest.raises(ParameterError, match=r"region=BoxRegion\(.*\) is too small for the "
                                             r"smallest particle"):
        Inlet(dpm.BoxRegion((0, 0, 0), (1e-3, 1e-3, 1e-3)), glass, rate=10.0, radius=R)


def test_region_outside_a_closed_box_refused_before_step_1(sim, glass):
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.05, 0.05, 0.05))
    sim.add_particles("sphere", material=glass, positions=[(0.02, 0.02, 0.02)], radius=R)
    sim.add_inlet(dpm.BoxRegion((0.1, 0.1, 0.1), (0.12, 0.12, 0.12)), glass, rate=100.0,
                  radius=(R, 2 * R))
    with pytest.raises(SceneError, match=r"inlet 0: no point of its region BoxRegion\("
                                         r"lower=\(0.1, 0.1, 0.1\).*boundary.*0 \(box\)"):
        validate_scene(sim)


def test_region_above_an_open_box_accepted(sim, glass):
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.05, 0.05, 0.05),
                     open="+z")
    sim.add_particles("sphere", material=glass, positions=[(0.02, 0.02, 0.02)], radius=R)
    sim.add_inlet(dpm.BoxRegion((0.0, 0.0, 0.1), (0.05, 0.05, 0.12)), glass, rate=100.0,
                  radius=R)
    validate_scene(sim)


def test_empty_scene_with_a_bad_inlet_names_the_inlet(sim, glass):
    """Before step 1 a run first lets the inlets fill an empty scene, then checks it: an
    inlet that placed nothing is named, not only 'the scene has no particles'."""
    from dpm import population

    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.05, 0.05, 0.05))
    sim.add_inlet(dpm.BoxRegion((0.1, 0.1, 0.1), (0.12, 0.12, 0.12)), glass, rate=1e4,
                  radius=R)
    population.flow_event(sim)  # what sim.run() does before its checks
    assert len(sim.bodies) == 0
    with pytest.raises(SceneError) as err:
        validate_scene(sim)
    assert "inlet 0: no point of its region" in str(err.value)


# 6. meshes -------------------------------------------------------------------------------
def _box_mesh():
    return trimesh.creation.box((0.02, 0.02, 0.02))


def test_particle_inside_a_closed_obstacle_refused(sim, glass):
    m = _box_mesh()  # outward normals: an obstacle, the particles belong outside
    sim.add_boundary("mesh", material=glass, vertices=m.vertices, faces=m.faces)
    sim.add_particles("sphere", material=glass, radius=R,
                      positions=[(0, 0, 0), (0.05, 0, 0)])
    with pytest.raises(SceneError, match=r"1 particle\(s\) lie outside boundary 0 \(mesh\): "
                                         r"id\(s\) 0 .*belong outside"):
        validate_scene(sim)


def test_particle_outside_a_closed_container_refused(sim, glass):
    m = _box_mesh()
    m.invert()  # inward normals: a container
    sim.add_boundary("mesh", material=glass, vertices=m.vertices, faces=m.faces)
    sim.add_particles("sphere", material=glass, radius=R,
                      positions=[(0, 0, 0), (0.05, 0, 0)])
    with pytest.raises(SceneError, match=r"id\(s\) 1 .*belong inside"):
        validate_scene(sim)


def test_mesh_side_given_explicitly(sim, glass):
    m = _box_mesh()
    sim.add_boundary("mesh", material=glass, vertices=m.vertices, faces=m.faces,
                     side="inside")
    sim.add_particles("sphere", material=glass, radius=R, positions=[(0.05, 0, 0)])
    with pytest.raises(SceneError, match="belong inside"):
        validate_scene(sim)
    with pytest.raises(ParameterError, match=r"side='in'; allowed: auto, inside"):
        sim.add_boundary("mesh", material=glass, vertices=m.vertices, faces=m.faces,
                         side="in")
    open_mesh = trimesh.Trimesh(m.vertices, m.faces[:-2], process=False)
    with pytest.raises(ParameterError, match="needs a closed"):
        sim.add_boundary("mesh", material=glass, vertices=open_mesh.vertices,
                         faces=open_mesh.faces, side="outside")


def test_mesh_contains_matches_a_sphere():
    from dpm.boundaries.mesh import contains

    ico = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    pts = np.random.default_rng(3).uniform(-1.5, 1.5, (3000, 3))
    r = np.linalg.norm(pts, axis=1)
    sure = np.abs(r - 1.0) > 0.01  # the facets lie within 1 % of the sphere
    np.testing.assert_array_equal(contains(ico.vertices, ico.faces, pts)[sure], (r < 1)[sure])


def test_unreadable_meshes_named(sim, glass, tmp_path):
    missing = tmp_path / "nothere.stl"
    with pytest.raises(ParameterError, match=r"file='.*nothere.stl' does not exist"):
        sim.add_boundary("mesh", material=glass, file=missing)
    junk = tmp_path / "junk.stl"
    junk.write_bytes(b"\x00\x01 not a mesh")
    with pytest.raises(ParameterError, match=r"file='.*junk.stl'"):
        sim.add_boundary("mesh", material=glass, file=junk)
    flat = tmp_path / "flat.stl"
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]])
    trimesh.Trimesh(v, [[0, 1, 2]], process=False).export(flat)
    with pytest.raises(ParameterError, match=r"file='.*flat.stl'.*(no triangle|holds no)"):
        sim.add_boundary("mesh", material=glass, file=flat)
    with pytest.raises(ParameterError, match=r"vertices/faces: the mesh has no triangle"):
        sim.add_boundary("mesh", material=glass, vertices=v, faces=[[0, 1, 2]])
    assert sim.boundaries == []


# 7. huge requests ------------------------------------------------------------------------
def test_check_request_names_count_and_memory():
    have = _memory.physical_memory()
    assert have and have > 0
    n = 2 * have // (_memory.BYTES_PER_BODY + _memory.BYTES_PER_ELEMENT)
    with pytest.raises(ParameterError) as err:
        _memory.check_request("sim.add_particles('sphere')", n, n)
    msg = str(err.value)
    assert msg.startswith("sim.add_particles('sphere'): ") and f"{float(n):.4g} bodies" in msg
    assert "GB of memory" in msg and "this machine has" in msg
    _memory.check_request("sim.add_particles('sphere')", 1000, 1000)  # fits


def test_huge_lattice_refused_before_allocating():
    with pytest.raises(ParameterError, match=r"dpm.lattice\(\): spacing=1e-06 gives 1e\+18 "
                                             r"points;.*GB of memory"):
        dpm.lattice((0, 0, 0), (1, 1, 1), 1e-6)
    with pytest.raises(ParameterError, match=r"spacing=0 is outside"):
        dpm.lattice((0, 0, 0), (1, 1, 1), 0.0)


def test_huge_positions_refused_before_the_copy(sim, glass):
    have = _memory.physical_memory()
    n = int(2 * have // (_memory.BYTES_PER_BODY + _memory.BYTES_PER_ELEMENT))
    # a broadcast view: n rows of three floats that take no memory
    huge = np.broadcast_to(np.zeros(3), (n, 3))
    with pytest.raises(ParameterError, match=r"bodies .*GB of memory"):
        sim.add_particles("sphere", material=glass, positions=huge, radius=R)


# 8. scene files --------------------------------------------------------------------------
def test_missing_scene_file(tmp_path):
    with pytest.raises(ParameterError, match="the scene file does not exist"):
        read_scene(tmp_path / "none.toml")


def test_single_particles_table_refused(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[simulation]\ndt = 1e-5\n[particles]\nshape = "sphere"\n')
    with pytest.raises(ParameterError, match=r"particles must be an array of tables: write "
                                             r"\[\[particles\]\]"):
        read_scene(f)


def test_unknown_keys_named_per_table(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text("""
[simulation]
dt = 1e-5
gravty = [0, 0, -9.81]
[materials.glass]
density = 2500
[[contacts]]
materials = ["glass", "glass"]
restitutoin = 0.3
[[inlets]]
material = "glass"
region = { box = { lower = [0, 0, 0], uper = [1, 1, 1] } }
rate = 10
radious = [1e-3, 2e-3]
[[particles]]
material = "glass"
radius = 1e-3
lattice = { lower = [0, 0, 0], upper = [0.01, 0.01, 0.01], spacin = 1e-3 }
[run]
step = 3
""")
    with pytest.raises(ParameterError) as err:
        read_scene(f)
    msg = str(err.value)
    for part in ("[simulation]: unknown key gravty", "allowed: ", "gravity",
                 "contacts[0]: unknown key restitutoin", "inlets[0]: region.box: unknown key "
                 "uper", "inlets[0]: unknown key radious", "lattice: unknown key spacin",
                 "[run]: unknown key step = 3 (did you mean steps?); allowed: steps, until"):
        assert part in msg, msg
    # each unknown key with the line it stands on (the file starts with an empty line)
    lines = {line.split(": unknown key ")[1].split(" ")[0]: line.rsplit("(line ", 1)[-1]
             for line in msg.splitlines()}
    assert lines == {"gravty": "4)", "restitutoin": "9)", "uper": "12)", "radious": "14)",
                     "spacin": "18)", "step": "20)"}, msg


def test_cli_reports_scene_errors_without_traceback(tmp_path, capsys):
    from dpm.cli import main

    assert main(["run", str(tmp_path / "none.toml")]) == 2
    assert "ParameterError" in capsys.readouterr().err
