"""Values of a scene file from the file to the run: units and expressions (dpm.units),
problems named with the file and the line, ``dpm run --set``, the ``[checkpoint]`` table
and ``dpm sweep``."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

import dpm
from dpm.cli import main
from dpm.io.scene import load_scene
from dpm.scene_file import apply_set, parse_path, parse_value, read_scene, split_values
from dpm.units import ExpressionError, convert, evaluate

# ---- the evaluator ----------------------------------------------------------------------


@pytest.mark.parametrize("text, unit, value", [
    ("30 deg", "rad", math.pi / 6),
    ("30 deg", "deg", 30.0),
    ("0.5 rad", "deg", 28.64788975654116),
    ("2 mm", "m", 2e-3),
    ("2 mm / 2", "m", 1e-3),
    ("sin(30 deg)", "", 0.5),
    ("tan(30 deg)", "", math.tan(math.pi / 6)),
    ("5e6 Pa", "Pa", 5e6),
    ("5 MPa", "Pa", 5e6),
    ("2.5 g/cm3", "kg/m3", 2500.0),
    ("9.81 m/s^2", "m/s2", 9.81),
    ("-9.81 m s**-2", "m/s2", -9.81),
    ("10 us", "s", 1e-5),
    ("2 min", "s", 120.0),
    ("30 rpm", "1/min", 30.0),
    ("0.5 Hz", "1/min", 30.0),
    ("30 rev/min", "rad/s", math.pi),
    ("1 / 2 s", "1/s", 0.5),
    ("2 mm / 1 m", "", 2e-3),
    ("sqrt(4 mm2)", "m", 2e-3),
    ("pi / 6", "rad", math.pi / 6),  # no unit: in the key's own
    ("sqrt(2) * 1e-3", "m", math.sqrt(2) * 1e-3),
    ("(1 + 2) mm", "m", 3e-3),
    ("2 kg * 9.81 m/s2", "N", 19.62),
    ("1e4 J/m3", "J/m3", 1e4),
    ("0.5 N / 1 mm", "N/m", 500.0),
    ("30 µm", "m", 3e-5),
])
def test_quantities_convert_to_the_unit_of_the_key(text, unit, value):
    assert convert(text, unit) == pytest.approx(value, rel=1e-14)


def test_values_are_read_to_15_digits_and_integers_stay_integers():
    assert convert("30 deg", "deg") == 30.0  # not 29.999999999999996
    assert convert("sin(30 deg)", "") == 0.5
    n = convert("1 min / 1 ms", "", integer=True)
    assert n == 60000 and isinstance(n, int)


@pytest.mark.parametrize("text, unit, why", [
    ("30 deg", "m", "angle; the key takes m (length)"),
    ("30 deg", "", "angle; the key takes a plain number"),
    ("30 rpm", "rad/s", "1/time; the key takes rad/s (angle/time)"),
    ("2 mm", "s", "length; the key takes s (time)"),
    ("30", "1/min", "a plain number in quotes"),
    ("1 - 0.5", "", "a plain number in quotes"),
    ("mm", "m", "a unit without a number"),
    ("2 mm + 1 s", "m", "adds time to length"),
    ("sin(2 mm)", "", "sin of length"),
    ("sin 30", "", "write sin(...)"),
    ("2 furlongs", "m", "unknown name 'furlongs'"),
    ("1.5.3", "", "a number after a value"),
    ("1/0 m", "m", "division by zero"),
    ("2**10000 * 1 m", "m", "too large"),
    ("(-8 m3)**(1/3)", "m", "negative"),
    ("", "m", "empty"),
    ("1 m" * 100, "m", "longer than"),
])
def test_refused_quantities_say_why(text, unit, why):
    with pytest.raises(ExpressionError, match=re.escape(why)):
        convert(text, unit)


@pytest.mark.parametrize("text", [
    "__import__('os').system('true')", "open('f')", "x.y", "lambda: 1", "[1, 2]",
    "1 if 1 else 2", "os", "sin.__class__", "m.__class__", "{1: 2}", "a; b", "f'{1}'",
    "1 == 1", "not 1", "2 mm @ 2", "print(1)", "sin(1, 2)", "sin(x=1)", "eval('1')",
])
def test_nothing_but_the_grammar_is_evaluated(text, monkeypatch):
    import builtins

    def refuse(*args, **kwargs):
        raise AssertionError("evaluated")

    monkeypatch.setattr(builtins, "eval", refuse)
    monkeypatch.setattr(builtins, "exec", refuse)
    monkeypatch.setattr(builtins, "__import__", refuse)
    with pytest.raises(ExpressionError):
        evaluate(text)


# ---- scene files with units -------------------------------------------------------------

PLAIN = """\
[simulation]
dt = 1e-5
gravity = [0, 0, -9.81]

