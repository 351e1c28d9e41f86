"""The run loop as operations with triggers (dpm/operations.py, issue #57): the built-in
events (sort, flow, frames, switches, checkpoints) and the script's own callbacks run at
the steps their triggers give, in the documented order, however the run is split; a
callback changes no result; it is stored by a checkpoint and runs on after a restart.
"""

from __future__ import annotations

import numpy as np
import pytest
from small_scene import small_scene

import dpm

SEEN: list[tuple[int, int]] = []


def record(sim):
    """A script's callback (module level: a checkpoint stores it by name)."""
    frames = sim.last_output.frames if sim.last_output is not None else -1
    SEEN.append((sim.step_count, frames))


def test_periodic_trigger():
    t = dpm.Periodic(100, phase=30)
    assert [t.next(s) for s in (0, 29, 30, 129, 130)] == [30, 30, 130, 130, 230]
    assert t(130) and not t(131)
    for bad in (0, -5, 2.5, True):
        with pytest.raises(dpm.ParameterError, match="period="):
            dpm.Periodic(bad)


def test_callbacks_run_at_their_steps_after_the_frames(tmp_path):
    SEEN.clear()
    sim = small_scene()
    sim.output(tmp_path / "run.h5", every_steps=50)
    cb = sim.operations.add(dpm.Callback(record, every_steps=100))
    for n in (30, 170, 101):  # (split anywhere: the same steps)
        sim.run(steps=n, progress=False)
    sim.close()
    # steps 100, 200, 300; at each the frame of that step was written before (frames
    # 0, 50, ..., so frame k = step / 50 is the (k+1)-th)
    assert SEEN == [(100, 3), (200, 5), (300, 7)]
    sim.operations.remove(cb)
    with pytest.raises(dpm.ParameterError, match="not one the script added"):
        sim.operations.remove(cb)
    names = [type(op).__name__ for op in sim.operations]
    assert names == ["CellSort", "FlowEvents", "Frames", "BoundarySwitches"]


def test_a_callback_changes_no_result():
    plain = small_scene()
    plain.run(steps=250, progress=False)
    watched = small_scene()
    watched.operations.add(dpm.Callback(record, every_steps=7))
    watched.run(steps=250, progress=False)
    np.testing.assert_array_equal(watched.bodies.position, plain.bodies.position)
    np.testing.assert_array_equal(watched.bodies.velocity, plain.bodies.velocity)


def test_a_callback_survives_a_checkpoint(tmp_path):
    SEEN.clear()
    sim = small_scene()
    sim.operations.add(dpm.Callback(record, trigger=dpm.Periodic(40, phase=10)))
    sim.checkpoint_every(tmp_path / "run.ckpt.h5", every_steps=60)
    sim.run(steps=60, progress=False)
    assert [s for s, _ in SEEN] == [10, 50]
    back = dpm.restart(tmp_path / "run.ckpt.h5", output=None)
    back.run(steps=60, progress=False)
    assert [s for s, _ in SEEN] == [10, 50, 90]
    assert [type(op).__name__ for op in back.operations][-2:] == ["Schedule", "Callback"]


def test_bad_operations_are_refused_by_name(tmp_path):
    sim = small_scene()
    with pytest.raises(dpm.ParameterError, match="exactly one of every_steps or trigger"):
        dpm.Callback(record)
    with pytest.raises(dpm.ParameterError, match="not callable"):
        dpm.Callback(5, every_steps=3)
    with pytest.raises(dpm.ParameterError, match="not an operation"):
        sim.operations.add(record)
    cb = sim.operations.add(dpm.Callback(record, every_steps=3))
    with pytest.raises(dpm.ParameterError, match="added already"):
        sim.operations.add(cb)
    sim.operations.add(dpm.Callback(lambda s: None, every_steps=5))
    with pytest.raises(dpm.ParameterError, match="function"):
        sim.checkpoint_every(tmp_path / "c.h5", every_steps=10)


def test_run_settings_are_declared_once():
    """gravity, skin, dt_check, max_overlap, overlap_tolerance: one declaration each
    (Simulation.parameters) checks the constructor's value and every later assignment
    the same way, and converts it (dpm/declared.py)."""
    sim = dpm.Simulation(dt=1e-5)
    for name, bad in (("gravity", (1, 2)), ("skin", -1.0), ("max_overlap", 5.0),
                      ("overlap_tolerance", -1.0)):
        with pytest.raises(dpm.ParameterError) as at_init:
            dpm.Simulation(dt=1e-5, **{name: bad})
        with pytest.raises(dpm.ParameterError) as later:
            setattr(sim, name, bad)
        assert str(later.value).split(": ", 1)[1] == str(at_init.value).split(": ", 1)[1]
    with pytest.raises(dpm.ParameterError, match="allowed: refuse, warn, off"):
        sim.dt_check = "maybe"
    sim.gravity = [0, 0, -9.81]
    assert isinstance(sim.gravity, np.ndarray) and sim.gravity[2] == -9.81
    sim.max_overlap = 1
    assert type(sim.max_overlap) is float
