"""dpm with other tools: LIGGGHTS' files read into dpm, a frame as a pandas DataFrame, the
XDMF sidecars read by VTK's XDMF reader without an error line, and the picture of a frame
with its boundaries.

References: the text LIGGGHTS itself writes (``liggghts`` runs a small input here: a data
file from ``write_data`` and ``dump custom`` files of the same state), parsed again in the
test by a plain split of its lines, and the same state in LIGGGHTS' other format; VTK's
``vtkXdmfReader`` (what ParaView's "XDMF Reader" is) in a separate process, its output
captured whole (VTK's error lines and the XDMF library's own ``Alloc ::`` lines), against
the HDF5 datasets; scipy's rotation matrices of the quaternions.
"""

import json
import math
import shutil
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import dpm
from dpm.errors import DpmError, ParameterError
from dpm.io import liggghts

LIGGGHTS = shutil.which("liggghts")
needs_liggghts = pytest.mark.skipif(
    LIGGGHTS is None, reason="liggghts is not on PATH (Debian: apt-get install liggghts); "
                             "the tests compare dpm's readers with files LIGGGHTS writes")

# 30 spheres of two types (radius 1 mm, 2500 kg/m3; 1.5 mm, 7800 kg/m3) poured with a
# velocity and a spin onto a floor: 2000 steps, dumps at 1000 and 2000 (one file per
# step in post/, and both in all.dump with scaled positions and diameters), the data file
# at step 2000
INPUT = """\
atom_style	granular
atom_modify	map array
boundary	f f f
newton		off
communicate	single vel yes
units		si
region		reg block 0 0.02 0 0.02 0 0.04 units box
create_box	2 reg
neighbor	0.0005 bin
neigh_modify	delay 0
fix m1 all property/global youngsModulus peratomtype 5.e6 5.e6
fix m2 all property/global poissonsRatio peratomtype 0.3 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 2 0.5 0.5 0.5 0.5
fix m4 all property/global coefficientFriction peratomtypepair 2 0.5 0.5 0.5 0.5
pair_style gran model hertz tangential history
pair_coeff	* *
timestep	0.00001
fix gravi all gravity 9.81 vector 0.0 0.0 -1.0
fix zwall all wall/gran model hertz tangential history primitive type 1 zplane 0.0
region		ins block 0.002 0.018 0.002 0.018 0.005 0.035 units box
fix pts1 all particletemplate/sphere 15485863 atom_type 1 density constant 2500 &
    radius constant 0.001
fix pts2 all particletemplate/sphere 15485867 atom_type 2 density constant 7800 &
    radius constant 0.0015
fix pdd1 all particledistribution/discrete 32452843 2 pts1 0.5 pts2 0.5
fix ins all insert/pack seed 32452867 distributiontemplate pdd1 maxattempt 200 &
    insert_every once overlapcheck yes all_in yes vel constant 0.05 -0.05 -0.3 &
    omega constant 1 2 3 region ins particles_in_region 30
fix integr all nve/sphere
run		1
dump dmp all custom 1000 post/dump*.liggghts id type type x y z ix iy iz vx vy vz &
    fx fy fz omegax omegay omegaz radius mass
dump dmp2 all custom 1000 all.dump id type xs ys zs vx vy vz diameter
run		1999
write_data	data.out
"""


