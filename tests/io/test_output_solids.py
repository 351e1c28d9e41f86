"""The solid shapes of clustered bodies in the output (``sim.output(..., solids=True)``)
and the scene stored in the run file.

References: scipy's rotations of the quaternions (``Rotation.from_quat``) applied to the
shape's own trimesh in its principal frame, built here from a new shape object; trimesh's
enclosed volume of each placed mesh against the shape's closed-form volume; VTK's own XDMF
reader for what ParaView sees; the checkpoint's scene description computed here.
"""

import contextlib
import itertools
import json
import shutil

import h5py
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import dpm
from dpm.checkpoint import fingerprint, scene_description
from dpm.errors import ParameterError
from dpm.io.hdf5 import Writer

SHAPES = {  # name -> parameters (one mesh each in the file)
    "ellipsoid": {"a": 1.5e-3, "b": 1e-3, "c": 0.8e-3, "resolution": 0.2},
    "cube": {"a": 1.6e-3, "resolution": 0.2},
    "cylinder": {"r": 0.6e-3, "l": 2e-3, "resolution": 0.2},
}
#: relative difference between a shape's faceted mesh and its ideal solid's volume
MESH_TOLERANCE = {"ellipsoid": 0.01, "cube": 1e-12, "cylinder": 0.01}


def _scene(device=None):
    sim = dpm.Simulation(dt=1e-5, dt_check="off", gravity=(0, 0, -9.81), device=device)
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.012, 0.012, 0.03),
                     open="+z")
    return sim, m


def _add(sim, m, name, z, seed):
    xyz = dpm.lattice((0.002, 0.002, z), (0.010, 0.010, z + 0.0001), 4e-3)
    q = Rotation.random(len(xyz), random_state=seed).as_quat(scalar_first=True)
    return sim.add_particles(name, material=m, positions=xyz, orientations=q,
                             velocities=np.tile([0.0, 0.0, -0.2], (len(xyz), 1)),
                             angular_velocities=np.tile([5.0, -3.0, 8.0], (len(xyz), 1)),
                             **SHAPES[name])


@pytest.fixture(scope="module")
def solids_run(tmp_path_factory):
    """Ellipsoids and cubes (and spheres, which have no solid of their own) written with
    solids=True; cylinders added between two runs into the same file (a mesh added after
    the file was created)."""
    path = tmp_path_factory.mktemp("solids") / "run.h5"
    sim, m = _scene()
    _add(sim, m, "ellipsoid", 0.004, 1)
    _add(sim, m, "cube", 0.008, 2)
    sim.add_particles("sphere", material=m, radius=0.7e-3,
                      positions=dpm.lattice((0.002, 0.002, 0.016), (0.010, 0.010, 0.0161),
                                            4e-3))
    sim.output(path, every_steps=100, solids=True)
    sim.run(steps=200, progress=False)
    _add(sim, m, "cylinder", 0.020, 3)
    sim.run(steps=200, progress=False)
    sim.close()
    return sim, path


def _local(name):
    """The shape's mesh in its principal frame, from a new shape object."""
    shape = dpm.shapes.BUILTIN_SHAPES[name](**SHAPES[name])
    mesh = shape.mesh()
    return shape, mesh.vertices @ shape.mass_properties().rotation, mesh.faces


def _bodies(run, k):
    """Per body of frame k: (id, shape name, position, quaternion, vertex rows, faces in
    the body's own vertex numbering)."""
    f, s = run.frame(k), run.solids(k)
    # (the shapes attribute names the shapes of the file's creation; the meshes name each)
    names = {m["shape"]: m["name"] for m in run.solid_shapes}
    sphere = [str(x) for x in run.attrs["shapes"]].index("sphere")
    out = []
    for body, shape, x, q in zip(f["id"], f["shape"], f["position"], f["orientation"],
                                 strict=True):
        sel = s["body_id"] == body
        faces = s["faces"][sel]
        if shape == sphere:
            assert len(faces) == 0
            continue
        assert set(s["shape"][sel]) == {shape}
        rows = np.unique(faces)
        assert np.array_equal(rows, np.arange(rows[0], rows[-1] + 1))  # one block each
        out.append((body, names[shape], x, q, s["vertices"][rows], faces - rows[0]))
    return out