[materials.glass]
density = 2500
young = 5e6
poisson = 0.45

[[contacts]]
materials = ["glass", "glass"]
model = "hertz_mindlin"
restitution = 0.3
friction = 0.5

[[boundaries]]
kind = "box"
material = "glass"
lower = [0, 0, 0]
upper = [0.02, 0.02, 0.03]
open = ["+z"]
motion = { type = "rotation", rpm = 30, axis = [1, 0, 0], center = [0.01, 0.01, 0.01] }

[[inlets]]
material = "glass"
region = { box = { lower = [0, 0, 0.02], upper = [0.02, 0.02, 0.03] } }
rate = 100
radius = { normal = { mean = 1e-3, std = 1e-4, low = 8e-4, high = 1.2e-3 } }

[[particles]]
shape = "sphere"
material = "glass"
radius = 1e-3
lattice = { lower = [0, 0, 0], upper = [0.02, 0.02, 0.01], spacing = 2.2e-3 }

[run]
steps = 10
"""

WITH_UNITS = (PLAIN.replace("dt = 1e-5", 'dt = "10 us"')
              .replace("gravity = [0, 0, -9.81]", 'gravity = [0, 0, "-9.81 m/s2"]')
              .replace("density = 2500", 'density = "2.5 g/cm3"')
              .replace("young = 5e6", 'young = "5 MPa"')
              .replace("friction = 0.5", 'friction = "tan(30 deg) * sqrt(3) / 2"')
              .replace("upper = [0.02, 0.02, 0.03]\nopen",
                       'upper = ["2 cm", "20 mm", "3 cm"]\nopen')
              .replace("rpm = 30", 'rpm = "0.5 Hz"')
              .replace("mean = 1e-3, std = 1e-4", 'mean = "1 mm", std = "100 um"')
              .replace("radius = 1e-3\nlattice", 'radius = "2 mm / 2"\nlattice')
              .replace("spacing = 2.2e-3", 'spacing = "2.2 mm"'))


def scene(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_a_scene_with_units_builds_the_scene_of_plain_numbers(tmp_path):
    assert WITH_UNITS.count('"') > PLAIN.count('"') + 20  # (every replacement took)
    a, _ = load_scene(scene(tmp_path, PLAIN, "a.toml"), output=False)
    b, _ = load_scene(scene(tmp_path, WITH_UNITS, "b.toml"), output=False)
    assert b.dt == a.dt and np.array_equal(b.gravity, a.gravity)
    assert (b.materials[0].density, b.materials[0].young) == (2500.0, 5e6)
    assert b._contacts[(0, 0)].params["friction"] == pytest.approx(0.5, rel=1e-15)
    assert b.boundaries[0].motion.omega == pytest.approx(a.boundaries[0].motion.omega)
    np.testing.assert_allclose(b.bodies.position, a.bodies.position, rtol=1e-15)
    np.testing.assert_array_equal(b.bodies.radius, a.bodies.radius)
    doc = read_scene(tmp_path / "b.toml")
    assert doc["inlets"][0]["radius"] == {"normal": {"mean": 1e-3, "std": 1e-4,
                                                     "low": 8e-4, "high": 1.2e-3}}
    assert doc["boundaries"][0]["upper"] == [0.02, 0.02, 0.03]
    assert doc["boundaries"][0]["open"] == ["+z"]  # names stay names
    assert doc["contacts"][0]["model"] == "hertz_mindlin"


def test_words_stay_words():
    """A word where a number goes is left to the call (dt = "auto")."""
    from dpm.scene_file import convert_values

    doc = {"simulation": {"dt": "auto", "integrator": "gear4"}}
    assert convert_values(doc) == [] and doc["simulation"] == {"dt": "auto",
                                                               "integrator": "gear4"}


def test_a_value_of_the_wrong_dimension_is_refused_with_the_file_and_line(tmp_path):
    bad = (PLAIN.replace("radius = 1e-3\nlattice", 'radius = "30 deg"\nlattice')
           .replace("gravity = [0, 0, -9.81]", 'gravity = [0, 0, "-9.81 m"]'))
    path = scene(tmp_path, bad)
    with pytest.raises(dpm.ParameterError) as err:
        read_scene(path)
    msg = str(err.value)
    line = 1 + bad.splitlines().index('radius = "30 deg"')
    assert f"{path}: particles[0]: radius = '30 deg': a quantity of angle; the key takes m " \
           f"(length) (line {line})" in msg
    assert "[simulation]: gravity = [0, 0, '-9.81 m']: gravity[2] = '-9.81 m': a quantity " \
           "of length; the key takes m/s2 (length/time^2) (line 3)" in msg


def test_a_quoted_number_in_a_motion_is_refused_with_the_file_and_line(tmp_path):
    path = scene(tmp_path, PLAIN.replace("rpm = 30", 'rpm = "30"'))
    line = 1 + PLAIN.splitlines().index(next(x for x in PLAIN.splitlines() if "rpm" in x))
    with pytest.raises(dpm.ParameterError, match=re.escape(
            f"{path}: boundaries[0]: motion: rpm = '30': a plain number in quotes") +
            r".* \(line " + str(line) + r"\)"):
        load_scene(path, output=False)


def test_values_the_calls_refuse_are_named_with_the_file_and_line(tmp_path):
    path = scene(tmp_path, PLAIN.replace("restitution = 0.3", "restitution = 2")
                 .replace("rpm = 30,", "rpm = 30, ramp = -1,"))
    line = 1 + PLAIN.splitlines().index("restitution = 0.3")
    with pytest.raises(dpm.ParameterError, match=re.escape(
            f"{path}: contacts[0]: sim.contact(glass, glass): restitution=2 is outside "
            f"(0, 1] (line {line})")):
        load_scene(path, output=False)
    path = scene(tmp_path, PLAIN.replace("rpm = 30,", "rpm = 30, ramp = -1,"))
    with pytest.raises(dpm.ParameterError, match=re.escape(
            "boundaries[0]: motion: Rotation(): ramp=-1 is outside [0, inf) (line 22)")):
        load_scene(path, output=False)


# ---- dpm run --set ----------------------------------------------------------------------


def test_set_paths_and_values():
    assert parse_path("contacts[0].friction") == ["contacts", 0, "friction"]
    assert parse_path('materials."glass.1".young') == ["materials", "glass.1", "young"]
    assert parse_path("boundaries[1].motion[0].rpm") == ["boundaries", 1, "motion", 0, "rpm"]
    for bad in ("contacts[0]..friction", "contacts[x].friction", "a b", ""):
        with pytest.raises(dpm.ParameterError, match="not a path"):
            parse_path(bad)
    assert parse_value("0.3") == 0.3 and parse_value("[0, 0, -9.81]") == [0, 0, -9.81]
    assert parse_value('"1e-5"') == 1e-5  # (a number in quotes: the number)
    assert parse_value("gear4") == "gear4" and parse_value("2 mm") == "2 mm"
    assert parse_value('"gear4"') == "gear4" and parse_value("true") is True
    assert split_values("0.2,0.3, 0.4") == ["0.2", "0.3", "0.4"]
    assert split_values('[0, 0, -9.81],[0, 0, -1],"a,b"') == ["[0, 0, -9.81]", "[0, 0, -1]",
                                                              '"a,b"']


def test_set_changes_the_document_before_it_is_checked(tmp_path):
    path = scene(tmp_path, PLAIN)
    sim, run_kw = load_scene(path, output=False, sets=[
        "contacts[0].friction=0.3", 'simulation.dt="2e-5"', "particles[0].radius=0.9 mm",
        "boundaries[0].motion.rpm=60 rpm", "materials.glass.young=1e7", "run.steps=20"])
    assert sim.dt == 2e-5 and run_kw == {"steps": 20}
    assert sim._contacts[(0, 0)].params["friction"] == 0.3
    assert np.all(sim.bodies.radius == 0.9e-3) and sim.materials[0].young == 1e7
    assert sim.boundaries[0].motion.omega == pytest.approx(2 * math.pi)
    assert "# --set contacts[0].friction=0.3" in sim._scene_source[1]  # (stored in the output)


@pytest.mark.parametrize("edit, why", [
    ("contact[0].friction=0.3", "the file has no contact (did you mean contacts?); its keys: "
                                "simulation, materials, contacts"),
    ("contacts[3].friction=0.3", "contacts has 1 entry (0 to 0); no [3]"),
    ("simulation.dt.x=1", "simulation.dt is not a table; simulation.dt has a value, 1e-05"),
    ("materials.steel.density=1", "materials has no steel; its keys: glass"),
    ("materials.glas.density=1", "materials has no glas (did you mean glass?)"),
    ("boundaries[0].motion.rpm.x=1", "is not a table"),
    ("simulation=1", "the path names a table, not a key"),
    ("contacts.friction=0.3", "contacts is an array with 1 entry (0 to 0): write "
                              "contacts[N].friction"),
    ("contacts[0].materials[5]=1", "contacts[0].materials has 2 entries (0 to 1); no [5]"),
])
def test_set_refuses_a_path_that_is_not_there_by_name(tmp_path, edit, why):
    path = scene(tmp_path, PLAIN)
    with pytest.raises(dpm.ParameterError, match=re.escape(f"{path}: --set {edit}") +
                       ".*" + re.escape(why)):
        read_scene(path, [edit])
    with pytest.raises(dpm.ParameterError, match="--set 'friction': write PATH=VALUE"):
        read_scene(path, ["friction"])


def test_a_set_value_the_checks_refuse_names_the_edit(tmp_path, capsys):
    path = scene(tmp_path, PLAIN)
    with pytest.raises(dpm.ParameterError, match=re.escape(
            "contacts[0]: unknown key frcition = 0.3 (did you mean friction?)") + ".*"
            + re.escape("(set on the command line: --set contacts[0].frcition=0.3)")):
        read_scene(path, ["contacts[0].frcition=0.3"])
    with pytest.raises(dpm.ParameterError, match=re.escape(
            "particles[0]: radius = '30 deg': a quantity of angle") + ".*"
            + re.escape("(set on the command line: --set particles[0].radius=30 deg)")):
        read_scene(path, ["particles[0].radius=30 deg"])
    assert main(["run", str(path), "--set", "contacts[0].friction=-1"]) == 2
    assert ("contacts[0]: sim.contact(glass, glass): friction=-1 is outside [0, inf) (set on "
            "the command line: --set contacts[0].friction=-1)") in capsys.readouterr().err


def test_apply_set_makes_a_missing_single_table():
    doc = {"simulation": {"dt": 1e-5}}
    assert apply_set(doc, "output.every=0.01") == ("[output]", "output.every=0.01")
    assert doc["output"] == {"every": 0.01}


# ---- [checkpoint] and dpm sweep (a few steps of a tiny scene) ---------------------------

TINY = """\
[simulation]
dt = 1e-5
gravity = [0, 0, -9.81]