@pytest.fixture(scope="module")
def liggghts_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("liggghts")
    (d / "post").mkdir()
    (d / "in.dpm").write_text(INPUT)
    done = subprocess.run([LIGGGHTS, "-in", "in.dpm", "-log", "none", "-echo", "none"],
                          cwd=d, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    for name in ("data.out", "post/dump1000.liggghts", "post/dump2000.liggghts", "all.dump"):
        assert (d / name).exists(), f"LIGGGHTS wrote no {name}:\n{done.stdout[-3000:]}"
    return d


def _plain_section(text, name):
    """The rows of a data file's section, split on blanks: id -> values."""
    lines = text.splitlines()
    k = lines.index(name)
    rows = {}
    for line in lines[k + 1:]:
        if line.strip() and line.strip()[0].isalpha():
            break
        if line.strip():
            v = line.split()
            rows[int(v[0])] = [float(x) for x in v[1:]]
    return rows


def _plain_dump(text):
    """The snapshots of a dump, split on blanks: (timestep, {column: {id: value}})."""
    lines = text.splitlines()
    out = []
    for k, line in enumerate(lines):
        if line == "ITEM: TIMESTEP":
            step = int(lines[k + 1])
            n = int(lines[k + 3])
        if line.startswith("ITEM: ATOMS"):
            cols = line.split()[2:]
            table = {}
            for row in lines[k + 1:k + 1 + n]:
                v = row.split()
                atom = int(v[cols.index("id")])
                for c, name in enumerate(cols):
                    table.setdefault(name, {}).setdefault(atom, float(v[c]))
            out.append((step, table))
    return out


# ------------------------------------------------------------------ LIGGGHTS files
@needs_liggghts
def test_read_data_gives_what_liggghts_wrote(liggghts_files):
    path = liggghts_files / "data.out"
    text = path.read_text()
    atoms, vel = _plain_section(text, "Atoms"), _plain_section(text, "Velocities")
    d = liggghts.read_data(path)
    assert len(atoms) == len(vel) == 30 and "30 atoms" in text
    assert d["timestep"] == 2000 and d["atom_types"] == 2
    assert d["id"].tolist() == sorted(atoms)
    np.testing.assert_array_equal(d["box"]["lower"], [0, 0, 0])
    np.testing.assert_array_equal(d["box"]["upper"], [0.02, 0.02, 0.04])
    for k, atom in enumerate(d["id"]):
        typ, diameter, density, x, y, z, *image = atoms[atom]
        assert d["type"][k] == typ
        assert d["radius"][k] == diameter / 2 and d["density"][k] == density
        assert d["mass"][k] == pytest.approx(4 / 3 * math.pi * (diameter / 2) ** 3 * density,
                                             rel=1e-15)
        np.testing.assert_array_equal(d["position"][k], [x, y, z])
        np.testing.assert_array_equal(d["image"][k], image)
        np.testing.assert_array_equal(d["velocity"][k], vel[atom][0:3])
        np.testing.assert_array_equal(d["angular_velocity"][k], vel[atom][3:6])
    assert set(d["radius"]) == {0.001, 0.0015}
    # the run moved them: the spheres that reached the floor bounced and spin otherwise
    assert len(np.unique(d["velocity"][:, 2])) > 2
    assert len(np.unique(d["angular_velocity"][:, 0])) > 2


@needs_liggghts
def test_read_dump_gives_what_liggghts_wrote(liggghts_files):
    path = liggghts_files / "post" / "dump2000.liggghts"
    ((step, table),) = _plain_dump(path.read_text())
    (s,) = liggghts.read_dump(path)
    assert s["timestep"] == step == 2000 and s["box"]["boundary"] == ("ff", "ff", "ff")
    np.testing.assert_array_equal(s["box"]["upper"], [0.02, 0.02, 0.04])
    ids = sorted(table["id"])
    assert s["id"].tolist() == ids and len(ids) == 30

    def column(name):
        return np.array([table[name][i] for i in ids])

    np.testing.assert_array_equal(s["type"], column("type"))
    np.testing.assert_array_equal(s["radius"], column("radius"))
    np.testing.assert_array_equal(s["mass"], column("mass"))
    for key, cols in (("position", "x y z"), ("velocity", "vx vy vz"),
                      ("angular_velocity", "omegax omegay omegaz"), ("force", "fx fy fz"),
                      ("image", "ix iy iz")):
        np.testing.assert_array_equal(s[key], np.stack([column(c) for c in cols.split()], 1),
                                      err_msg=key)


@needs_liggghts
def test_the_dump_and_the_data_file_of_one_state_agree(liggghts_files):
    """Step 2000 in LIGGGHTS' two formats: the data file's 16 digits against the dump's
    6 (``%g``)."""
    d = liggghts.read_data(liggghts_files / "data.out")
    (s,) = liggghts.read_dump(liggghts_files / "post" / "dump2000.liggghts")
    np.testing.assert_array_equal(s["id"], d["id"])
    np.testing.assert_array_equal(s["type"], d["type"])
    for key in ("position", "radius", "velocity", "angular_velocity", "mass"):
        np.testing.assert_allclose(s[key], d[key], rtol=1e-5, atol=1e-12, err_msg=key)


@needs_liggghts
def test_a_dump_of_several_snapshots_with_scaled_positions(liggghts_files):
    snaps = liggghts.read_dump(liggghts_files / "all.dump")
    assert [s["timestep"] for s in snaps] == [1000, 2000]
    for s in snaps:
        (ref,) = liggghts.read_dump(liggghts_files / "post" / f"dump{s['timestep']}.liggghts")
        np.testing.assert_array_equal(s["id"], ref["id"])
        # xs = (x - xlo) / (xhi - xlo) to 6 digits, diameter = 2 radius
        np.testing.assert_allclose(s["position"], ref["position"], rtol=0, atol=1e-7)
        np.testing.assert_allclose(s["radius"], ref["radius"], rtol=1e-6)
        np.testing.assert_array_equal(s["velocity"], ref["velocity"])
        assert "angular_velocity" not in s and "diameter" in s["columns"]


@needs_liggghts
def test_liggghts_spheres_into_a_simulation(liggghts_files):
    d = liggghts.read_data(liggghts_files / "data.out")
    sim = dpm.Simulation(dt=1e-5, dt_check="off", gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.3)
    steel = dpm.Material("steel", density=7800, young=5e6, poisson=0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (the densities agree: no warning)
        ids = liggghts.add_particles(sim, d, material={1: glass, 2: steel})
    assert len(ids) == 30 and len(set(ids.tolist())) == 30
    row = {int(i): k for k, i in enumerate(sim.bodies.id)}
    at = np.array([row[int(i)] for i in ids])
    b = sim.bodies
    np.testing.assert_array_equal(b.position[at], d["position"])
    np.testing.assert_array_equal(b.radius[at], d["radius"])
    np.testing.assert_array_equal(b.velocity[at], d["velocity"])
    np.testing.assert_array_equal(b.angular_velocity[at], d["angular_velocity"])
    assert [sim.materials[k].name for k in b.material[at]] == [
        "glass" if t == 1 else "steel" for t in d["type"]]
    np.testing.assert_allclose(b.mass[at], d["mass"], rtol=1e-12)
    # a dump snapshot goes in the same way; one material for all warns of type 2's density
    (s,) = liggghts.read_dump(liggghts_files / "post" / "dump2000.liggghts")
    sim2 = dpm.Simulation(dt=1e-5, dt_check="off")
    with pytest.warns(UserWarning, match=r"atom type 2 of .*dump2000.liggghts has density "
                                         r"7800.* its material 'glass' 2500"):
        ids2 = liggghts.add_particles(sim2, s, material=glass)
    row2 = {int(i): k for k, i in enumerate(sim2.bodies.id)}
    np.testing.assert_array_equal(sim2.bodies.position[[row2[int(i)] for i in ids2]],
                                  s["position"])


# ------------------------------------------------------------------ malformed files
DATA = """LAMMPS data file via write_data, timestep = 7

2 atoms
1 atom types

0 1 xlo xhi
0 1 ylo yhi
0 1 zlo zhi

Atoms # granular

1 1 0.002 2500 0.5 0.5 0.5 0 0 0
2 1 0.002 2500 0.5 0.5 0.6 0 0 0

Velocities

1 0 0 -1 0 0 0
2 0 0 -1 0 0 0
"""
DUMP = """ITEM: TIMESTEP
100
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS ff ff ff
0 1
0 1
0 1
ITEM: ATOMS id type x y z vx vy vz radius
2 1 0.5 0.5 0.6 0 0 -1 0.001
1 1 0.5 0.5 0.5 0 0 -1 0.001
"""


@pytest.mark.parametrize("reader,text,line,what", [
    ("data", DATA.replace("2 1 0.002 2500 0.5 0.5 0.6", "2 1 0.002 2500 0.5 x 0.6"), 13,
     "value 6, 'x', is not a number"),
    ("data", DATA.replace("2 1 0.002 2500 0.5 0.5 0.6 0 0 0\n", ""), 10,
     "the Atoms section has 1 line(s), the header says 2 atoms"),
    ("data", DATA.replace("1 1 0.002 2500 0.5 0.5 0.5 0 0 0", "1 1 0.5 0.5 0.5"), 12,
     "expected an Atoms line of atom_style sphere/granular: atom-ID atom-type diameter "
     "density x y z [ix iy iz] (7 or 10 numbers), got 5 value(s)"),
    ("data", DATA.replace("Atoms # granular", "Atoms # atomic"), 10,
     "atom_style 'atomic': expected sphere or granular"),
    ("data", DATA.replace("2 0 0 -1 0 0 0", "3 0 0 -1 0 0 0"), 18,
     "a velocity of atom-ID 3, which the Atoms section does not have"),
    ("data", DATA.replace("2 atoms", "2 atoms 3"), 3, "expected a header line"),
    ("dump", "ITEM: TIMESTEPS\n100\n", 1, "expected 'ITEM: TIMESTEP'"),
    ("dump", DUMP.replace("1 1 0.5 0.5 0.5 0 0 -1 0.001\n", ""), 10,
     "the snapshot of timestep 100 has 1 atom row(s), its NUMBER OF ATOMS says 2"),
    ("dump", DUMP.replace("2 1 0.5 0.5 0.6 0 0 -1 0.001", "2 1 0.5 0.5 0 0 -1 0.001"), 10,
     "expected an atom row of the columns id type x y z vx vy vz radius (9 numbers), "
     "got 8 value(s)"),
    ("dump", DUMP.replace("id type x y z", "id type a b c"), 1,
     "has no position columns (x y z, xu yu zu, xs ys zs or xsu ysu zsu)"),
    ("dump", DUMP.replace("100\nITEM: NUMBER", "1e2\nITEM: NUMBER"), 2,
     "expected the timestep (an integer), got '1e2'"),
])
def test_a_malformed_file_is_refused_naming_the_line(tmp_path, reader, text, line, what):
    path = tmp_path / f"bad.{reader}"
    path.write_text(text)
    read = liggghts.read_data if reader == "data" else liggghts.read_dump
    with pytest.raises(ParameterError) as e:
        read(path)
    assert str(e.value).startswith(f"{path}:{line}: "), str(e.value)
    assert what in str(e.value)


def test_handwritten_files_columns_in_any_order(tmp_path):
    (tmp_path / "data").write_text(DATA)
    d = liggghts.read_data(tmp_path / "data")
    assert d["timestep"] == 7 and d["id"].tolist() == [1, 2]
    np.testing.assert_array_equal(d["position"], [[0.5, 0.5, 0.5], [0.5, 0.5, 0.6]])
    np.testing.assert_array_equal(d["velocity"], [[0, 0, -1], [0, 0, -1]])
    (tmp_path / "dump").write_text(
        DUMP.replace("id type x y z vx vy vz radius", "radius z vz id y type vy x vx")
        .replace("2 1 0.5 0.5 0.6 0 0 -1 0.001", "0.001 0.6 -1 2 0.5 1 0 0.25 0")
        .replace("1 1 0.5 0.5 0.5 0 0 -1 0.001", "0.002 0.5 -2 1 0.5 1 0 0.75 0")
        + DUMP.replace("100", "200", 1).replace("ff ff ff", "pp pp ff"))
    a, b = liggghts.read_dump(tmp_path / "dump")
    assert (a["timestep"], b["timestep"]) == (100, 200) and b["box"]["boundary"] == (
        "pp", "pp", "ff")
    np.testing.assert_array_equal(a["id"], [1, 2])
    np.testing.assert_array_equal(a["position"], [[0.75, 0.5, 0.5], [0.25, 0.5, 0.6]])
    np.testing.assert_array_equal(a["velocity"], [[0, 0, -2], [0, 0, -1]])
    np.testing.assert_array_equal(a["radius"], [0.002, 0.001])
    assert "angular_velocity" not in a and "mass" not in a
    sim = dpm.Simulation(dt=1e-5, dt_check="off")
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.3)
    with pytest.raises(ParameterError, match=r"a list of 2 snapshot\(s\); pass one"):
        liggghts.add_particles(sim, [a, b], material=glass)
    with pytest.raises(ParameterError, match=r"no material for atom type\(s\) 1"):
        liggghts.add_particles(sim, a, material={2: glass})
    with pytest.raises(ParameterError, match="has no radii"):
        liggghts.add_particles(sim, {k: v for k, v in a.items() if k != "radius"},
                               material=glass)


# ------------------------------------------------------------------ a dpm run
@pytest.fixture(scope="module")
def run_path(tmp_path_factory):
    """A box, 16 spheres stacked in 4 columns that settle into contact (no contact in the
    first frames, 4 and 12 later), cylinders (clustered) poured in at 5 ms (no element
    and no solid in the first frames), every optional field, contacts and solids."""
    out = tmp_path_factory.mktemp("interop") / "run.h5"
    sim = dpm.Simulation(dt=1e-5, dt_check="off", gravity=(0, 0, -9.81))
    m = dpm.Material("glass", density=2500, young=1e7, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.5, friction=0.5)
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.02, 0.02, 0.03), open="+z")
    xyz = np.array([(x, y, 0.0012 + 2.3e-3 * k) for x in (0.006, 0.014)
                    for y in (0.006, 0.014) for k in range(4)])
    rng = np.random.default_rng(5)
    q = rng.normal(size=(len(xyz), 4))
    sim.add_particles("sphere", material=m, radius=1e-3, positions=xyz,
                      orientations=q / np.linalg.norm(q, axis=1, keepdims=True))
    sim.add_inlet(dpm.BoxRegion((0.003, 0.003, 0.016), (0.017, 0.017, 0.02)), m, rate=2000,
                  shape="cylinder", r=0.6e-3, l=2e-3, start=5e-3, stop=6e-3, every=1e-3)
    sim.output(out, every_steps=200, contacts=True, solids=True, fields="all")
    sim.run(steps=2000, progress=False)
    sim.close()
    return out


