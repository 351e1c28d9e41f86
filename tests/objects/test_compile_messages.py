"""The compile in plain sight (issue #56): a step module that compiles is announced with
this machine's last compile time as the estimate, a line every few seconds says it is
still compiling, and one line says how long it took (kept for the next estimate)."""

from __future__ import annotations

import time
import types

import dpm.warm as warm


def fake_module(tmp_path, name):
    mod = types.ModuleType(name)
    mod.__file__ = str(tmp_path / f"{name}.py")
    return mod


def test_a_compile_is_announced_reported_and_timed(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DPM_CACHE_DIR", str(tmp_path / "cache"))
    (tmp_path / "cache").mkdir()
    monkeypatch.setattr(warm, "TICK_S", 0.05)
    first = fake_module(tmp_path, "dpm_step_first")
    warm._load_module(first, "this scene's")
    err = capsys.readouterr().err
    assert "compiling this scene's step kernels" in err
    assert "1-4 minutes on a 2-core machine" in err  # (nothing measured here yet)
    with warm.compiling(first):
        time.sleep(0.3)
        warm.mark_ready(first)
    err = capsys.readouterr().err
    assert "dpm: still compiling this scene's step kernels: 0 s" in err
    assert err.strip().splitlines()[-1].startswith(
        "dpm: compiled this scene's step kernels in 0 s")
    with warm.compiling(first):  # (compiled: silent)
        time.sleep(0.15)
    assert capsys.readouterr().err == ""
    second = fake_module(tmp_path, "dpm_step_second")
    warm._load_module(second, "this scene's")
    assert "0 s the last time on this machine" in capsys.readouterr().err


def test_a_failed_compile_stops_the_ticker(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("DPM_CACHE_DIR", str(tmp_path / "cache"))
    (tmp_path / "cache").mkdir()
    monkeypatch.setattr(warm, "TICK_S", 0.05)
    mod = fake_module(tmp_path, "dpm_step_failing")
    warm._load_module(mod, "this scene's")
    try:
        with warm.compiling(mod):
            raise RuntimeError("a typing error")
    except RuntimeError:
        pass
    capsys.readouterr()
    time.sleep(0.2)
    assert capsys.readouterr().err == ""  # (no ticker left behind)
