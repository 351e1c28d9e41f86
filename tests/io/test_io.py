"""HDF5 output: layout, round trip, a killed run keeps its frames, XDMF sidecar."""

import os
import signal
import subprocess
import sys
import textwrap
import time
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

import dpm


def _small_sim(dt=1e-5):
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, -9.81))
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("box", material=m, lower=(0, 0, 0), upper=(0.01, 0.01, 0.02), open="+z")
    xyz = dpm.lattice((0, 0, 0), (0.01, 0.01, 0.01), 2.2e-3, jitter=5e-5)
    sim.add_particles("sphere", material=m, radius=1e-3, positions=xyz,
                      velocities=np.full((len(xyz), 3), 0.01))
    return sim


def test_round_trip_and_layout(tmp_path):
    sim = _small_sim()
    path = tmp_path / "run.h5"
    sim.output(str(path), every_steps=50)
    x0 = sim.bodies.position.copy()
    sim.run(steps=200, progress=False)
    sim.close()
    run = dpm.load(path)
    assert run.n_frames == 5
    np.testing.assert_allclose(run.times, np.arange(5) * 50 * 1e-5, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(run.steps, [0, 50, 100, 150, 200])
    first, last = run.frame(0), run.frame(-1)
    np.testing.assert_array_equal(first["position"], x0)
    np.testing.assert_array_equal(last["position"], sim.bodies.position)
    np.testing.assert_array_equal(last["velocity"], sim.bodies.velocity)
    np.testing.assert_array_equal(last["angular_velocity"], sim.bodies.angular_velocity)
    np.testing.assert_array_equal(last["orientation"], sim.bodies.orientation)
    np.testing.assert_array_equal(last["id"], sim.bodies.id)
    assert len(run.field("position")) == 5
    np.testing.assert_allclose(run.boundary_force[-1, 0], sim.boundaries[0].force)
    with h5py.File(path, "r") as f:  # the documented layout (docs/output-format.md)
        assert f.attrs["format"] == "dpm-hdf5"
        assert f.attrs["format_version"] == 1
        assert f["particles/position"].maxshape == (None, 3)
        assert f["particles/position"].chunks is not None
        for name in ("time", "step", "start", "count"):
            assert len(f["frames"][name]) == 5


def test_xdmf_references_existing_data(tmp_path):
    sim = _small_sim()
    path = tmp_path / "run.h5"
    sim.output(str(path), every_steps=100)
    sim.run(steps=200, progress=False)
    sim.close()
    root = ET.parse(path.with_suffix(".xdmf")).getroot()
    grids = root.findall(".//Grid[@GridType='Uniform']")
    assert len(grids) == 3
    with h5py.File(path, "r") as f:
        for item in root.iter("DataItem"):
            if item.get("Format") == "HDF":
                fname, ds = item.text.split(":")
                assert fname == path.name
                rows = int(item.get("Dimensions").split()[0])
                assert f[ds].shape[0] == rows
    times = [float(g.find("Time").get("Value")) for g in grids]
    np.testing.assert_allclose(times, [0, 1e-3, 2e-3])


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_killed_run_keeps_written_frames(tmp_path):
    path = tmp_path / "killed.h5"
    script = textwrap.dedent(f"""
        import sys; sys.path.insert(0, {str(os.path.dirname(__file__))!r})
        from test_io import _small_sim
        sim = _small_sim()
        sim.output({str(path)!r}, every_steps=5)
        sim.run(steps=10_000_000, progress=False)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script])
    try:
        deadline = time.time() + 120
        frames = 0
        while time.time() < deadline and frames < 20:
            time.sleep(0.2)
            if path.exists():
                try:
                    frames = dpm.load(path).n_frames
                except Exception:
                    frames = 0
        assert frames >= 20, "the writer never got going"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    run = dpm.load(path)
    assert run.n_frames >= 20
    for k in (0, run.n_frames // 2, run.n_frames - 1):
        fr = run.frame(k)
        assert np.all(np.isfinite(fr["position"])) and len(fr["position"]) == run.count[k]
    np.testing.assert_array_equal(np.diff(run.steps), 5)


def test_unstable_run_keeps_frames_and_says_why(tmp_path):
    sim = dpm.Simulation(dt=2e-4, gravity=(0, 0, -9.81), dt_check="off")
    m = dpm.Material("soft", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="linear_spring_dashpot", stiffness=1e7, restitution=0.9)
    sim.add_boundary("plane", material=m)
    sim.add_particles("sphere", material=m, radius=1e-3, positions=[[0, 0, 1.5e-3]],
                      velocities=[[0, 0, -2.0]])
    path = tmp_path / "unstable.h5"
    sim.output(str(path), every_steps=1)
    with pytest.raises(dpm.UnstableRunError, match="dt = 0.0002 s") as err:
        sim.run(steps=100, progress=False)
    assert "stay readable" in str(err.value)
    run = dpm.load(path)
    assert run.n_frames >= 1
    assert np.all(np.isfinite(run.frame(-1)["position"]))


def test_clustered_bodies_write_their_elements(tmp_path):
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -9.81))
    m = dpm.Material("glass", density=2500, young=5e6, poisson=0.45)
    sim.contact(m, m, model="hertz_mindlin", restitution=0.3, friction=0.5)
    sim.add_boundary("plane", material=m)
    sim.add_particles("cylinder", material=m, r=1e-3, l=3e-3, resolution=0.1,
                      positions=[[0, 0, 2e-3], [5e-3, 0, 2e-3]])
    path = tmp_path / "clusters.h5"
    sim.output(str(path), every_steps=100)
    sim.run(steps=200, progress=False)
    sim.close()
    run = dpm.load(path)
    el = run.elements(-1)
    np.testing.assert_array_equal(el["position"], sim.elements.position)
    np.testing.assert_array_equal(el["radius"], sim.elements.radius)
    assert set(el["body_id"]) == {0, 1} and len(el["radius"]) == len(sim.elements)
    # each element sits at its body's pose: x = X + R(q) offset
    b = sim.bodies
    owner = sim.elements.owner
    world = dpm.measures.to_body(b.orientation[owner] * [1, -1, -1, -1],
                                    sim.elements.offset)
    np.testing.assert_allclose(el["position"], b.position[owner] + world, atol=1e-15)
    root = ET.parse(path.with_suffix(".elements.xdmf")).getroot()
    assert len(root.findall(".//Grid[@GridType='Uniform']")) == 3
    assert "/elements/position" in ET.tostring(root, encoding="unicode")