def test_a_frame_as_a_dataframe(run_path, monkeypatch):
    pytest.importorskip("pandas")
    from scipy.spatial.transform import Rotation

    run = dpm.load(run_path)
    f = run.frame(-1)
    df = run.to_dataframe(-1)
    assert list(df.columns) == [
        "id", "position_x", "position_y", "position_z", "velocity_x", "velocity_y",
        "velocity_z", "orientation_w", "orientation_x", "orientation_y", "orientation_z",
        "angular_velocity_x", "angular_velocity_y", "angular_velocity_z", "radius", "mass",
        "material", "shape", "force_x", "force_y", "force_z", "torque_x", "torque_y",
        "torque_z", "contact_count", "rotation_xx", "rotation_yx", "rotation_zx",
        "rotation_xy", "rotation_yy", "rotation_zy", "rotation_xz", "rotation_yz",
        "rotation_zz"]
    assert len(df) == len(f["id"]) == 18
    np.testing.assert_array_equal(df["id"], f["id"])
    for name in ("position", "velocity", "angular_velocity", "force", "torque"):
        for c, axis in enumerate("xyz"):
            np.testing.assert_array_equal(df[f"{name}_{axis}"], f[name][:, c])
    for c, part in enumerate("wxyz"):
        np.testing.assert_array_equal(df[f"orientation_{part}"], f["orientation"][:, c])
    # rotation_ab: row a, column b of the body's rotation matrix
    q = f["orientation"]
    rot = Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()
    assert np.abs(rot - np.eye(3)).max() > 0.5  # (turned bodies)
    for i, a in enumerate("xyz"):
        for j, b in enumerate("xyz"):
            np.testing.assert_allclose(df[f"rotation_{a}{b}"], rot[:, i, j], atol=1e-12)
    assert df["id"].dtype == np.int64 and df["material"].dtype == np.int32
    assert df.attrs["time"] == f["time"] and df.attrs["step"] == f["step"] == 2000
    assert df.attrs["materials"] == ["glass"]
    np.testing.assert_array_equal(run.to_dataframe(0)["position_z"], run.frame(0)["position"][:, 2])
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(DpmError, match=r"needs pandas: pip install 'dpm-granular\[pandas\]'"):
        run.to_dataframe(0)


