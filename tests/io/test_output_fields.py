"""The optional output: per-particle force, torque, contact count and rotation
(``sim.output(fields=...)``) and the touching pairs with their forces (``contacts=True``),
each against a reference computed without them.

References: Newton's third law (the particle forces of a frame sum to the weight less the
boundaries' reactions, which the boundary loads give independently), a k-d tree count of
the overlapping pairs (scipy's cKDTree) plus the box's planes within a radius, the weights
above each contact of a resting column, the force rows of the two-pass force form (the
fused pass keeps none: its pair forces are evaluated again), scipy's rotation matrices of
the quaternions, and VTK's own readers and tensor glyph filter for what ParaView sees.
"""

import numpy as np
import pytest

import dpm
from dpm.errors import ParameterError
from dpm.io.contacts import pair_forces, rotation_columns

G = 9.81
R = 1e-3


def _scene(positions, device=None, friction=0.5):
    """Spheres in a box open at the top: the laws and boundary of tests/io/test_io.py (the
    same compiled step)."""
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -G), device=device)
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=friction)
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.008, 0.008, 0.02),
                     open="+z")
    sim.add_particles("sphere", material=m, radius=R, positions=positions)
    return sim


def _packing():
    return _scene(dpm.lattice((0.0011, 0.0011, 0.0011), (0.0069, 0.0069, 0.012), 2.1e-3,
                              jitter=5e-5, seed=1))


def _column(n=5, device=None):
    """n spheres stacked on the floor, 1 % of a radius apart."""
    z = R * (1 + 2.02 * np.arange(n))
    return _scene(np.column_stack([np.full(n, 0.004), np.full(n, 0.004), z]), device)


@pytest.fixture(scope="module")
def packing_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("fields") / "packing.h5"
    sim = _packing()
    sim.output(path, every_steps=1000, fields="all", contacts=True)
    sim.run(steps=4000, progress=False)
    sim.close()
    return sim, path


@pytest.fixture(scope="module")
def column_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("fields") / "column.h5"
    sim = _column()
    sim.output(path, every_steps=2500, fields=("force", "contact_count"), contacts=True)
    sim.run(steps=10000, progress=False)
    sim.close()
    return sim, path


# ---------------------------------------------------------------- the option
@pytest.mark.parametrize("kwargs, words", [
    ({"fields": "forces"}, ["fields='forces'", "'forces' is not a field", "force, torque",
                            "contact_count", "rotation", "'all'"]),
    ({"fields": ("force", 3)}, ["fields=('force', 3)", "3 is not a field"]),
    ({"fields": 7}, ["fields=7", "allowed"]),
    ({"contacts": "yes"}, ["contacts='yes'", "True or False"]),
])
def test_a_bad_option_is_refused_before_any_step(tmp_path, kwargs, words):
    sim = _column(2)
    with pytest.raises(ParameterError) as err:
        sim.output(tmp_path / "run.h5", every_steps=10, **kwargs)
    for w in words:
        assert w in str(err.value)
    assert sim.step_count == 0 and not (tmp_path / "run.h5").exists()


def test_fields_by_name_all_and_the_layout_is_fixed_while_written(tmp_path):
    import h5py

    sim = _column(2)
    sim.output(tmp_path / "a.h5", every_steps=10, fields=["rotation", "force"])
    assert sim._output_fields == ("force", "rotation")  # (the table's order)
    sim.output(tmp_path / "a.h5", every_steps=10, fields="torque")
    sim.run(steps=10, progress=False)
    with h5py.File(tmp_path / "a.h5", "r") as f:
        extra = {"force", "torque", "contact_count", "rotation"} & set(f["particles"])
        assert extra == {"torque"} and "contacts" not in f
    with pytest.raises(ParameterError, match="layout is fixed"):
        sim.output(tmp_path / "a.h5", every_steps=10, fields="all")
    sim.output(tmp_path / "a.h5", every_steps=20, fields="torque")  # the same: appends
    sim.close()


