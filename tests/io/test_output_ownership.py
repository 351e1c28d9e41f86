"""One owner per output file, and restart never touches a file it was not told to (issue
#55, items 1, 2, 4 and 9): a second writer of a file that a live process writes is
refused naming it; a copied checkpoint restarted elsewhere leaves the original run's files
bit-identical; a file that another run replaced is refused on resume; checkpoint_every()
checks its directory at the call (item 7, plain-data checkpoints:
tests/io/test_plain_checkpoints.py).

The scene is the small box of tests/io/test_checkpoint.py (same law, boundary and
integrator: the compiled step module is reused), with fewer spheres.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest
from small_scene import small_scene

import dpm
from dpm import checkpoint as ckpt

HERE = Path(__file__).resolve().parent


def snapshot(d: Path) -> dict[str, bytes]:
    """Every file under ``d`` (hidden ones included) by name, with its bytes."""
    return {str(p.relative_to(d)): p.read_bytes() for p in sorted(d.rglob("*"))
            if p.is_file()}


def first_run(d: Path, steps: int = 60) -> Path:
    """A run writing ``d/run.h5`` every 10 steps with periodic checkpoints every 20
    (``d/run.ckpt.h5``); returns the checkpoint base."""
    sim = small_scene()
    sim.output(d / "run.h5", every_steps=10)
    sim.checkpoint_every(d / "run.ckpt.h5", every_steps=20, keep=2)
    sim.run(steps=steps, progress=False)
    sim.close()
    return d / "run.ckpt.h5"


# ----------------------------------------------------------------- 1. one writer per file
LIVE_RESTART = textwrap.dedent("""
    import sys
    sys.path.insert(0, {here!r})
    import dpm
    sim = dpm.restart(sys.argv[1])
    sim.run(steps=10, progress=False)  # the output file is open for writing
    print("running", flush=True)
    sys.stdin.readline()               # (held open until the test says go)
    sim.run(steps=20, progress=False)
    sim.close()
    print("done", sim.last_output.frames, flush=True)
