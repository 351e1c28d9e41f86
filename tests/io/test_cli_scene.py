"""TOML scenes and the command line."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import dpm
from dpm.cli import main
from dpm.io.scene import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

SCENE = """
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

[[boundaries]]
kind = "plane"
material = "glass"

[[particles]]
shape = "sphere"
material = "glass"
csv = "p.csv"

[output]
path = "{out}"
every_steps = 10

[run]
steps = 50
"""


def test_scene_mirrors_the_api(tmp_path):
    np.savetxt(tmp_path / "p.csv", [[0, 0, 2e-3, 0, 0, -0.1, 1e-3], [5e-3, 0, 2e-3, 0, 0, 0,
                                                                      0.5e-3]],
               delimiter=",", header="x,y,z,vx,vy,vz,r", comments="")
    out = tmp_path / "out.h5"
    (tmp_path / "s.toml").write_text(SCENE.format(out=out))
    sim, run_kw = load_scene(tmp_path / "s.toml")  # opens no file before a run
    assert run_kw == {"steps": 50}
    np.testing.assert_array_equal(sim.bodies.radius, [1e-3, 0.5e-3])  # radii from the csv
    np.testing.assert_array_equal(sim.bodies.velocity[0], [0, 0, -0.1])
    assert main(["run", str(tmp_path / "s.toml"), "--no-progress"]) == 0
    run = dpm.load(out)
    assert run.n_frames == 6 and run.steps[-1] == 50


def test_scene_errors_name_the_problem(tmp_path):
    bad = SCENE.replace('material = "glass"\ncsv', 'material = "steel"\ncsv')
    (tmp_path / "p.csv").write_text("x,y,z\n0,0,0.002\n")
    (tmp_path / "s.toml").write_text(bad.format(out=tmp_path / "o.h5"))
    with pytest.raises(dpm.ParameterError, match="material='steel' is not defined"):
        load_scene(tmp_path / "s.toml")
    (tmp_path / "t.toml").write_text("[simulation]\ndt = -1\n")
    with pytest.raises(dpm.ParameterError, match=r"dt=-1 is outside \(0, inf\)"):
        load_scene(tmp_path / "t.toml")


def test_cli_reports_errors_without_traceback(tmp_path):
    (tmp_path / "t.toml").write_text("[simulation]\ndt = 1e-5\nintegrator = 'rk99'\n")
    r = subprocess.run([sys.executable, "-m", "dpm.cli", "run", str(tmp_path / "t.toml")],
                       capture_output=True, text=True)
    assert r.returncode == 2
    assert "unknown integrator 'rk99'" in r.stderr and "Traceback" not in r.stderr


def test_example_scene_file_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(EXAMPLES / "box_settle.toml"), "--steps", "200",
                 "--no-progress"]) == 0
    assert dpm.load(tmp_path / "box_settle_toml.h5").n_frames == 1


def test_scene_file_output_options(tmp_path, monkeypatch):
    """[output] takes sim.output's optional fields, contacts and solids; a bad field
    name is refused with its name before any step."""
    monkeypatch.chdir(tmp_path)
    text = (EXAMPLES / "box_settle.toml").read_text().replace(
        'every = 0.01', 'every_steps = 10\nfields = ["force", "contact_count"]\n'
        'contacts = true\nsolids = false')
    (tmp_path / "s.toml").write_text(text)
    assert main(["run", "s.toml", "--steps", "20", "--no-progress"]) == 0
    run = dpm.load(tmp_path / "box_settle_toml.h5")
    frame = run.frame(-1)
    assert frame["force"].shape == (1000, 3) and frame["contact_count"].shape == (1000,)
    assert "normal_force" in run.contacts(-1)
    (tmp_path / "bad.toml").write_text(text.replace('"contact_count"', '"contacts"'))
    with pytest.raises(dpm.ParameterError, match="fields"):
        load_scene(tmp_path / "bad.toml", overwrite=True)


FLOW_SCENE = """
[simulation]
dt = 1e-5
gravity = [0, 0, -9.81]
dt_check = "off"

[materials.steel]
density = 7800
young = 2e8
poisson = 0.3

[[contacts]]
materials = ["steel", "steel"]
model = "hertz_mindlin"
restitution = 0.5
friction = 0.5

[[boundaries]]
kind = "tube"
material = "steel"
start = [0, 0, 0]
axis = [0, 1, 0]
length = 0.02
radius = 0.03
caps = "both"
motion = [{ type = "rotation", rpm = 30, axis = [0, 1, 0] },
          { type = "oscillation", amplitude = [0, 0, 1e-4], frequency = 5 }]

[[periodic]]
axis = "x"
lower = -0.5
upper = 0.5

[[inlets]]
material = "steel"
region = { box = { lower = [-0.01, 0.002, -0.01], upper = [0.01, 0.018, 0.01] } }
rate = 2000
radius = [1e-3, 1.5e-3]
every = 2e-3
stop = 0.01