# ---------------------------------------------------------------- per-particle fields
def test_particle_forces_sum_to_weight_less_the_boundary_reactions(packing_run):
    """Pair forces cancel in the sum over the bodies (Newton's third law), so the frame's
    forces add up to M g plus the boundaries' pushes on the particles, -sum of the loads
    on the boundaries (summed by the step from the boundary rows alone)."""
    sim, path = packing_run
    run = dpm.load(path)
    assert run.n_frames == 5
    weight = np.array([0.0, 0.0, -G]) * sim.bodies.mass.sum()
    for k in range(run.n_frames):
        f = run.frame(k)
        total = f["force"].sum(axis=0)
        expected = weight - run.boundary_force[k].sum(axis=0)
        np.testing.assert_allclose(total, expected, rtol=0, atol=1e-12 * np.abs(weight[2]))
    last = run.frame(-1)
    np.testing.assert_array_equal(last["force"], sim.bodies.force)
    np.testing.assert_array_equal(last["torque"], sim.bodies.torque)


def test_contact_count_matches_a_kd_tree_count(packing_run):
    from scipy.spatial import cKDTree

    sim, path = packing_run
    run = dpm.load(path)
    lo, hi = np.zeros(3), np.array([0.008, 0.008, np.inf])
    seen = 0
    for k in range(run.n_frames):
        f = run.frame(k)
        x, r = f["position"], f["radius"]
        pairs = cKDTree(x).query_pairs(2 * r.max(), output_type="ndarray")
        d = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
        touch = pairs[d < r[pairs[:, 0]] + r[pairs[:, 1]]]
        expected = np.bincount(touch.ravel(), minlength=len(x))
        walls = np.concatenate([x - lo, hi - x], axis=1) < r[:, None]  # the five planes
        expected += walls.sum(axis=1)
        np.testing.assert_array_equal(f["contact_count"], expected, err_msg=f"frame {k}")
        seen += expected.sum()
    assert seen > 0


def test_clustered_bodies_count_their_element_contacts(tmp_path):
    """Cylinders of sphere elements (the two-pass force form: the pair rows are read):
    each body's count is that of its elements' overlaps with other bodies' elements (a
    k-d tree over the elements) and with the box's planes; the pairs written are the
    touching element pairs; the forces obey Newton's third law."""
    from scipy.spatial import cKDTree

    sim = dpm.Simulation(dt=1e-5, dt_check="off", gravity=(0, 0, -G))
    steel = dpm.Material("steel", density=7800, young=1e7, poisson=0.3)
    sim.contact(steel, steel, model="hertz_mindlin", restitution=0.5, friction=0.5)
    lo, hi = np.array([-0.01, -0.01, 0.0]), np.array([0.01, 0.01, np.inf])
    sim.add_boundary("box", material=steel, lower=lo, upper=(0.01, 0.01, 0.03), open="+z")
    sim.add_particles("cylinder", material=steel, r=0.5e-3, l=2e-3, resolution=0.2,
                      positions=dpm.lattice((-0.007, -0.007, 0.002), (0.007, 0.007, 0.01),
                                            2.5e-3))
    path = tmp_path / "cylinders.h5"
    sim.output(path, every_steps=10000, fields=("force", "contact_count"), contacts=True)
    sim.run(steps=20000, progress=False)
    sim.close()
    run = dpm.load(path)
    for k in range(run.n_frames):
        f, e, c = run.frame(k), run.elements(k), run.contacts(k)
        x, r, body = e["position"], e["radius"], e["body_id"]
        pairs = cKDTree(x).query_pairs(2 * r.max(), output_type="ndarray")
        pairs = pairs[body[pairs[:, 0]] != body[pairs[:, 1]]]
        d = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
        touch = pairs[d < r[pairs[:, 0]] + r[pairs[:, 1]]]
        walls = (np.concatenate([x - lo, hi - x], axis=1) < r[:, None]).sum(axis=1)
        per_element = np.bincount(touch.ravel(), minlength=len(x)) + walls
        expected = {i: per_element[body == i].sum() for i in f["id"]}
        assert dict(zip(f["id"], f["contact_count"], strict=True)) == expected
        assert sorted(map(tuple, np.sort(c["id"], axis=1))) == \
            sorted(map(tuple, np.sort(body[touch], axis=1)))
        weight = np.array([0.0, 0.0, -G]) * f["mass"].sum()
        np.testing.assert_allclose(f["force"].sum(axis=0),
                                   weight - run.boundary_force[k].sum(axis=0), rtol=0,
                                   atol=1e-12 * G * f["mass"].sum())
    assert len(run.contacts(-1)["id"]) > 20