def test_placed_vertices_are_the_pose_applied_to_the_shape_mesh(solids_run):
    _, path = solids_run
    run = dpm.load(path)
    assert run.n_frames == 5
    seen = set()
    for k in range(run.n_frames):
        bodies = _bodies(run, k)
        assert len(bodies) == len(run.frame(k)["id"]) - 4  # every body but the 4 spheres
        for _, name, x, q, vertices, faces in bodies:
            seen.add(name)
            _, local, local_faces = _local(name)
            expected = Rotation.from_quat(q, scalar_first=True).apply(local) + x
            np.testing.assert_allclose(vertices, expected, rtol=0, atol=1e-15)
            np.testing.assert_array_equal(faces, local_faces)
    assert seen == set(SHAPES)
    # the cylinders appear from the run after they were added
    assert {b[1] for b in _bodies(run, 2)} == {"ellipsoid", "cube"}
    assert "cylinder" in {b[1] for b in _bodies(run, 3)}


def test_each_placed_mesh_encloses_the_solid_volume(solids_run):
    _, path = solids_run
    run = dpm.load(path)
    for _, name, _, _, vertices, faces in _bodies(run, -1):
        shape, _, _ = _local(name)
        mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        assert mesh.is_watertight
        assert mesh.volume == pytest.approx(shape.volume(), rel=MESH_TOLERANCE[name])
    stored = {s["name"]: s for s in run.solid_shapes}
    assert set(stored) == set(SHAPES)
    for name, s in stored.items():
        shape, local, local_faces = _local(name)
        assert s["volume"] == pytest.approx(shape.volume(), rel=1e-12)
        assert s["mesh_volume"] == pytest.approx(shape.volume(), rel=MESH_TOLERANCE[name])
        np.testing.assert_allclose(s["vertices"], local, rtol=0, atol=1e-18)
        np.testing.assert_array_equal(s["faces"], local_faces)
        assert s["description"].startswith(name + "(")


def test_frames_with_the_same_bodies_share_their_faces(solids_run):
    _, path = solids_run
    with h5py.File(path, "r") as f:
        fr = f["frames"]
        start, count = fr["solid_face_start"][:], fr["solid_face_count"][:]
        # frames 0-2 hold the same bodies, 3-4 the cylinders too
        assert len(set(start[:3])) == 1 and len(set(start[3:])) == 1
        assert len(f["solids/faces"]) == count[0] + count[3]
        assert f["solids/vertices"].attrs["unit"] == "m"


def test_paraview_reads_the_solids_beside_the_elements(solids_run):
    pytest.importorskip("vtkmodules.vtkIOXdmf2")
    from test_paraview_output import _at, _read  # (VTK's XDMF reader)
    from vtkmodules.util.numpy_support import vtk_to_numpy

    _, path = solids_run
    run = dpm.load(path)
    times, solids = _read(path.with_suffix(".solids.xdmf"))
    etimes, _ = _read(path.with_suffix(".elements.xdmf"))
    assert times == etimes == pytest.approx(list(run.times))
    for k, t in enumerate(times):
        grid = _at(solids, t)
        s = run.solids(k)
        assert grid.GetNumberOfCells() == len(s["faces"]) > 0
        assert {grid.GetCellType(i) for i in range(0, grid.GetNumberOfCells(), 97)} == {5}
        np.testing.assert_array_equal(vtk_to_numpy(grid.GetPoints().GetData()),
                                      s["vertices"])
        cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 3)
        np.testing.assert_array_equal(cells, s["faces"])
        for name in ("body_id", "shape"):
            np.testing.assert_array_equal(vtk_to_numpy(grid.GetCellData().GetArray(name)),
                                          s[name])


def test_resume_goes_on_with_the_solids(tmp_path, solids_run):
    sim, path = solids_run
    ref = dpm.load(path)
    copy = shutil.copy(path, tmp_path / "copy.h5")
    with contextlib.closing(Writer.resume(copy, sim, frames=4, removed=0)) as w:
        w.write(sim)  # the state at the end of the run: frame 4 anew
    run = dpm.load(copy)
    assert run.n_frames == 5 and len(run.solid_shapes) == 3  # (its meshes found again)
    for k, name in itertools.product(range(5), ("vertices", "faces", "body_id", "shape")):
        np.testing.assert_array_equal(run.solids(k)[name], ref.solids(k)[name], err_msg=name)


