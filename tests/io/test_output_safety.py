"""Output that never loses or silently overwrites data: an existing file is kept unless
overwrite=True, the path is checked at output() time, the file is created atomically (a
kill at any moment leaves a file dpm.load opens, every frame in it complete), a lagging
XDMF sidecar is rebuilt, and Writer.resume cuts a file back to a checkpoint."""

import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pytest

import dpm
from dpm.io import hdf5
from dpm.io.hdf5 import Writer

HERE = os.path.dirname(os.path.abspath(__file__))


def _tiny_sim():
    """48 spheres in a box: compiles the same kernels as tests/io/test_io.py."""
    sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81))
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02), open="+z")
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.007), 2.2e-3, jitter=5e-5)
    sim.add_particles("sphere", material=m, radius=1e-3, positions=xyz,
                      velocities=np.full((len(xyz), 3), 0.01))
    return sim


# ---------------------------------------------------------------- a stand-in Simulation
class _Rows(SimpleNamespace):
    def __len__(self):
        return len(self.radius)


def _fake_sim(k, nb=2):
    """The state of 'frame k' of a made-up run: what Writer reads from a Simulation,
    with a particle count and element count that change from frame to frame."""
    rng = np.random.default_rng(k)
    n = 5 + k % 3
    bodies = _Rows(id=np.arange(n) + 10 * k, position=rng.random((n, 3)),
                   velocity=rng.random((n, 3)), orientation=rng.random((n, 4)),
                   angular_velocity=rng.random((n, 3)), radius=rng.random(n),
                   mass=rng.random(n), material=np.zeros(n, "i4"),
                   shape=np.zeros(n, "i4"))
    owner = np.repeat(np.arange(n), 2)
    elements = _Rows(position=rng.random((2 * n, 3)), radius=rng.random(2 * n), owner=owner)
    tri = (np.eye(3), np.array([[0, 1, 2]]))  # a surface of one triangle, at rest
    boundaries = [SimpleNamespace(name="box", force=rng.random(3), torque=rng.random(3),
                                  motion=None, surface=lambda extent: tri)
                  for _ in range(nb)]
    return SimpleNamespace(dt=1e-5, gravity=(0.0, 0.0, -9.81),
                           integrator=SimpleNamespace(name="velocity_verlet"),
                           materials=[SimpleNamespace(name="glass")], boundaries=boundaries,
                           bodies=bodies, elements=elements,
                           plan=SimpleNamespace(spheres_only=False),
                           step_count=100 * k, time=1e-3 * k, shape_names=["sphere"])


def _removals(k):
    rng = np.random.default_rng(100 + k)
    m = 1 + k % 2
    return {"id": np.arange(m) + 1000 * k, "time": rng.random(m), "mass": rng.random(m),
            "residence_time": rng.random(m), "position": rng.random((m, 3)),
            "velocity": rng.random((m, 3))}


def _write_frames(w, ks):
    for k in ks:
        w.write(_fake_sim(k))
        w.write_removed(_removals(k), k % 2)


def _contents(path):
    out = {}
    with h5py.File(path, "r") as f:
        out["attrs"] = {k: np.asarray(v).tolist() for k, v in f.attrs.items()}

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = (obj.dtype, obj.maxshape, obj.chunks, obj[()])
        f.visititems(visit)
    return out


def _assert_same_file(a, b):
    ca, cb = _contents(a), _contents(b)
    assert ca.keys() == cb.keys()
    assert ca.pop("attrs") == cb.pop("attrs")
    for name in ca:
        (da, ma, ka, va), (db, mb, kb, vb) = ca[name], cb[name]
        assert (da, ma, ka) == (db, mb, kb), name
        np.testing.assert_array_equal(va, vb, err_msg=name)


