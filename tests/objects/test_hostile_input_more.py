"""Hostile or careless input, issue #55 items 10 and 11: a named error where a traceback
was due (a garbage csv, nesting deeper than the parser's recursion, a torus needing a
16 GiB grid, a plugin that exits at import), and bounded resources (a huge value echoed,
a binary STL whose header contradicts its size, a device as csv, a number as the output
path). Every case raises a :class:`dpm.errors.ParameterError` naming what it refuses
(or, for the plugin, lists it as broken) before anything large is read or allocated."""

from __future__ import annotations

import importlib
import struct
import sys

import pytest
import trimesh

import dpm
from dpm import plugins
from dpm.cli import main
from dpm.errors import ParameterError
from dpm.io.scene import load_scene
from dpm.regions import MeshFace
from dpm.scene_file import read_scene
from dpm.shapes import MeshShape, Torus

BASE = """\
[simulation]
dt = 1e-5

[materials.glass]
density = 2500
young = 5e6
poisson = 0.45

[[contacts]]
materials = ["glass", "glass"]
restitution = 0.3
friction = 0.5
"""
PARTICLES = '\n[[particles]]\nmaterial = "glass"\nradius = 1e-3\ncsv = "{}"\n'


def scene(tmp_path, text: str):
    path = tmp_path / "scene.toml"
    path.write_text(BASE + text, encoding="utf-8")
    return path


def refused(fn, *args, **kwargs) -> str:
    with pytest.raises(ParameterError) as info:
        fn(*args, **kwargs)
    return str(info.value)


# item 10: a named error where a traceback was due --------------------------------------------
def test_csv_of_garbage(tmp_path):
    """a. a binary or a badly written csv: named, with the form allowed and the row."""
    (tmp_path / "garbage.csv").write_bytes(bytes(range(256)) * 8)
    path = scene(tmp_path, PARTICLES.format("garbage.csv"))
    msg = refused(load_scene, path)
    for part in (str(path), "particles[0]", "csv='garbage.csv'", "not UTF-8 text",
                 "x,y,z[,vx,vy,vz[,r]]", "one header line"):
        assert part in msg, msg
    (tmp_path / "bad.csv").write_text("x,y,z\n0,0,0.01\n1,2,abc\n")
    msg = refused(load_scene, scene(tmp_path, PARTICLES.format("bad.csv")))
    assert "csv='bad.csv'" in msg and "'abc'" in msg and "data row 2" in msg, msg
    (tmp_path / "short.csv").write_text("x,y\n0,0\n")
    msg = refused(load_scene, scene(tmp_path, PARTICLES.format("short.csv")))
    assert "has 2 column(s)" in msg and "x,y,z[,vx,vy,vz[,r]]" in msg, msg


@pytest.mark.parametrize("value", [
    "[run]\nuntil = " + "[" * 5000 + "]" * 5000,          # arrays: tomllib recursion
    "[run]\nuntil = " + "{ a = " * 3000 + "1" + " }" * 3000,  # inline tables: the same
    "[" + ".".join(["a"] * 3000) + "]\nx = 1",             # tables: the repr of the error
    "[run]\nuntil = " + "[" * 65 + "]" * 65,               # parsed, but past the limit
], ids=["arrays", "inline_tables", "tables", "just_past"])
def test_deep_nesting(tmp_path, value):
    """b. nesting deeper than 64: refused by name (not a RecursionError)."""
    path = scene(tmp_path, value + "\n")
    msg = refused(read_scene, path)
    assert str(path) in msg and "nested more than 64 deep" in msg, msg


def test_slender_torus_refused_before_allocating():
    """c. r1 = 1e-6 against r2 = 5e-3 would need a voxel grid of 1.8e10 cells (16.4 GiB
    of booleans alone): refused before it is allocated, with the shape, its parameters,
    the cells and the limit."""
    msg = refused(Torus(r1=1e-6, r2=5e-3).cluster)
    for part in ("Torus()", "torus(r1=1e-06, r2=0.005", "17,611,441,859 cells",
                 "allowed: at most 8,000,000 cells"):
        assert part in msg, msg
    sim = dpm.Simulation(dt=1e-6)
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    msg = refused(sim.add_particles, "torus", material=glass, r1=1e-6, r2=5e-3,
                  positions=[[0, 0, 0]])
    assert msg.startswith("sim.add_particles('torus'): torus(r1=1e-06"), msg