def test_rotation_is_the_quaternions_matrix_column_by_column(packing_run):
    from scipy.spatial.transform import Rotation

    _, path = packing_run
    f = dpm.load(path).frame(-1)
    q = f["orientation"]
    assert np.abs(q[:, 1:]).max() > 1e-6  # (the bodies did turn)
    ref = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()  # scalar last in scipy
    np.testing.assert_allclose(f["rotation"].reshape(-1, 3, 3), ref.transpose(0, 2, 1),
                               atol=1e-14)
    rng = np.random.default_rng(3)
    q = rng.normal(size=(50, 4))
    ref = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()
    np.testing.assert_allclose(rotation_columns(q).reshape(-1, 3, 3),
                               ref.transpose(0, 2, 1), atol=1e-14)


# ---------------------------------------------------------------- contacts
def test_a_resting_column_carries_the_weight_above_each_contact(column_run):
    sim, path = column_run
    run = dpm.load(path)
    c = run.contacts(-1)
    f = run.frame(-1)
    ids = sim.bodies.id
    z = dict(zip(f["id"], f["position"][:, 2], strict=True))
    n = len(ids)
    assert len(c["id"]) == n - 1  # one pair between neighbours; the floor is not a pair
    m = sim.bodies.mass[0]
    for (a, b), fn, force, ends, point in zip(c["id"], c["normal_force"], c["force"],
                                              c["ends"], c["point"], strict=True):
        upper = a if z[a] > z[b] else b
        above = sum(1 for k in ids if z[k] >= z[upper])
        assert fn == pytest.approx(above * m * G, rel=1e-4)  # (at rest to 1e-5)
        # the force on the first body pushes it away from the second
        assert np.sign(force[2]) == np.sign(z[a] - z[b])
        np.testing.assert_allclose(np.abs(force[:2]), 0, atol=1e-12 * fn)
        np.testing.assert_array_equal(ends[:, 2], [z[a], z[b]])
        assert min(z[a], z[b]) < point[2] < max(z[a], z[b])
    np.testing.assert_array_equal(np.sort(f["contact_count"]), [1] + [2] * (n - 1))
    np.testing.assert_allclose(f["force"][:, 2], 0, atol=1e-4 * m * G)  # at rest


def test_evaluated_pair_forces_equal_the_two_pass_rows_and_change_nothing():
    """The fused pass keeps no force rows: its pair forces are evaluated again (dt = 0,
    on copies). On the two-pass form, which stores every pair's row, both agree; and the
    evaluation leaves every array of the state as it was."""
    from dpm.backends import CpuBackend

    sim = _column(4, CpuBackend(force_pass="two_pass"))
    sim.run(steps=1500, progress=False)  # still moving: dashpots and springs at work
    before = {(name, field): getattr(lst, field)[:lst.count].copy()
              for name, lst in (("pairs", sim.contacts), ("walls", sim.wall_contacts))
              for field in ("history", "active", "force")}
    force = sim.bodies.force.copy()
    rows = pair_forces(sim, evaluate=False)
    again = pair_forces(sim, evaluate=True)
    assert len(rows["i"]) == 3 and np.abs(rows["force"]).max() > 0
    np.testing.assert_allclose(again["force"], rows["force"], rtol=0,
                               atol=1e-12 * np.abs(rows["force"]).max())
    for name, lst in (("pairs", sim.contacts), ("walls", sim.wall_contacts)):
        for field in ("history", "active", "force"):
            np.testing.assert_array_equal(getattr(lst, field)[:lst.count],
                                          before[name, field], err_msg=f"{name} {field}")
    np.testing.assert_array_equal(sim.bodies.force, force)