# ---------------------------------------------------------------- 1. overwrite rule
def test_existing_file_is_kept_unless_overwrite(tmp_path):
    path = tmp_path / "run.h5"
    sim = _tiny_sim()
    sim.output(path, every_steps=10)
    sim.run(steps=100, progress=False)
    sim.close()
    assert dpm.load(path).n_frames == 11
    again = _tiny_sim()
    with pytest.raises(dpm.ParameterError) as err:
        again.output(path, every_steps=50)
    msg = str(err.value)
    assert str(path) in msg and "overwrite=True" in msg and "another name" in msg
    assert dpm.load(path).n_frames == 11  # untouched
    # overwrite=True replaces the file and its sidecars (a stale elements sidecar goes)
    stale = path.with_suffix(".elements.xdmf")
    stale.write_text("<Xdmf/>")
    again.output(path, every_steps=50, overwrite=True)
    assert dpm.load(path).n_frames == 11  # replaced only when the run starts
    again.run(steps=100, progress=False)
    again.close()
    run = dpm.load(path)
    assert run.n_frames == 3
    np.testing.assert_array_equal(run.steps, [0, 50, 100])
    assert not stale.exists()
    assert len(ET.parse(path.with_suffix(".xdmf")).findall(".//Grid[@GridType='Uniform']")) == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.boundaries.xdmf", "run.h5",
                                                          "run.xdmf"]


def test_file_appearing_before_the_run_is_kept(tmp_path):
    path = tmp_path / "run.h5"
    sim = dpm.Simulation(dt=1e-5)
    sim.output(str(path), every_steps=10)
    path.write_bytes(b"someone else's data")
    with pytest.raises(dpm.ParameterError, match="already exists"):
        Writer(path, _fake_sim(0))
    assert path.read_bytes() == b"someone else's data"
    assert [p.name for p in tmp_path.iterdir()] == ["run.h5"]  # no temporary file left


def test_same_path_while_writing_appends(tmp_path):
    path = tmp_path / "run.h5"
    sim = _tiny_sim()
    sim.output(path, every_steps=50)
    sim.run(steps=100, progress=False)
    sim.output(str(path), every_steps=25)  # the open file: keep appending, new interval
    sim.run(steps=50, progress=False)
    sim.close()
    np.testing.assert_array_equal(dpm.load(path).steps, [0, 50, 100, 125, 150])


# ---------------------------------------------------------------- 2. checks at output()
@pytest.mark.parametrize("path, why", [(None, "a file name"), (12, "a file name"),
                                       ("", "non-empty"), (True, "a file name")])
def test_output_refuses_non_paths(tmp_path, monkeypatch, path, why):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(dpm.ParameterError, match=why):
        dpm.Simulation(dt=1e-5).output(path, every_steps=10)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kw, why", [
    ({"every": "0.1"}, "every='0.1' is not a number"),
    ({"every_steps": "10"}, "every_steps='10' is not a number"),
    ({"every_steps": True}, "every_steps=True is not a number"),
    ({"every": False}, "every=False is not a number"),
    ({"every_steps": 2.5}, "every_steps=2.5; allowed: an integer"),
    ({"every_steps": 0}, "outside"),
    ({"every": -1.0}, "outside"),
    ({"every": 1.0, "every_steps": 3}, "exactly one"),
])
def test_output_checks_the_interval(tmp_path, kw, why):
    with pytest.raises(dpm.ParameterError, match=why):
        dpm.Simulation(dt=1e-5).output(tmp_path / "run.h5", **kw)


def test_output_accepts_integral_float_steps(tmp_path):
    sim = dpm.Simulation(dt=1e-5)
    sim.output(tmp_path / "run.h5", every_steps=1e3)
    assert sim.operations.frames.every == 1000


def test_output_checks_the_path_before_the_run(tmp_path):
    sim = dpm.Simulation(dt=1e-5)
    with pytest.raises(dpm.ParameterError, match="it is a directory"):
        sim.output(tmp_path, every_steps=10)
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    with pytest.raises(dpm.ParameterError) as err:
        sim.output(blocker / "run.h5", every_steps=10)
    assert str(blocker / "run.h5") in str(err.value)
    assert f"{str(blocker)!r} is a file, not a directory" in str(err.value)
    with pytest.raises(dpm.ParameterError, match="is a file, not a directory"):
        sim.output(blocker / "sub" / "run.h5", every_steps=10)
    # a missing directory is created
    sim.output(tmp_path / "a" / "b" / "run.h5", every_steps=10)
    assert (tmp_path / "a" / "b").is_dir() and list((tmp_path / "a" / "b").iterdir()) == []


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="Linux /proc")
def test_output_refuses_an_impossible_directory():
    # /proc takes no new directory or file, not even from root
    with pytest.raises(dpm.ParameterError, match="'/proc/dpm-no-such/run.h5'.*cannot be "):
        dpm.Simulation(dt=1e-5).output("/proc/dpm-no-such/run.h5", every_steps=10)
    with pytest.raises(dpm.ParameterError, match="'/proc/run.h5'.*no file can be created"):
        dpm.Simulation(dt=1e-5).output("/proc/run.h5", every_steps=10)


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0,
                    reason="root writes into read-only directories")