""")


def test_a_second_restart_of_a_live_run_is_refused(tmp_path):
    """Two processes restarting one run: the first writes, the second is refused naming
    the file and the process; a new run with overwrite=True is refused at output(); the
    live file stays the first's (same inode), and it ends with every frame."""
    base = first_run(tmp_path)
    out = tmp_path / "run.h5"
    live = subprocess.Popen([sys.executable, "-c", LIVE_RESTART.format(here=str(HERE)),
                             str(base)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        line = live.stdout.readline().strip()
        assert line == "running", live.stderr.read()
        inode = os.stat(out).st_ino
        with pytest.raises(dpm.ParameterError) as err:
            dpm.restart(base)
        msg = str(err.value)
        assert str(out) in msg and f"process {live.pid}" in msg, msg
        assert os.stat(out).st_ino == inode  # not replaced
        other = small_scene()
        with pytest.raises(dpm.ParameterError, match=f"process {live.pid}"):
            other.output(out, every_steps=10, overwrite=True)
        assert os.stat(out).st_ino == inode
    finally:
        stdout, stderr = live.communicate("go\n", timeout=600)
    assert live.returncode == 0, stderr
    assert stdout.split() == ["done", "10"]  # frames 0..60 kept, 70..90 written
    run = dpm.load(out)
    np.testing.assert_array_equal(run.steps, np.arange(0, 91, 10))
    assert not [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    # once the writer is gone, the run restarts as before
    again = dpm.restart(base)
    again.run(steps=10, progress=False)
    again.close()


# ----------------------------------------------------------------- 2. a copied checkpoint
def test_a_copied_checkpoint_leaves_the_original_run_alone(tmp_path):
    """A checkpoint copied elsewhere and restarted there: the original run's output, its
    sidecars and checkpoints stay bit-identical (no file added or removed); the copy's run
    writes no output until sim.output() and its periodic checkpoints go beside it."""
    orig, other = tmp_path / "orig", tmp_path / "branch"
    orig.mkdir()
    other.mkdir()
    base = first_run(orig)
    before = snapshot(orig)
    copy = other / "from60.ckpt.h5"
    shutil.copy(ckpt.latest(base), copy)
    with pytest.warns(UserWarning, match="left untouched"):
        sim = dpm.restart(copy)
    assert snapshot(orig) == before  # the restart itself changes nothing
    sim.run(steps=60, progress=False)
    sim.output(other / "branch.h5", every_steps=10)
    sim.run(steps=20, progress=False)
    sim.close()
    assert snapshot(orig) == before
    assert dpm.load(other / "branch.h5").n_frames == 3
    assert [s for s, _ in ckpt.numbered_files(copy)] == [120, 140]
    # asked for, the original is continued (it is still that run's file)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim = dpm.restart(copy, output="continue")
    sim.run(steps=20, progress=False)
    sim.close()
    assert dpm.load(orig / "run.h5").n_frames == 7 + 2


# ----------------------------------------------------------------- 4. identity on resume
@pytest.mark.parametrize("other", ["another scene", "another run of the scene"])
def test_resume_refuses_a_file_another_run_replaced(tmp_path, other):
    """The run's checkpoint at step 40, then another run replaces run.h5: the restart
    refuses it by name and leaves it as it is (no frames of two runs in one file)."""
    sim = small_scene()
    sim.output(tmp_path / "run.h5", every_steps=10)
    sim.run(steps=40, progress=False)
    sim.checkpoint(tmp_path / "c.h5")
    sim.close()
    b = small_scene(friction=0.4) if other == "another scene" else small_scene(shift=1e-4)
    b.output(tmp_path / "run.h5", every_steps=10, overwrite=True)
    b.run(steps=60, progress=False)
    b.close()
    before = (tmp_path / "run.h5").read_bytes()
    why = "scene fingerprint" if other == "another scene" else "frame 4 holds other"
    with pytest.raises(dpm.ParameterError, match=f"not the output of the checkpoint's "
                       f"run: .*{why}"):
        dpm.restart(tmp_path / "c.h5")
    assert (tmp_path / "run.h5").read_bytes() == before


# ----------------------------------------------------------------- 9. checked at the call
def test_checkpoint_every_checks_its_directory_at_the_call(tmp_path):
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    sim = dpm.Simulation(dt=1e-5)
    for bad in (blocker / "run.ckpt.h5", blocker / "sub" / "run.ckpt.h5"):
        with pytest.raises(dpm.ParameterError) as err:
            sim.checkpoint_every(bad, every_steps=10)
        msg = str(err.value)
        assert msg.startswith("sim.checkpoint_every(): path=") and str(bad) in msg
        assert "is a file, not a directory" in msg and "allowed:" in msg
    assert sim.operations.checkpoints is None
    if os.path.isdir("/proc/self"):  # /proc takes no file, not even from root
        with pytest.raises(dpm.ParameterError, match="no file can be created in '/proc'"):
            sim.checkpoint_every("/proc/run.ckpt.h5", every_steps=10)
    if os.name == "posix" and os.geteuid() != 0:  # (root writes anywhere)
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        try:
            with pytest.raises(dpm.ParameterError, match="no file can be created"):
                sim.checkpoint_every(ro / "run.ckpt.h5", every_steps=10)
        finally:
            ro.chmod(0o755)
    sim.checkpoint_every(tmp_path / "new" / "run.ckpt.h5", every_steps=10)  # created
    assert (tmp_path / "new").is_dir() and list((tmp_path / "new").iterdir()) == []


# ----------------------------------------------------------------- 11. stale temporaries
def test_temporary_files_of_dead_writers_are_cleaned(tmp_path):
    """Temporary files that killed writers left (output, sidecar, checkpoint) are removed
    by the next writer in that directory; those of a live process are left."""
    from dpm.io.hdf5 import _HOST

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    pid = int(dead.stdout)
    stale = [tmp_path / f".run.h5.{_HOST}.{pid}.k2j4.tmp",
             tmp_path / f".run.xdmf.{_HOST}.{pid}.a8x1.tmp",
             tmp_path / f".run.ckpt.0000000020.h5.{_HOST}.{pid}.q0w9.tmp"]
    live = tmp_path / f".run.h5.{_HOST}.{os.getppid()}.zz11.tmp"
    other_host = tmp_path / f".run.h5.elsewhere.{pid}.zz12.tmp"
    for p in (*stale, live, other_host):
        p.write_bytes(b"x" * 100)
    first_run(tmp_path, steps=20)
    assert not any(p.exists() for p in stale)
    assert live.exists() and other_host.exists()


# ----------------------------------------------------------------- repair in place
KILLED_RUN = textwrap.dedent("""
    import os, signal, sys
    sys.path.insert(0, {here!r})
    from small_scene import small_scene
    sim = small_scene()
    sim.output(sys.argv[1] + "/run.h5", every_steps=10)
    sim.checkpoint_every(sys.argv[1] + "/run.ckpt.h5", every_steps=20, keep=2)
    sim.run(steps=45, progress=False)
    os.kill(os.getpid(), signal.SIGKILL)
""")


def test_a_killed_runs_file_is_repaired_in_place(tmp_path):
    """A run killed with its output open for writing: the restart clears HDF5's "open for
    writing" flags in place (h5clear -s) instead of copying the file (same inode), and the
    run ends with every frame equal to the uninterrupted run's."""
    p = subprocess.run([sys.executable, "-c", KILLED_RUN.format(here=str(HERE.parent)),
                        str(tmp_path)], capture_output=True, text=True, check=False)
    assert p.returncode == -9, p.stderr
    out = tmp_path / "run.h5"
    assert open(out, "rb").read(12)[11] != 0  # (left marked open for writing)
    inode = os.stat(out).st_ino
    sim = dpm.restart(tmp_path / "run.ckpt.h5")
    assert sim.step_count == 40
    assert os.stat(out).st_ino == inode  # not copied
    sim.run(steps=20, progress=False)
    sim.close()
    ref = small_scene()
    ref.output(tmp_path / "ref.h5", every_steps=10)
    ref.run(steps=60, progress=False)
    ref.close()
    a, b = dpm.load(out), dpm.load(tmp_path / "ref.h5")
    assert a.n_frames == b.n_frames == 7
    for k in range(7):
        for name, value in b.frame(k).items():
            np.testing.assert_array_equal(a.frame(k)[name], value)
