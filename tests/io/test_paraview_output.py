"""What ParaView sees: the XDMF sidecars read back by VTK's own XDMF reader (the VTK
wheel, an independent reader) equal the state, and the boundaries' surfaces move with
their motions.

References: the HDF5 datasets written from the state; the boundary surfaces against
trimesh's rotation of the t = 0 surface by the drum's known angle (omega t) and against
the exact areas of a box and a frustum; the quaternion read as 4 components per particle.
"""

import math

import numpy as np
import pytest

import dpm
from dpm.io.surfaces import SEGMENTS, boundary_surface

vtk_xdmf = pytest.importorskip("vtkmodules.vtkIOXdmf2")
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
from vtkmodules.vtkCommonExecutionModel import (  # noqa: E402
    vtkStreamingDemandDrivenPipeline as Pipeline,
)

RPM = 60.0


def _read(path):
    """(times, reader) of an XDMF file opened with vtkXdmfReader."""
    r = vtk_xdmf.vtkXdmfReader()
    r.SetFileName(str(path))
    r.UpdateInformation()
    return list(r.GetOutputInformation(0).Get(Pipeline.TIME_STEPS())), r


def _at(reader, t):
    reader.UpdateTimeStep(t)
    return reader.GetOutputDataObject(0)


def _array(data, name):
    a = data.GetArray(name)
    assert a is not None, name
    return vtk_to_numpy(a)


@pytest.fixture(scope="module")
def drum_run(tmp_path_factory):
    """A rotating drum (tube with caps at 60 rpm) over a floor plane, spheres and
    cylinders of two materials, three frames."""
    out = tmp_path_factory.mktemp("pv") / "drum.h5"
    sim = dpm.Simulation(dt=1e-5, dt_check="off", gravity=(0, 0, -9.81))
    steel = dpm.Material("steel", density=7800, young=1e7, poisson=0.3)
    glass = dpm.Material("glass", density=2500, young=5e7, poisson=0.3)
    for a, b in ((steel, steel), (glass, steel), (glass, glass)):
        sim.contact(a, b, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.add_boundary("tube", material=steel, start=(0, 0, 0), axis=(0, 1, 0), length=0.02,
                     radius=0.02, caps="both", motion=dpm.Rotation(axis=(0, 1, 0), rpm=RPM))
    sim.add_boundary("box", material=steel, lower=(-0.03, -0.01, -0.03),
                     upper=(0.03, 0.03, 0.03), open="+z")
    xyz = dpm.lattice((-0.01, 0.003, -0.01), (0.01, 0.017, 0.0), 2.5e-3)
    half = len(xyz) // 2
    sim.add_particles("sphere", material=glass, radius=1e-3, positions=xyz[:half])
    sim.add_particles("cylinder", material=steel, r=0.5e-3, l=2e-3, resolution=0.2,
                      positions=xyz[half:])
    sim.output(out, every=0.01)
    sim.run(until=0.02, progress=False)
    sim.close()
    return sim, out


def test_particles_read_back_by_vtk_equal_the_file(drum_run):
    sim, out = drum_run
    run = dpm.load(out)
    times, reader = _read(out.with_suffix(".xdmf"))
    assert times == pytest.approx(list(run.times))
    for k, t in enumerate(times):
        grid = _at(reader, t)
        frame = run.frame(k)
        np.testing.assert_array_equal(vtk_to_numpy(grid.GetPoints().GetData()),
                                      frame["position"])
        pd = grid.GetPointData()
        q = _array(pd, "orientation")
        assert q.shape == (len(frame["id"]), 4)  # a 4-vector per particle, not one tuple
        np.testing.assert_array_equal(q, frame["orientation"])
        for name in ("id", "velocity", "angular_velocity", "radius", "mass", "material",
                     "shape"):
            np.testing.assert_array_equal(_array(pd, name), frame[name], err_msg=name)
    last = run.frame(-1)
    by_id = np.argsort(sim.bodies.id)
    np.testing.assert_array_equal(last["material"], sim.bodies.material[by_id])
    names = list(run.attrs["shapes"])
    assert names == ["sphere", "cylinder"]
    assert {names[s] for s in last["shape"]} == {"sphere", "cylinder"}
    assert run.attrs["materials"].tolist() == ["steel", "glass"]


def test_boundaries_read_back_by_vtk_move_with_the_drum(drum_run):
    """Each frame's triangles are the t = 0 surface turned by omega t about the drum's
    axis (trimesh's rotation matrix); the box does not move; every triangle carries its
    boundary's index."""
    import h5py
    import trimesh

    sim, out = drum_run
    times, reader = _read(out.with_suffix(".boundaries.xdmf"))
    with h5py.File(out, "r") as f:
        local = f["surfaces/local_vertices"][:]
        vowner = f["surfaces/vertex_boundary"][:]
        faces = f["surfaces/faces"][:]
        owner = f["surfaces/boundary"][:]
        assert f["boundaries/surface"].attrs["unit"] == "m"
    tube_v, tube_f = boundary_surface(sim.boundaries[0])
    box_v, box_f = boundary_surface(sim.boundaries[1])
    np.testing.assert_array_equal(local[vowner == 0], tube_v)
    np.testing.assert_array_equal(local[vowner == 1], box_v)
    assert len(times) == 3
    for t in times:
        grid = _at(reader, t)
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        angle = 2 * math.pi * RPM / 60.0 * t
        rot = trimesh.transformations.rotation_matrix(angle, (0, 1, 0))[:3, :3]
        np.testing.assert_allclose(pts[vowner == 0], tube_v @ rot.T, atol=1e-15)
        np.testing.assert_array_equal(pts[vowner == 1], box_v)
        cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 3)
        np.testing.assert_array_equal(cells, faces)
        np.testing.assert_array_equal(_array(grid.GetCellData(), "boundary"), owner)


def test_surfaces_have_the_area_of_the_boundaries():
    """A box without its lid: five faces; a tube with both caps: the frustum's lateral
    area and two discs, to the polygon's ratio sin(2 pi / n) n / (2 pi)."""
    import trimesh

    steel = dpm.Material("steel", density=7800, young=1e7, poisson=0.3)
    box = dpm.boundaries.Box(steel, lower=(0, 0, 0), upper=(1.0, 2.0, 3.0), open="+z")
    v, f = boundary_surface(box)
    # -x, +x: 2 x 3 each; -y, +y: 1 x 3 each; -z: 1 x 2
    assert trimesh.Trimesh(v, f, process=False).area == pytest.approx(20.0, rel=1e-12)
    r0, r1, length = 0.5, 0.3, 1.0
    tube = dpm.boundaries.Tube(steel, start=(0, 0, 0), axis=(0, 0, 1), length=length,
                               radius_start=r0, radius_end=r1, caps="both")
    v, f = boundary_surface(tube)
    poly = math.sin(2 * math.pi / SEGMENTS) * SEGMENTS / (2 * math.pi)
    chord = math.cos(math.pi / SEGMENTS)  # the facets' slant and the caps' apothem
    lateral = math.pi * (r0 + r1) * math.hypot(length, (r0 - r1) * chord) * \
        math.sin(math.pi / SEGMENTS) / (math.pi / SEGMENTS)
    caps = poly * math.pi * (r0**2 + r1**2)
    assert trimesh.Trimesh(v, f, process=False).area == pytest.approx(lateral + caps,
                                                                       rel=1e-9)