def test_output_refuses_a_read_only_directory(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(dpm.ParameterError, match="no file can be created"):
            dpm.Simulation(dt=1e-5).output(ro / "run.h5", every_steps=10)
    finally:
        ro.chmod(0o755)


# ---------------------------------------------------------------- 3. atomic creation
def test_a_file_without_frames_loads(tmp_path):
    path = tmp_path / "run.h5"
    w = Writer(path, _fake_sim(0))  # as a run killed right after creating its file
    w.file.close()
    assert [p.name for p in tmp_path.iterdir()] == ["run.h5"]
    run = dpm.load(path)
    assert run.n_frames == 0 and len(run.times) == 0
    with pytest.raises(IndexError, match="0 complete frame"):
        run.frame(0)
    with pytest.raises(IndexError):
        run.elements(-1)
    with h5py.File(path, "r") as f:  # the whole layout is there from the start
        assert f.attrs["format"] == "dpm-hdf5"
        for group in ("particles", "elements", "frames", "boundaries", "removed"):
            assert len(f[group]) > 0
    assert Path(path).stat().st_mode & 0o777 == 0o666 & ~_umask()


def _umask():
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def test_a_partly_written_frame_is_dropped(tmp_path):
    path = tmp_path / "run.h5"
    w = Writer(path, _fake_sim(0))
    _write_frames(w, range(3))
    # frame 3's table entry without its rows (what an unordered flush could leave)
    fr = w.file["frames"]
    for name in hdf5.FRAME_FIELDS:
        fr[name].resize(4, axis=0)
    fr["start"][3], fr["count"][3] = w.rows, 7
    for name in ("force", "torque"):
        w.file["boundaries"][name].resize(4, axis=0)
    w.file.close()
    with pytest.warns(UserWarning):
        run = dpm.load(path)
    assert run.n_frames == 3


KILL_CHILD = textwrap.dedent("""
    import sys
    sys.path.insert(0, {here!r})
    from test_output_safety import _tiny_sim
    path, steps = sys.argv[1], int(sys.argv[2])
    warm = _tiny_sim()
    warm.run(steps=5, progress=False)  # compiled (or loaded from the cache) before the marker
    sim = _tiny_sim()
    sim.output(path, every_steps=3)
    print("started", flush=True)
    sim.run(steps=steps, progress=False)
    sim.close()
    print("done", flush=True)
""")


def _child(path, steps):
    return subprocess.Popen([sys.executable, "-c", KILL_CHILD.format(here=HERE), str(path),
                             str(steps)], stdout=subprocess.PIPE, text=True)


def _killed_runs(tmp_path, delays):
    """Start the run in a subprocess, SIGKILL it ``delay`` s after its marker line."""
    paths = []
    for i, delay in enumerate(delays):
        path = tmp_path / f"killed{i}.h5"
        proc = _child(path, 10_000_000)
        try:
            assert proc.stdout.readline().strip() == "started"
            time.sleep(delay)
        finally:
            proc.send_signal(signal.SIGKILL)
            proc.wait()
        paths.append(path)
    return paths


def _check_killed_against_reference(tmp_path, delays):
    paths = _killed_runs(tmp_path, delays)
    frames = []
    for path in paths:
        if not path.exists():  # killed before the file was published: nothing lost
            frames.append(None)
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the sidecar lags: rewritten, tested below
            frames.append(dpm.load(path).n_frames)
    assert any(n for n in frames if n), f"no kill landed after the first frame: {frames}"
    most = max(n for n in frames if n is not None)
    ref_path = tmp_path / "reference.h5"
    proc = _child(ref_path, 3 * max(most - 1, 0))
    assert proc.communicate()[0].split() == ["started", "done"]
    ref = dpm.load(ref_path)
    assert ref.n_frames == most
    for path, n in zip(paths, frames, strict=True):
        if n is None:
            continue
        run = dpm.load(path, repair_xdmf=False)
        np.testing.assert_array_equal(run.steps, ref.steps[:n])
        np.testing.assert_array_equal(run.times, ref.times[:n])
        np.testing.assert_array_equal(run.boundary_force, ref.boundary_force[:n])
        for k in range(n):
            got, want = run.frame(k), ref.frame(k)
            for name in hdf5.FIELDS:
                np.testing.assert_array_equal(got[name], want[name], err_msg=f"{path} {k}")
        # no half-built file under the final name; at most the temporary it was built in
        leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(f".{path.name}")]
        assert all(p.endswith(".tmp") for p in leftovers)
    return frames


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_kill_at_random_moments_after_start(tmp_path):
    # the marker comes before the run's preparation (~0.2 s on one core); the file is then
    # created (~30 ms) and a frame written every ~7 ms: 0 s kills before the file exists,
    # 0.15-0.3 s around its creation and first frames, 0.3-0.6 s some 10-50 frames in
    rng = np.random.default_rng(7)
    delays = [0.0, *rng.uniform(0.15, 0.3, 5), *rng.uniform(0.3, 0.6, 3)]
    frames = _check_killed_against_reference(tmp_path, delays)
    print("frames per kill:", frames)


