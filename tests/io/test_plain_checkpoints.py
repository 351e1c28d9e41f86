"""Checkpoints as plain data (issue #55, item 7): loading one runs no code from the file.

The state is JSON text and datasets (readable with h5py and json); a crafted state that
names a function or class outside dpm, its plugins and the running script is refused by
name and nothing runs; a checkpoint of the pickle format (version 1) is refused before it
is read; a scene object that cannot be stored is refused at ``checkpoint_every()`` naming
where it sits; a script's own motion class round-trips.
"""

from __future__ import annotations

import json
import pickle
import shutil

import h5py
import numpy as np
import pytest
from small_scene import small_scene
from test_output_ownership import first_run

import dpm
from dpm import checkpoint as ckpt


class Sway(dpm.Motion):
    """A script's own motion (module level): stored by name, rebuilt from its attributes."""

    name = "sway"

    def pose(self, t):
        t = np.atleast_1d(t)
        o = np.zeros((len(t), 3))
        o[:, 0] = 1e-4 * np.sin(40.0 * t)
        return np.tile(np.eye(3), (len(t), 1, 1)), o


def checkpoint_of(tmp_path):
    return ckpt.latest(first_run(tmp_path))


def read_state(p):
    with h5py.File(p, "r") as f:
        return json.loads(f["state"][()].tobytes())


def write_state(p, tree):
    with h5py.File(p, "r+") as f:
        del f["state"]
        f.create_dataset("state", data=np.frombuffer(json.dumps(tree).encode(), np.uint8))


def test_the_state_is_json_and_datasets(tmp_path):
    p = checkpoint_of(tmp_path)
    with h5py.File(p, "r") as f:
        assert "objects" not in f and int(f.attrs["format_version"]) == 2
        arrays = {k: f["arrays"][k][()] for k in f["arrays"]}
    tree = read_state(p)
    assert tree["O"][0] == "dpm.simulation:Simulation"
    text = json.dumps(tree)
    assert '"dpm.state:Bodies"' in text
    n = len(dpm.restart(p, output=None).bodies)
    assert any(a.shape[:1] == (n,) for a in arrays.values())  # the bodies' rows


@pytest.mark.parametrize("payload", [
    {"O": ["subprocess:Popen", [["touch", "MARKER"]], None, None, None]},
    {"O": ["posix:system", ["touch MARKER"], None, None, None]},
    {"K": "os:system"},
    {"K": "dpm.io.hdf5:os.system"},
    {"K": "builtins:eval"},
    {"O": ["dpm.checkpoint:__builtins__", [], None, None, None]},
    {"E": ["os:PathLike", 1]},
])
def test_a_crafted_state_runs_nothing(tmp_path, monkeypatch, payload):
    """Each payload put where the simulation's boundaries are: refused naming what it
    names, and nothing ran (no MARKER file)."""
    monkeypatch.chdir(tmp_path)
    p = checkpoint_of(tmp_path)
    tree = read_state(p)
    state = dict(tree["O"][2]["D"])
    state["boundaries"] = {"L": [json.loads(json.dumps(payload).replace(
        "MARKER", str(tmp_path / "MARKER")))]}
    tree["O"][2]["D"] = [[k, v] for k, v in state.items()]
    write_state(p, tree)
    with pytest.raises(dpm.ParameterError, match="refused|no such name|has not imported"):
        dpm.restart(p, output=None)
    assert not (tmp_path / "MARKER").exists()


class _Boom:
    def __reduce__(self):
        import os

        return (os.system, ("touch MARKER",))


def test_a_pickle_checkpoint_is_refused_unread(tmp_path, monkeypatch):
    """A version-1 checkpoint (a pickle) whose payload would run a command: refused by its
    version before anything is read."""
    monkeypatch.chdir(tmp_path)
    p = checkpoint_of(tmp_path)
    with h5py.File(p, "r+") as f:
        f.attrs["format_version"] = 1
        f.create_dataset("objects", data=np.frombuffer(pickle.dumps(_Boom()), np.uint8))
    with pytest.raises(dpm.ParameterError, match="version 1 pickled the simulation"):
        dpm.restart(p)
    assert not (tmp_path / "MARKER").exists()


def test_a_missing_array_and_a_damaged_state_are_named(tmp_path):
    p = checkpoint_of(tmp_path)
    q = tmp_path / "copy.h5"
    shutil.copy(p, q)
    with h5py.File(q, "r+") as f:
        del f["arrays/a0"]
    with pytest.raises(dpm.ParameterError, match="array 'a0'.*missing from /arrays"):
        dpm.restart(q, output=None)
    with h5py.File(q, "r+") as f:
        del f["state"]
        f.create_dataset("state", data=np.frombuffer(b"[" * 100000, np.uint8))
    with pytest.raises(dpm.ParameterError, match="not the JSON text of a state"):
        dpm.restart(q, output=None)


def test_an_unstorable_object_is_refused_at_checkpoint_every(tmp_path):
    def local_motion():
        class Local(Sway):
            pass
        return Local()

    sim = small_scene()
    sim.boundaries[0].notes = {"made by": lambda: None}
    with pytest.raises(dpm.ParameterError,
                       match=r"sim\.boundaries\[0\]\.notes\['made by'\].*function"):
        sim.checkpoint_every(tmp_path / "run.ckpt.h5", every_steps=10)
    del sim.boundaries[0].notes
    sim.boundaries[0].motion_note = local_motion()
    with pytest.raises(dpm.ParameterError, match="defined inside a function"):
        sim.checkpoint_every(tmp_path / "run.ckpt.h5", every_steps=10)


def test_a_script_motion_restarts_bit_identical(tmp_path):
    def scene():
        sim = small_scene()
        glass = sim.materials[0]
        sim.add_boundary("wall", material=glass, center=(0.005, 0.005, 0.012),
                         half_extents=(0.01, 0.01), normal=(0, 0, -1),
                         motion=Sway())
        return sim

    one = scene()
    one.run(steps=80, progress=False)
    two = scene()
    two.run(steps=40, progress=False)
    two.checkpoint(tmp_path / "c.h5")
    back = dpm.restart(tmp_path / "c.h5", output=None)
    assert type(back.boundaries[-1].motion) is Sway
    back.run(steps=40, progress=False)
    np.testing.assert_array_equal(back.bodies.position, one.bodies.position)
    np.testing.assert_array_equal(back.bodies.velocity, one.bodies.velocity)


def test_load_names_a_checkpoint_and_other_files(tmp_path):
    p = checkpoint_of(tmp_path)
    with pytest.raises(dpm.ParameterError, match="is a dpm checkpoint: dpm.restart"):
        dpm.load(p)
    with pytest.raises(dpm.ParameterError, match="no such file"):
        dpm.load(tmp_path / "nothing.h5")
    (tmp_path / "text.h5").write_text("hello")
    with pytest.raises(dpm.ParameterError, match="not an HDF5 file"):
        dpm.load(tmp_path / "text.h5")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = 1
    with pytest.raises(dpm.ParameterError, match="another kind"):
        dpm.load(tmp_path / "other.h5")
