"""Checkpoints and restart: a restarted run continues the uninterrupted one bit for bit.

The scene (tests/scripts/restart_scene.py) has clustered bodies, a rotating triangle mesh,
an inlet with a shape mix and size range, an outlet, the Gear integrator, output frames and
periodic checkpoints; each run is a process of its own (as after a crash).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import dpm
from dpm import checkpoint as ckpt

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "restart_scene.py"
STEPS = 1200


def run_scene(d: Path, mode: str, steps: int = STEPS) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), str(d), mode, str(steps)],
                          capture_output=True, text=True, timeout=900, check=False)


def assert_same_state(a: Path, b: Path) -> None:
    x, y = np.load(a), np.load(b)
    assert set(x.files) == set(y.files)
    differ = [k for k in x.files if not np.array_equal(x[k], y[k])]
    assert not differ, f"arrays that differ after the restart: {differ}"


def assert_same_frames(a: Path, b: Path) -> None:
    ra, rb = dpm.load(a), dpm.load(b)
    assert ra.n_frames == rb.n_frames > 0
    assert np.array_equal(ra.times, rb.times)
    for k in range(ra.n_frames):
        fa, fb = ra.frame(k), rb.frame(k)
        for name in fa:
            assert np.array_equal(fa[name], fb[name]), (k, name)
    for name in ra.removed:
        assert np.array_equal(ra.removed[name], rb.removed[name]), name


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("full")
    p = run_scene(d, "full")
    assert p.returncode == 0, p.stderr
    return d


def test_restart_in_a_new_process_is_bit_identical(uninterrupted, tmp_path):
    """Run N steps; run N/2, checkpoint, restart in a new process, run N/2: every array of
    the state (bodies, elements' contacts with their history, integrator state, boundary
    frames and loads, outlet records, inlet count) and every output frame are equal."""
    p = run_scene(tmp_path, "half")
    assert p.returncode == 0, p.stderr
    p = run_scene(tmp_path, "rest")
    assert p.returncode == 0, p.stderr
    full = np.load(uninterrupted / "full.npz")
    assert len(full["removed"]) >= 1 and int(full["inserted"]) > 20  # the flows worked
    assert_same_state(uninterrupted / "full.npz", tmp_path / "rest.npz")
    assert_same_frames(uninterrupted / "full.h5", tmp_path / "half.h5")


def newest_step(d: Path) -> int:
    files = ckpt.numbered_files(d / "run.ckpt.h5")
    return files[-1][0] if files else -1


def kill_and_restart(d: Path, kills: int, seed: int) -> list[int]:
    """Start the checkpointing run, kill it (SIGKILL) at a random moment, restart from the
    newest checkpoint, ``kills`` times; then let it finish. The moment: a random time
    (0-0.8 s, about one checkpoint interval here) after the run wrote a new checkpoint,
    so that every restart makes progress and the kills fall during steps, checkpoint
    writes and output writes alike. Returns the step each restart began from."""
    rng = np.random.default_rng(seed)
    began = []
    mode = "start"
    for _ in range(kills):
        before = newest_step(d)
        proc = subprocess.Popen([sys.executable, str(SCRIPT), str(d), mode, str(STEPS)],
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        assert proc.stdout.readline().strip() == "running"
        t0 = time.monotonic()
        while proc.poll() is None and newest_step(d) <= before and time.monotonic() - t0 < 60:
            time.sleep(0.01)
        time.sleep(float(rng.uniform(0.0, 0.8)))
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        if newest_step(d) < 0:
            mode = "start"  # killed before the first checkpoint: from the beginning
            continue
        mode = "resume"
        began.append(newest_step(d))
        # whatever the kill left, the output file opens
        dpm.load(d / "run.h5")
    p = run_scene(d, mode)
    assert p.returncode == 0, p.stderr
    return began


def test_killed_runs_restart_bit_identical(uninterrupted, tmp_path):
    """3 kills at random moments; each restart from the newest checkpoint; the end state
    and the output equal the uninterrupted run's (the 20-kill version is in the slow
    set)."""
    kill_and_restart(tmp_path, 3, seed=1)
    name = "resume" if (tmp_path / "resume.npz").exists() else "start"
    assert_same_state(uninterrupted / "full.npz", tmp_path / f"{name}.npz")
    assert_same_frames(uninterrupted / "full.h5", tmp_path / "run.h5")
    assert len(ckpt.numbered_files(tmp_path / "run.ckpt.h5")) <= 2  # keep=2


@pytest.mark.slow
def test_twenty_kills(uninterrupted, tmp_path):
    """The reliability promise: 20 kills -9 at random moments, each restarted from the
    newest checkpoint, end bit-equal to the uninterrupted run, every output readable."""
    began = kill_and_restart(tmp_path, 20, seed=2)
    assert len(set(began)) >= 5  # (the kills fell all over the run)
    name = "resume" if (tmp_path / "resume.npz").exists() else "start"
    assert_same_state(uninterrupted / "full.npz", tmp_path / f"{name}.npz")
    assert_same_frames(uninterrupted / "full.h5", tmp_path / "run.h5")


# ----------------------------------------------------------------- in one process
def small_scene(friction: float = 0.5) -> dpm.Simulation:
    sim = dpm.Simulation(dt=2e-5, gravity=(0, 0, -9.81))
    glass = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(glass, glass, model="hertz_mindlin", restitution=0.3, friction=friction)
    sim.add_boundary("box", material=glass, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02),
                     open=("+z",))
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.008), spacing=2.1e-3, jitter=4e-5)
    sim.add_particles("sphere", material=glass, radius=1e-3, positions=xyz)
    return sim


def test_checkpoint_file_layout_and_atomic_write(tmp_path):
    sim = small_scene()
    sim.run(steps=200)
    path = sim.checkpoint(tmp_path / "a.h5")
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == "dpm-checkpoint" and f.attrs["step"] == 200
        assert f.attrs["bodies"] == len(sim.bodies)
        # the state arrays are plain datasets: the positions are among them
        assert any(ds.shape == sim.bodies.position.shape
                   and np.array_equal(ds[()], sim.bodies.position)
                   for ds in f["arrays"].values())
    assert not list(tmp_path.glob(".*tmp"))  # no temporary file left
    back = dpm.restart(path)
    assert back.step_count == 200 and back.time == sim.time
    sim.run(steps=300)
    back.run(steps=300)
    assert np.array_equal(sim.bodies.position, back.bodies.position)
    assert np.array_equal(sim.contacts.history, back.contacts.history)


def test_restart_refuses_other_version_scene_and_files(tmp_path):
    sim = small_scene()
    sim.run(steps=10)
    path = sim.checkpoint(tmp_path / "a.h5")
    with pytest.raises(dpm.ParameterError, match="another scene; first difference: "
                       "contacts.glass-glass.params.friction"):
        dpm.restart(path, scene=small_scene(friction=0.4))
    dpm.restart(path, scene=small_scene())  # the same scene built again: accepted
    with h5py.File(path, "r+") as f:
        f.attrs["dpm_version"] = "0.0.1"
    with pytest.raises(dpm.ParameterError, match="written by dpm 0.0.1"):
        dpm.restart(path)
    out = tmp_path / "out.h5"
    s2 = small_scene()
    s2.output(out, every_steps=5)
    s2.run(steps=5)
    s2.close()
    with pytest.raises(dpm.ParameterError, match="is not a dpm checkpoint"):
        dpm.restart(out)
    (tmp_path / "junk.h5").write_bytes(b"not hdf5")
    with pytest.raises(dpm.ParameterError, match="cannot be read as a checkpoint"):
        dpm.restart(tmp_path / "junk.h5")
    with pytest.raises(dpm.ParameterError, match="no checkpoint at"):
        dpm.restart(tmp_path / "none.h5")


def test_periodic_checkpoints_keep_the_last_k(tmp_path):
    sim = small_scene()
    sim.checkpoint_every(tmp_path / "c.h5", every_steps=50, keep=3)
    sim.run(steps=400)
    files = ckpt.numbered_files(tmp_path / "c.h5")
    assert [s for s, _ in files] == [300, 350, 400]
    assert ckpt.latest(tmp_path / "c.h5") == files[-1][1]
    with pytest.raises(dpm.ParameterError, match="every_steps=2.5 must be an integer"):
        sim.checkpoint_every(tmp_path / "c.h5", every_steps=2.5)
    with pytest.raises(dpm.ParameterError, match="exactly one of every"):
        sim.checkpoint_every(tmp_path / "c.h5")


class _PluginState:
    """A plugin that counts steps in its own state and keeps it through a restart."""

    def __init__(self) -> None:
        self.count = 0
        self.restored = None

    @dpm.hookimpl
    def dpm_on_output(self, sim, frame, path):
        self.count += 1

    @dpm.hookimpl
    def dpm_on_checkpoint(self, sim, state):
        state["counter"] = self.count

    @dpm.hookimpl
    def dpm_on_restart(self, sim, state):
        self.restored = state.get("counter")


def test_plugin_state_goes_through_the_hooks(tmp_path):
    plugin = _PluginState()
    mgr = dpm.registry().manager
    mgr.register(plugin)
    try:
        sim = small_scene()
        sim.output(tmp_path / "o.h5", every_steps=10)
        sim.run(steps=30)
        sim.checkpoint(tmp_path / "p.h5")
        assert plugin.count == 4
        sim._writer.file.close()  # (as if the process had ended: the restart reopens it)
        back = dpm.restart(tmp_path / "p.h5")
        assert plugin.restored == 4
        back.run(steps=10)  # the output goes on in the file the run was writing
        back.close()
        assert dpm.load(tmp_path / "o.h5").n_frames == 5
    finally:
        mgr.unregister(plugin)


def test_a_checkpoint_onto_an_existing_one_replaces_it_atomically(tmp_path):
    """A checkpoint onto an existing one replaces it atomically (os.replace)."""
    sim = small_scene()
    sim.run(steps=10)
    p = tmp_path / "x.h5"
    sim.checkpoint(p)
    ino = os.stat(p).st_ino
    sim.run(steps=10)
    sim.checkpoint(p)
    assert os.stat(p).st_ino != ino
    assert dpm.restart(p).step_count == 20