@pytest.mark.slow
@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_kill_at_many_random_moments(tmp_path):
    rng = np.random.default_rng(11)
    _check_killed_against_reference(tmp_path, rng.uniform(0.0, 1.0, 40))


# ---------------------------------------------------------------- 4. XDMF sidecar
def _grids(path):
    return len(ET.parse(path).getroot().findall(".//Grid[@GridType='Uniform']"))


def _lagging(tmp_path):
    path = tmp_path / "run.h5"
    w = Writer(path, _fake_sim(0))
    _write_frames(w, range(4))  # the sidecar is written after frame 1, then every 5 s
    w.file.close()  # killed: no sidecar at close
    return path


def test_load_rebuilds_a_lagging_sidecar(tmp_path):
    path = _lagging(tmp_path)
    assert _grids(path.with_suffix(".xdmf")) == 1
    with pytest.warns(UserWarning, match=r"run.xdmf lists 1 frame\(s\).*has 4; rewrote"):
        run = dpm.load(path)
    assert run.n_frames == 4
    assert _grids(path.with_suffix(".xdmf")) == 4
    assert _grids(path.with_suffix(".elements.xdmf")) == 4
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        dpm.load(path)  # now in step: no warning


def test_load_leaves_a_read_only_file_alone(tmp_path, monkeypatch):
    path = _lagging(tmp_path)
    before = path.with_suffix(".xdmf").read_text()
    monkeypatch.setattr(hdf5.os, "access", lambda p, mode: False)
    with pytest.warns(UserWarning, match="read-only, the sidecar is not rewritten"):
        dpm.load(path)
    assert path.with_suffix(".xdmf").read_text() == before


def test_write_xdmf_rebuilds_explicitly(tmp_path):
    path = _lagging(tmp_path)
    path.with_suffix(".xdmf").unlink()
    assert hdf5.write_xdmf(path) == path.with_suffix(".xdmf")
    assert _grids(path.with_suffix(".xdmf")) == 4
    path.with_suffix(".xdmf").unlink()
    dpm.load(path, repair_xdmf=False).write_xdmf()
    assert _grids(path.with_suffix(".xdmf")) == 4