# VTK's XDMF reader in a separate process: every line it or the XDMF library prints, and
# the error and warning events of the reader, come back with what it read
READ_XDMF = textwrap.dedent("""
    import json, sys
    from vtkmodules.vtkIOXdmf2 import vtkXdmfReader
    from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as P
    from vtkmodules.util.numpy_support import vtk_to_numpy
    out, events = {}, []
    for path in sys.argv[1:]:
        r = vtkXdmfReader()
        for ev in ("ErrorEvent", "WarningEvent"):
            r.AddObserver(ev, lambda obj, e: events.append((path, e)))
        r.SetFileName(path)
        r.UpdateInformation()
        frames = []
        for t in r.GetOutputInformation(0).Get(P.TIME_STEPS()) or []:
            r.UpdateTimeStep(t)
            g = r.GetOutputDataObject(0)
            arrays = {}
            for data, center in ((g.GetPointData(), "point"), (g.GetCellData(), "cell")):
                for k in range(data.GetNumberOfArrays()):
                    a = data.GetArray(k)
                    arrays[center + ":" + a.GetName()] = vtk_to_numpy(a).tolist()
            pts = g.GetPoints()
            frames.append({"time": t, "points": g.GetNumberOfPoints(),
                           "cells": g.GetNumberOfCells(), "arrays": arrays,
                           "xyz": vtk_to_numpy(pts.GetData()).tolist() if pts else []})
        out[path] = frames
    print("JSON" + json.dumps({"frames": out, "events": events}))
""")