[materials.glass]
density = 2500
young = 5e6
poisson = 0.45

[[contacts]]
materials = ["glass", "glass"]
friction = 0.5

[[boundaries]]
kind = "plane"
material = "glass"

[[particles]]
material = "glass"
radius = "1 mm"
positions = [[0, 0, "1.5 mm"], [3e-3, 0, 2e-3]]

[output]
path = "tiny.h5"
every_steps = 2

[checkpoint]
every_steps = 2
keep = 2

[run]
steps = 4
"""


def test_checkpoint_table_and_the_flag_that_wins(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = scene(tmp_path, TINY, "tiny.toml")
    sim, _ = load_scene(path)
    ck = sim.operations.checkpoints
    assert (ck.every, ck.every_steps, ck.keep, Path(ck.base).name) == (None, 2, 2,
                                                                      "tiny.ckpt.h5")
    assert load_scene(path, output=False)[0].operations.checkpoints is None
    assert main(["run", "tiny.toml", "--no-progress"]) == 0
    assert sorted(p.name for p in tmp_path.glob("tiny.ckpt.*.h5")) == [
        "tiny.ckpt.0000000002.h5", "tiny.ckpt.0000000004.h5"]
    # the command line wins: its interval, its path; [checkpoint]'s keep stays
    assert main(["run", "tiny.toml", "--no-progress", "--overwrite", "--steps", "6",
                 "--checkpoint-every", "3e-5", "--checkpoint", "flag.ckpt.h5"]) == 0
    assert sorted(p.name for p in tmp_path.glob("flag.ckpt.*.h5")) == [
        "flag.ckpt.0000000003.h5", "flag.ckpt.0000000006.h5"]
    with pytest.raises(dpm.ParameterError, match=r"\[checkpoint\]: sim.checkpoint_every\(\)"
                       r": give exactly one of every \(s\) or every_steps \(line 27\)"):
        load_scene(scene(tmp_path, TINY.replace("every_steps = 2\nkeep", "keep"), "b.toml"),
                   overwrite=True)


def test_sweep_runs_the_product_of_the_values(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    scene(tmp_path, TINY, "tiny.toml")
    argv = ["sweep", "tiny.toml", "--set", "contacts[0].friction=0.2,0.4",
            "--set", "simulation.dt=1e-5", "--jobs", "1", "--steps", "4", "--out", "runs",
            "--csv", "table.csv"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines()]
    head = next(r for r in rows if r and r[0] == "contacts[0].friction")
    assert head[:4] == ["contacts[0].friction", "simulation.dt", "steps", "t"]
    for value in ("0.2", "0.4"):
        row = next(r for r in rows if r and r[0] == value)
        assert row[2] == "4" and row[-1] == f"runs/tiny-friction={value}.h5"
        run = dpm.load(tmp_path / "runs" / f"tiny-friction={value}.h5")
        assert list(run.steps) == [0, 2, 4]
        assert f"# --set contacts[0].friction={value}" in run.scene_toml
        assert (tmp_path / "runs" / f"tiny-friction={value}.ckpt.0000000002.h5").is_file()
    table = (tmp_path / "table.csv").read_text().splitlines()
    assert table[0].startswith("contacts[0].friction,simulation.dt,steps,t [s],wall [s],"
                               "particles,KE [J],mean z [m],output")
    assert len(table) == 3 and table[1].startswith("0.2,1e-5,4,4e-05,")
    # the files are kept; a bad path is refused before any run
    assert main(argv) == 2
    assert "already exist and are kept" in capsys.readouterr().err
    assert main(["sweep", "tiny.toml", "--set", "contacts[0].frcition=0.2,0.4"]) == 2
    assert "unknown key frcition" in capsys.readouterr().err