def test_contact_output_does_not_change_the_run(tmp_path, packing_run):
    sim, _ = packing_run
    plain = _packing()
    plain.run(steps=4000, progress=False)
    np.testing.assert_array_equal(plain.bodies.position, sim.bodies.position)
    np.testing.assert_array_equal(plain.bodies.velocity, sim.bodies.velocity)


# ---------------------------------------------------------------- files
def test_resume_keeps_the_contact_rows_of_the_kept_frames(tmp_path, packing_run):
    import shutil

    from dpm.io.hdf5 import Writer

    sim, path = packing_run
    copy = tmp_path / "copy.h5"
    shutil.copy(path, copy)
    ref = dpm.load(path)
    w = Writer.resume(copy, sim, frames=3, removed=0)
    w.write(sim)  # the state at the end of the run: frame 3 anew
    w.close()
    run = dpm.load(copy)
    assert run.n_frames == 4
    for k in range(3):
        for name, value in ref.contacts(k).items():
            np.testing.assert_array_equal(run.contacts(k)[name], value)
    for name, value in ref.contacts(-1).items():
        np.testing.assert_array_equal(run.contacts(3)[name], value)
    np.testing.assert_array_equal(run.frame(3)["contact_count"], ref.frame(-1)["contact_count"])


def test_a_frame_without_all_its_contact_rows_is_dropped(tmp_path, packing_run):
    import shutil

    import h5py

    _, path = packing_run
    copy = tmp_path / "cut.h5"
    shutil.copy(path, copy)
    with h5py.File(copy, "r+", libver="latest") as f:
        fr = f["frames"]
        end = int(fr["contact_start"][-1] + fr["contact_count"][-1])
        assert fr["contact_count"][-1] > 0
        f["contacts/force"].resize(end - 1, axis=0)  # (a kill while the rows were written)
    with pytest.warns(UserWarning, match="rewrote"):
        run = dpm.load(copy)
    assert run.n_frames == 4


def test_paraview_reads_the_fields_and_the_contact_lines(packing_run):
    """VTK's XDMF reader (what ParaView's XDMF readers build on) sees the new fields as
    point attributes (the rotation a 9-component tensor) and the contacts as 2-node lines
    between the body centres with their forces as cell attributes."""
    vtk_xdmf = pytest.importorskip("vtkmodules.vtkIOXdmf2")
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as P

    _, path = packing_run
    run = dpm.load(path)

    def read(suffix):
        r = vtk_xdmf.vtkXdmfReader()
        r.SetFileName(str(path.with_suffix(suffix)))
        r.UpdateInformation()
        return list(r.GetOutputInformation(0).Get(P.TIME_STEPS())), r

    times, particles = read(".xdmf")
    ctimes, lines = read(".contacts.xdmf")
    assert times == ctimes == pytest.approx(list(run.times))
    for k, t in enumerate(times):
        particles.UpdateTimeStep(t)
        pd = particles.GetOutputDataObject(0).GetPointData()
        f = run.frame(k)
        for name in ("force", "torque", "contact_count", "rotation"):
            a = pd.GetArray(name)
            assert a is not None, name
            np.testing.assert_array_equal(vtk_to_numpy(a), f[name], err_msg=name)
        assert pd.GetArray("rotation").GetNumberOfComponents() == 9
        lines.UpdateTimeStep(t)
        grid = lines.GetOutputDataObject(0)
        c = run.contacts(k)
        nc = len(c["id"])
        assert grid.GetNumberOfCells() == nc
        if nc == 0:
            continue
        assert {grid.GetCellType(i) for i in range(nc)} == {4}  # VTK_POLY_LINE
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        conn = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 2)
        np.testing.assert_array_equal(pts[conn], c["ends"])
        cd = grid.GetCellData()
        for name in ("force", "normal_force", "overlap", "point"):
            np.testing.assert_array_equal(vtk_to_numpy(cd.GetArray(name)), c[name],
                                          err_msg=name)
        np.testing.assert_array_equal(vtk_to_numpy(cd.GetArray("id_i")), c["id"][:, 0])
        np.testing.assert_array_equal(vtk_to_numpy(cd.GetArray("id_j")), c["id"][:, 1])