@pytest.fixture
def exiting_plugins(tmp_path, monkeypatch):
    (tmp_path / "exiting_dpm_plugin.py").write_text("import sys\nsys.exit(3)\n")
    (tmp_path / "interrupting_dpm_plugin.py").write_text("raise KeyboardInterrupt\n")
    info = tmp_path / "exiting_dpm_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: exiting-dpm-plugin\n"
                                   "Version: 0.1\n")
    (info / "entry_points.txt").write_text("[dpm]\nexits = exiting_dpm_plugin\n"
                                           "interrupts = interrupting_dpm_plugin\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    yield
    monkeypatch.undo()
    for name in ("exiting_dpm_plugin", "interrupting_dpm_plugin"):
        sys.modules.pop(name, None)
    importlib.invalidate_caches()
    plugins.registry(reload=True)


def test_plugin_exiting_at_import_is_listed_broken(exiting_plugins, capsys):
    """d. sys.exit() or KeyboardInterrupt at a plugin's import: listed as broken, the
    others load and dpm goes on."""
    reg = plugins.registry(reload=True)
    broken = dict(reg.broken)
    assert "sys.exit(3)" in broken["exiting-dpm-plugin:exits"]
    assert "KeyboardInterrupt" in broken["exiting-dpm-plugin:interrupts"]
    assert "sphere" in reg.entries["shape"]
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    assert "BROKEN plugin exiting-dpm-plugin:exits: SystemExit" in out
    assert "BROKEN plugin exiting-dpm-plugin:interrupts: KeyboardInterrupt" in out


# item 11: resources ------------------------------------------------------------------------
def test_huge_unknown_value_echoed_on_one_short_line(tmp_path):
    """e. an unknown key's value is echoed to 80 characters, then ``...`` and its length."""
    text = BASE.replace("dt = 1e-5", f'dt = 1e-5\nbogus = "{"x" * 2_000_000}"\n'
                        f"junk = [{', '.join(['0'] * 100_000)}]")
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    msg = refused(read_scene, path)
    assert len(msg) < 1000, len(msg)
    assert "unknown key bogus = '" + "x" * 79 + "... (2,000,000 characters)" in msg, msg
    assert "unknown key junk = [0, 0, 0" in msg and "... (100,000 items)" in msg, msg


def stl_files(tmp_path):
    claims = tmp_path / "claims.stl"  # 200 bytes, its header says 4e9 triangles
    claims.write_bytes(b"\0" * 80 + struct.pack("<I", 4_000_000_000) + b"\0" * 116)
    zeros = tmp_path / "zeros.stl"
    zeros.write_bytes(b"\0" * (1 << 20))
    return [(claims, "4,000,000,000 triangles, 200,000,000,084 bytes", "200 bytes"),
            (zeros, "0 triangles, 84 bytes", "1,048,576 bytes")]


def test_binary_stl_header_against_size(tmp_path, monkeypatch):
    """f. a binary STL whose size is not 84 + 50 x its header's count: refused by name
    without reading it, wherever a mesh file is read."""
    def read(*args, **kwargs):
        raise AssertionError("the file was read")

    sim = dpm.Simulation(dt=1e-5)
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    for file, claim, found in stl_files(tmp_path):
        with monkeypatch.context() as m:
            m.setattr(trimesh, "load", read)
            for fn, lead in [
                    (lambda f: sim.add_boundary("mesh", material=glass, file=str(f)), "file"),
                    (lambda f: MeshShape(path=str(f)), "MeshShape(): path"),
                    (lambda f: MeshFace(file=str(f)), "MeshFace(): file")]:
                msg = refused(fn, file)
                for part in (f"{lead}={str(file)!r}", "binary STL", claim,
                             f"the file has {found}", "ASCII STL"):
                    assert part in msg, msg
    # well-formed files, binary and ASCII (even a binary one whose header says "solid")
    box = trimesh.creation.box(extents=(0.01, 0.01, 0.01))
    box.export(tmp_path / "box.stl")
    box.export(tmp_path / "box_ascii.stl", file_type="stl_ascii")
    data = bytearray((tmp_path / "box.stl").read_bytes())
    data[:80] = b"solid box".ljust(80)
    (tmp_path / "box_solid.stl").write_bytes(bytes(data))
    for name in ("box.stl", "box_ascii.stl", "box_solid.stl"):
        assert MeshShape(path=str(tmp_path / name)).volume() == pytest.approx(1e-6)
        sim.add_boundary("mesh", material=glass, file=str(tmp_path / name))


def test_csv_not_a_regular_file(tmp_path):
    """g. a device (or a folder) as csv: not a regular file, not "no such file"; a name
    too long to look up: named too."""
    msg = refused(load_scene, scene(tmp_path, PARTICLES.format("/dev/zero")))
    assert "csv = '/dev/zero' is not a regular file" in msg and "x,y,z" in msg, msg
    (tmp_path / "folder.csv").mkdir()
    msg = refused(load_scene, scene(tmp_path, PARTICLES.format("folder.csv")))
    assert "csv = 'folder.csv' is not a regular file" in msg, msg
    msg = refused(load_scene, scene(tmp_path, PARTICLES.format("a" * 5000)))
    assert "(5,000 characters) cannot be looked up" in msg, msg


@pytest.mark.parametrize("value,shown", [("5", "5"), ("5.0", "5.0"), ("true", "True"),
                                         ('["run.h5"]', "['run.h5']")])
def test_output_path_not_a_name(tmp_path, monkeypatch, value, shown):
    """h. ``path = 5`` in [output]: refused by name, no file "5" written."""
    monkeypatch.chdir(tmp_path)
    path = scene(tmp_path, f"\n[output]\npath = {value}\nevery = 0.01\n")
    msg = refused(load_scene, path)
    assert f"{path}: [output]: path={shown}; allowed: a file name" in msg, msg
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]