def test_sidecar_write_is_atomic(tmp_path, monkeypatch):
    path = _lagging(tmp_path)
    hdf5.write_xdmf(path)
    before = path.with_suffix(".xdmf").read_text()

    def half(self, text, *a, **k):
        with open(self, "w") as fh:
            fh.write(text[: len(text) // 2])
        raise KeyboardInterrupt  # stands in for a kill in the middle of the write

    monkeypatch.setattr(Path, "write_text", half)
    with pytest.raises(KeyboardInterrupt):
        hdf5.write_xdmf(path)
    monkeypatch.undo()
    assert path.with_suffix(".xdmf").read_text() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "run.boundaries.xdmf", "run.elements.xdmf", "run.h5", "run.xdmf"]


# ---------------------------------------------------------------- 5. resume
def test_resume_equals_one_go(tmp_path):
    one_go = tmp_path / "one_go.h5"
    w = Writer(one_go, _fake_sim(0))
    _write_frames(w, range(5))
    w.close()
    resumed = tmp_path / "resumed.h5"
    w = Writer(resumed, _fake_sim(0))
    _write_frames(w, range(3))
    state = w.state()
    assert state == {"frames": 3, "removed": 4, "path": str(resumed)}
    _write_frames(w, range(3, 5))  # written after the checkpoint, then the run stops
    w.close()
    w = Writer.resume(state["path"], _fake_sim(3), state["frames"], state["removed"])
    assert (w.frames, w.removed) == (3, 4)
    assert dpm.load(resumed, repair_xdmf=False).n_frames == 3
    _write_frames(w, range(3, 5))
    assert w.state() == {"frames": 5, "removed": 7, "path": str(resumed)}
    w.close()
    _assert_same_file(one_go, resumed)
    assert _grids(resumed.with_suffix(".xdmf")) == 5


RESUME_CHILD = textwrap.dedent("""
    import os, signal, sys
    sys.path.insert(0, {here!r})
    from test_output_safety import Writer, _fake_sim, _write_frames
    w = Writer(sys.argv[1], _fake_sim(0))
    _write_frames(w, range(4))
    os.kill(os.getpid(), signal.SIGKILL)  # the file stays marked open for SWMR writing
""")


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_resume_a_file_a_killed_run_left_open(tmp_path):
    one_go = tmp_path / "one_go.h5"
    w = Writer(one_go, _fake_sim(0))
    _write_frames(w, range(5))
    w.close()
    killed = tmp_path / "killed.h5"
    subprocess.run([sys.executable, "-c", RESUME_CHILD.format(here=HERE), str(killed)])
    with pytest.raises(OSError):  # HDF5 itself refuses to reopen it for writing
        h5py.File(killed, "r+", libver="latest")
    w = Writer.resume(killed, _fake_sim(2), 2, 3)
    _write_frames(w, range(2, 5))
    w.close()
    _assert_same_file(one_go, killed)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_resume_at_zero_and_refusals(tmp_path):
    path = tmp_path / "run.h5"
    w = Writer(path, _fake_sim(0))
    _write_frames(w, range(2))
    w.close()
    w = Writer.resume(path, _fake_sim(0), 0, 0)
    _write_frames(w, range(2))
    w.close()
    other = tmp_path / "other.h5"
    w = Writer(other, _fake_sim(0))
    _write_frames(w, range(2))
    w.close()
    _assert_same_file(path, other)
    with pytest.raises(dpm.ParameterError, match="has 2 complete frame"):
        Writer.resume(path, _fake_sim(0), 3, 0)
    with pytest.raises(dpm.ParameterError, match="3 removal record"):
        Writer.resume(path, _fake_sim(0), 1, 4)
    with pytest.raises(dpm.ParameterError, match="frames=-1"):
        Writer.resume(path, _fake_sim(0), -1, 0)
    with pytest.raises(dpm.ParameterError, match="boundary column"):
        Writer.resume(path, _fake_sim(0, nb=3), 1, 0)
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f["x"] = [1, 2]
    with pytest.raises(dpm.ParameterError, match=f"{str(foreign)!r} is not a dpm run file"):
        Writer.resume(foreign, _fake_sim(0), 0, 0)
    text = tmp_path / "notes.h5"
    text.write_text("not hdf5")
    with pytest.raises(dpm.ParameterError, match="not a dpm run file"):
        Writer.resume(text, _fake_sim(0), 0, 0)
    with pytest.raises(dpm.ParameterError, match="no such file"):
        Writer.resume(tmp_path / "missing.h5", _fake_sim(0), 0, 0)
    assert text.read_text() == "not hdf5"