def test_a_tensor_glyph_turns_with_the_body():
    """VTK's tensor glyph (ParaView's Tensor Glyph filter, eigenvalues not extracted)
    takes the rotation's columns as the glyph's axes: a unit segment along x becomes the
    body's first principal axis."""
    pytest.importorskip("vtkmodules.vtkFiltersCore")
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkPolyData
    from vtkmodules.vtkFiltersCore import vtkTensorGlyph
    from vtkmodules.vtkFiltersSources import vtkLineSource

    rng = np.random.default_rng(5)
    q = rng.normal(size=(4, 4))
    rot = rotation_columns(q)
    centres = rng.random((4, 3))
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(centres))
    data = vtkPolyData()
    data.SetPoints(pts)
    tensors = numpy_to_vtk(rot)
    tensors.SetName("rotation")
    data.GetPointData().SetTensors(tensors)
    line = vtkLineSource()
    line.SetPoint1(0, 0, 0)
    line.SetPoint2(1, 0, 0)
    glyph = vtkTensorGlyph()
    glyph.SetInputData(data)
    glyph.SetSourceConnection(line.GetOutputPort())
    glyph.ExtractEigenvaluesOff()
    glyph.ColorGlyphsOff()
    glyph.Update()
    out = vtk_to_numpy(glyph.GetOutput().GetPoints().GetData()).reshape(4, 2, 3)
    from dpm.shapes.geometry import matrix_from_quaternion

    for k in range(4):
        axis = matrix_from_quaternion(q[k])[:, 0]
        np.testing.assert_allclose(out[k, 0], centres[k], atol=1e-6)
        np.testing.assert_allclose(out[k, 1] - out[k, 0], axis, atol=1e-6)


def test_a_pair_across_a_periodic_boundary_is_drawn_to_the_nearest_image(monkeypatch):
    """Two spheres touching through the periodic face x = 0 | 1: the line ends at the
    image of the second body beside the first, the contact point lies between them."""
    from types import SimpleNamespace

    import dpm.io.contacts as contacts
    from dpm.state import Contacts

    # a stand-in state whose force rows hold the forces
    monkeypatch.setattr(contacts, "_rows_hold_forces", lambda sim: True)
    c = Contacts(2, 16)
    c.use_rows(True)
    c.start[:] = [0, 1, 1]
    c.key[0], c.active[0] = 1, 1
    c.force[0, :3] = [0.5, 0.0, 0.0]
    x = np.array([[0.0005, 0.2, 0.3], [0.9993, 0.2, 0.3]])
    bodies = SimpleNamespace(position=x, id=np.array([7, 9]))
    elements = SimpleNamespace(position=x, radius=np.array([1e-3, 1e-3]), owner=np.arange(2))
    sim = SimpleNamespace(bodies=bodies, elements=elements, contacts=c,
                          period=np.array([0.0, 0, 0, 1.0, 0, 0]))
    rows = contacts.contact_rows(sim)
    np.testing.assert_array_equal(rows["id"], [[7, 9]])
    np.testing.assert_allclose(rows["ends"][0], [x[0], x[1] - [1.0, 0, 0]], atol=1e-15)
    assert rows["overlap"][0] == pytest.approx(2e-3 - 1.2e-3, rel=1e-9)
    # the middle of the overlap: 1 mm - 0.4 mm from the first centre, towards the image
    np.testing.assert_allclose(rows["point"][0], [0.0005 - 0.6e-3, 0.2, 0.3], atol=1e-15)
    assert rows["normal_force"][0] == pytest.approx(0.5)