[[outlets]]
region = { cylinder = { start = [0, -1, 0], axis = [0, 1, 0], length = 2, radius = 0.005 } }
remove = "outside"
"""


def test_scene_with_motion_periodic_inlet_outlet(tmp_path):
    """The TOML tables of moving boundaries, periodic axes, inlets and outlets build the
    same objects the API would."""
    path = tmp_path / "flow.toml"
    path.write_text(FLOW_SCENE)
    sim, run = load_scene(path)
    drum = sim.boundaries[0]
    assert isinstance(drum.motion, dpm.Compose)
    assert drum.motion.motions[0].omega == pytest.approx(np.pi)
    assert sim.period[3] == pytest.approx(1.0)
    assert len(sim.inlets) == 1 and len(sim.outlets) == 1
    sim.run(until=0.01, progress=False)
    inlet, outlet = sim.inlets[0], sim.outlets[0]
    assert inlet.inserted == 20
    assert inlet.inserted == outlet.count + len(sim.bodies)
    assert np.all(np.hypot(sim.bodies.position[:, 0], sim.bodies.position[:, 2]) < 0.03)


def test_cli_checkpoints_and_restart(tmp_path, monkeypatch, capsys):
    """dpm run --checkpoint-every writes numbered checkpoints; --restart goes on from the
    newest (steps count from the start); another scene's checkpoint is refused; a second
    run onto the existing output needs --overwrite."""
    monkeypatch.chdir(tmp_path)
    scene = EXAMPLES / "box_settle.toml"
    assert main(["run", str(scene), "--steps", "200", "--checkpoint-every", "0.001",
                 "--no-progress"]) == 0
    assert (tmp_path / "box_settle.ckpt.0000000200.h5").exists()
    assert main(["run", str(scene), "--steps", "300", "--restart", "box_settle.ckpt.h5",
                 "--no-progress"]) == 0
    assert "restarted from step 200" in capsys.readouterr().out
    other = tmp_path / "other.toml"
    other.write_text(scene.read_text().replace("friction = 0.5", "friction = 0.4"))
    assert "friction = 0.4" in other.read_text()
    assert main(["run", str(other), "--steps", "300", "--restart", "box_settle.ckpt.h5",
                 "--no-progress"]) == 2
    assert "checkpoint of another scene" in capsys.readouterr().err
    assert main(["run", str(scene), "--steps", "10", "--no-progress"]) == 2
    assert "dpm run --overwrite" in capsys.readouterr().err
    assert main(["run", str(scene), "--steps", "10", "--no-progress", "--overwrite"]) == 0


def test_cli_restart_takes_the_edited_run_settings(tmp_path, monkeypatch, capsys):
    """Issue #55, item 5: dpm run --restart with an edited [simulation] and [output]: dt,
    max_overlap and the output interval take effect and are reported (the frames after
    the restart are at the new dt's times); a setting a restart cannot change is refused
    by name before any step."""
    monkeypatch.chdir(tmp_path)
    scene = EXAMPLES / "box_settle.toml"
    assert main(["run", str(scene), "--steps", "200", "--checkpoint-every", "0.001",
                 "--no-progress"]) == 0
    capsys.readouterr()
    edited = tmp_path / "edited.toml"
    edited.write_text(scene.read_text().replace("dt = 1e-5", "dt = 5e-6\nmax_overlap = 0.4")
                      .replace("every = 0.01", "every = 0.0005"))
    assert main(["run", str(edited), "--steps", "300", "--restart", "box_settle.ckpt.h5",
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "dt: 1e-05 -> 5e-06" in out and "max_overlap: 0.5 -> 0.4" in out, out
    assert "output: box_settle_toml.h5 every=0.0005 s, continued" in out, out
    run = dpm.load(tmp_path / "box_settle_toml.h5")
    # frame 0 (every 0.01 s before), then every 0.0005 s = 100 steps of 5e-6 s from 200
    assert run.steps.tolist() == [0, 300]
    assert run.times[-1] == pytest.approx(200 * 1e-5 + 100 * 5e-6)
    bad = tmp_path / "bad.toml"
    bad.write_text(scene.read_text().replace("dt = 1e-5", "dt = 1e-5\nsphere_orientation = false"))
    assert main(["run", str(bad), "--steps", "300", "--restart", "box_settle.ckpt.h5",
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "sphere_orientation=False in the scene file, True in the checkpoint" in err, err


def test_a_large_scene_file_is_stored_by_digest(tmp_path, monkeypatch):
    """Issue #55, item 11: a scene file over 1 MiB is not copied into the output file: its
    path and SHA-256 are."""
    import hashlib

    monkeypatch.chdir(tmp_path)
    big = tmp_path / "big.toml"
    text = (EXAMPLES / "box_settle.toml").read_text() + "# " + "x" * (1 << 20) + "\n"
    big.write_text(text)
    assert main(["run", str(big), "--steps", "1", "--no-progress"]) == 0
    run = dpm.load(tmp_path / "box_settle_toml.h5")
    assert run.scene_toml is None and run.scene_file == str(big)
    assert run.attrs["scene_sha256"] == hashlib.sha256(text.encode()).hexdigest()
    assert (tmp_path / "box_settle_toml.h5").stat().st_size < (1 << 20)