def _read_xdmf(*paths):
    pytest.importorskip("vtkmodules.vtkIOXdmf2")
    done = subprocess.run([sys.executable, "-c", READ_XDMF, *map(str, paths)],
                          capture_output=True, text=True, timeout=300)
    text = done.stdout + done.stderr
    assert done.returncode == 0, text[-3000:]
    data = [line for line in done.stdout.splitlines() if line.startswith("JSON")]
    other = "\n".join(line for line in text.splitlines()
                      if not line.startswith("JSON") and line.strip())
    assert data, text[-3000:]
    return json.loads(data[0][4:]), other


def test_vtk_reads_every_sidecar_without_an_error_line(run_path):
    """Before: 'Cannot find DataItem element in geometry xml, no caching possible' for
    every frame of run.boundaries.xdmf, and 'Alloc :: ...' lines of the XDMF library for
    every frame without contacts (run.contacts.xdmf) or without clustered bodies
    (run.elements.xdmf)."""
    import h5py

    run = dpm.load(run_path)
    names = {s: run_path.with_suffix(s) for s in (".xdmf", ".boundaries.xdmf",
                                                  ".contacts.xdmf", ".elements.xdmf",
                                                  ".solids.xdmf")}
    assert all(p.exists() for p in names.values())
    got, other = _read_xdmf(*names.values())
    assert other == "" and got["events"] == [], other + str(got["events"])
    frames = {s: got["frames"][str(p)] for s, p in names.items()}
    nf = run.n_frames
    assert all(len(v) == nf for v in frames.values())
    with h5py.File(run_path, "r") as f:
        fr = {k: f["frames"][k][:nf] for k in f["frames"]}
        faces = f["surfaces/faces"][:]
        surface = f["boundaries/surface"][:nf]
    ncont, nel = fr["contact_count"], fr["element_count"]
    # the scene has what the test is about: frames with and without contacts, elements
    assert (ncont == 0).any() and (ncont > 0).any() and (nel == 0).any() and (nel > 0).any()
    for k in range(nf):
        p = frames[".xdmf"][k]
        frame = run.frame(k)
        assert p["points"] == p["cells"] == len(frame["id"])
        np.testing.assert_array_equal(p["xyz"], frame["position"])
        np.testing.assert_array_equal(p["arrays"]["point:radius"], frame["radius"])
        np.testing.assert_array_equal(p["arrays"]["point:orientation"], frame["orientation"])
        b = frames[".boundaries.xdmf"][k]
        assert b["cells"] == len(faces) and b["points"] == surface.shape[1]
        np.testing.assert_array_equal(b["xyz"], surface[k])
        c, cont = frames[".contacts.xdmf"][k], run.contacts(k)
        assert c["cells"] == ncont[k]
        if ncont[k]:
            assert c["points"] == 2 * ncont[k]
            np.testing.assert_array_equal(c["arrays"]["cell:normal_force"],
                                          cont["normal_force"])
            np.testing.assert_array_equal(c["arrays"]["cell:id_i"], cont["id"][:, 0])
        else:  # (one point, no cell, no attribute)
            assert c["points"] == 1 and c["arrays"] == {}
        e = frames[".elements.xdmf"][k]
        assert e["cells"] == nel[k]
        if nel[k]:
            np.testing.assert_array_equal(e["arrays"]["point:radius"], run.elements(k)["radius"])
        s = frames[".solids.xdmf"][k]
        assert s["cells"] == fr["solid_face_count"][k]