def test_the_option_is_checked_and_the_layout_fixed(tmp_path):
    sim, m = _scene()
    _add(sim, m, "cube", 0.004, 1)
    with pytest.raises(ParameterError, match=r"solids='yes'; allowed: True or False"):
        sim.output(tmp_path / "run.h5", every_steps=10, solids="yes")
    sim.output(tmp_path / "run.h5", every_steps=10)
    sim.run(steps=10, progress=False)
    with pytest.raises(ParameterError, match="solids=False; its layout is fixed"):
        sim.output(tmp_path / "run.h5", every_steps=10, solids=True)
    sim.close()
    run = dpm.load(tmp_path / "run.h5")
    assert run.solid_shapes == []
    with pytest.raises(KeyError, match="solids=True"):
        run.solids(0)
    assert not (tmp_path / "run.solids.xdmf").exists()


def test_sphere_scenes_write_empty_solids(tmp_path):
    sim, m = _scene()
    sim.add_particles("sphere", material=m, radius=1e-3, positions=[[0.006, 0.006, 0.002]])
    sim.output(tmp_path / "run.h5", every_steps=10, solids=True)
    sim.run(steps=20, progress=False)
    sim.close()
    run = dpm.load(tmp_path / "run.h5")
    assert run.n_frames == 3
    assert all(len(run.solids(k)["faces"]) == 0 for k in range(3))
    pytest.importorskip("vtkmodules.vtkIOXdmf2")
    from test_paraview_output import _at, _read

    times, reader = _read(tmp_path / "run.solids.xdmf")
    assert times == pytest.approx(list(run.times))
    assert _at(reader, times[-1]).GetNumberOfCells() == 0


# ---------------------------------------------------------------- the scene
def test_the_scene_description_round_trips(solids_run):
    sim, path = solids_run
    run = dpm.load(path)
    description = json.loads(json.dumps(scene_description(sim), sort_keys=True))
    assert run.scene == description
    assert run.attrs["scene_fingerprint"] == fingerprint(scene_description(sim))
    assert run.scene["boundaries"][0]["kind"] == "box"
    assert run.scene_toml is None and run.scene_file is None  # (built in Python)


def test_a_toml_scene_is_stored_with_its_text(tmp_path):
    from test_cli_scene import SCENE  # (spheres on a plane, read from p.csv)

    from dpm.cli import main

    np.savetxt(tmp_path / "p.csv", [[0, 0, 2e-3, 0, 0, 0, 1e-3], [5e-3, 0, 2e-3, 0, 0, 0,
                                                                  1e-3]],
               delimiter=",", header="x,y,z,vx,vy,vz,r", comments="")
    out = tmp_path / "out.h5"
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(out=out))
    assert main(["run", str(scene), "--no-progress"]) == 0
    run = dpm.load(out)
    assert run.scene_toml == scene.read_text()
    assert run.scene_file == str(scene)
    assert run.scene["materials"][0]["name"] == "glass"
    assert "hertz" in run.scene["contacts"]["glass-glass"]["type"].lower()


def test_a_file_without_the_scene_still_loads(tmp_path, solids_run):
    _, path = solids_run
    old = tmp_path / "old.h5"
    shutil.copy(path, old)
    with h5py.File(old, "r+", libver="latest") as f:  # (as written before the scene was)
        for name in ("scene", "scene_fingerprint"):
            del f.attrs[name]
    run = dpm.load(old, repair_xdmf=False)
    assert run.scene is None and run.scene_toml is None
    assert run.n_frames == 5


def test_a_frame_without_all_its_solid_rows_is_dropped(tmp_path, solids_run):
    _, path = solids_run
    copy = tmp_path / "cut.h5"
    shutil.copy(path, copy)
    with h5py.File(copy, "r+", libver="latest") as f:  # (a kill while the rows were written)
        f["solids/vertices"].resize(len(f["solids/vertices"]) - 1, axis=0)
    with pytest.warns(UserWarning, match="rewrote"):
        run = dpm.load(copy)
    assert run.n_frames == 4
    assert run.solids(-1)["vertices"].shape == dpm.load(path).solids(3)["vertices"].shape
