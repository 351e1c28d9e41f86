"""Disk full during output and during a checkpoint (issue #55, item 3): the run stops with
:class:`dpm.OutputError` naming the file, the frame or checkpoint and the checkpoint to
restart from; nothing fake is written (every frame that dpm.load reports equals the
uninterrupted run's, bit for bit); the restart from the last checkpoint ends bit-identical
to the uninterrupted run. The full disk is a file-size limit of the process
(tests/scripts/disk_full.py): writes past it fail as they do on a full disk; where the test
may mount a file system (root), a small tmpfs fills up for real.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from small_scene import small_scene

import dpm
from dpm import checkpoint as ckpt

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "disk_full.py"
STEPS = 600


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> tuple[Path, dpm.Simulation]:
    d = tmp_path_factory.mktemp("ref")
    sim = small_scene()
    sim.output(d / "ref.h5", every_steps=10)
    sim.run(steps=STEPS, progress=False)
    sim.close()
    return d / "ref.h5", sim


def full_disk(d: Path, mode: str) -> subprocess.CompletedProcess:
    p = subprocess.run([sys.executable, str(SCRIPT), str(d), mode], capture_output=True,
                       text=True, timeout=600, check=False)
    assert p.returncode == 3, (p.returncode, p.stdout, p.stderr)  # (no crash, no segfault)
    assert "Exception ignored" not in p.stderr, p.stderr
    return p


def same_frames(run: dpm.io.Run, ref: dpm.io.Run, n: int) -> None:
    for k in range(n):
        a, b = run.frame(k), ref.frame(k)
        assert a.keys() == b.keys()
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"frame {k} {name}")


def test_disk_full_during_output(reference, tmp_path):
    ref_path, ref = reference
    p = full_disk(tmp_path, "output")
    msg = p.stdout
    newest, base = ckpt.numbered_files(tmp_path / "run.ckpt.h5")[-1]
    assert "run.h5" in msg and "failed" in msg and "File too large" in msg, msg
    assert f"restart from the last checkpoint, step {newest}" in msg and str(base) in msg, msg
    run = dpm.load(tmp_path / "run.h5")
    assert 21 <= run.n_frames < STEPS // 10 + 1  # (frames 0-20 before the limit)
    same_frames(run, dpm.load(ref_path), run.n_frames)  # no fake frame
    assert not [q.name for q in tmp_path.iterdir() if q.name.endswith(".tmp")]
    # space again: the restart continues the file from the checkpoint, to the end
    sim = dpm.restart(tmp_path / "run.ckpt.h5")
    sim.run(steps=STEPS - sim.step_count, progress=False)
    sim.close()
    run = dpm.load(tmp_path / "run.h5")
    assert run.n_frames == STEPS // 10 + 1
    same_frames(run, dpm.load(ref_path), run.n_frames)
    np.testing.assert_array_equal(sim.bodies.position, ref.bodies.position)


def test_disk_full_during_a_checkpoint(reference, tmp_path):
    _, ref = reference
    p = full_disk(tmp_path, "checkpoint")
    msg = p.stdout
    assert "writing the checkpoint" in msg and "at step 250 failed" in msg, msg
    assert "intact" in msg and "step 200" in msg, msg
    assert not [q.name for q in tmp_path.iterdir() if q.name.endswith(".tmp")]
    assert [s for s, _ in ckpt.numbered_files(tmp_path / "run.ckpt.h5")] == [150, 200]
    sim = dpm.restart(tmp_path / "run.ckpt.h5")
    sim.run(steps=STEPS - sim.step_count, progress=False)
    np.testing.assert_array_equal(sim.bodies.position, ref.bodies.position)
    np.testing.assert_array_equal(sim.bodies.velocity, ref.bodies.velocity)


def test_a_full_file_system(reference, tmp_path):
    """A real ENOSPC: the output on a 1.5 MB tmpfs (skipped where mounting is not
    allowed). The run stops naming the device error; the frames on it are the
    uninterrupted run's."""
    ref_path, _ = reference
    full = tmp_path / "full"
    full.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1500k",
                                            "tmpfs", str(full)], capture_output=True,
                                           check=False).returncode:
        pytest.skip("cannot mount a small file system here (needs root)")
    try:
        p = full_disk(tmp_path, "enospc")
        assert "No space left on device" in p.stdout and "run.h5" in p.stdout, p.stdout
        run = dpm.load(full / "run.h5")
        assert run.n_frames > 21
        same_frames(run, dpm.load(ref_path), min(run.n_frames, STEPS // 10 + 1))
    finally:
        subprocess.run(["umount", str(full)], check=False)