def test_vtk_reads_a_frame_without_particles(run_path, tmp_path):
    """A frame with no particle rows (before an inlet's first bodies) is a grid of one
    point, no cell, no attribute."""
    import h5py

    from dpm.io.xdmf import write_xdmf_from_arrays

    path = tmp_path / run_path.name
    shutil.copy(run_path, path)
    run = dpm.load(path, repair_xdmf=False)
    with h5py.File(path, "r") as f:
        rows, fields = len(f["particles/id"]), set(f["particles"])
    write_xdmf_from_arrays(path, run.times[:3], [0, *run.start[1:3]], [0, *run.count[1:3]],
                           rows, fields=fields)
    got, other = _read_xdmf(path.with_suffix(".xdmf"))
    assert other == "" and got["events"] == [], other + str(got["events"])
    frames = got["frames"][str(path.with_suffix(".xdmf"))]
    assert [(f["points"], f["cells"]) for f in frames] == [(1, 0), (16, 16), (16, 16)]
    assert frames[0]["arrays"] == {} and frames[1]["arrays"]["point:id"] == list(range(16))


# ------------------------------------------------------------------ the picture
def test_the_picture_draws_the_boundaries_in_equal_axes(run_path, tmp_path):
    pytest.importorskip("matplotlib")
    import h5py

    from dpm.analysis.picture import picture
    from dpm.cli import main

    run = dpm.load(run_path)
    with h5py.File(run_path, "r") as f:
        nfaces = len(f["surfaces/faces"])
    fig = picture(run, view="3d", path=tmp_path / "3d.png")
    ax = fig.axes[0]
    (faces,) = [c for c in ax.collections if c.get_label() == "boundaries"]
    assert len(faces.get_paths()) == nfaces  # every triangle of the box
    (edges,) = [c for c in ax.collections if c.get_label() == "boundary edges"]
    assert len(edges.get_segments()) == 12  # an open box: 4 + 4 rims, 4 vertical edges
    lims = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
    np.testing.assert_allclose(np.diff(lims, axis=1), np.diff(lims[2])[0], rtol=1e-12)
    assert (lims[:, 0] <= [0, 0, 0]).all() and (lims[:, 1] >= [0.02, 0.02, 0.03]).all()
    np.testing.assert_allclose(ax.get_box_aspect(), ax.get_box_aspect()[0], rtol=1e-12)
    # a projection: the box in the view, over the particles (which fill its bottom)
    fig = picture(run, view="xz", path=tmp_path / "xz.png")
    ax = fig.axes[0]
    assert [c.get_label() for c in ax.collections if "bound" in c.get_label()] == [
        "boundaries", "boundary edges"]
    assert ax.get_xlim()[0] <= 0 and ax.get_xlim()[1] >= 0.02 and ax.get_ylim()[1] >= 0.03
    # a frame dict has no boundaries; boundaries=False leaves them out
    for fig in (picture(run.frame(-1), view="3d", path=None),
                picture(run, view="xz", path=None, boundaries=False)):
        assert not [c for c in fig.axes[0].collections if "bound" in c.get_label()]
    png = tmp_path / "cli.png"
    assert main(["analyse", str(run_path), "--picture", "view=3d", f"out={png}"]) == 0
    assert png.stat().st_size > 10000
