"""The universal step module (dpm/universal_step.py) and the choice of step module
(dpm/warm.py): a scene gives the same results bit for bit on the universal module as on
its own; "auto" takes its own when compiled, else the universal one (and hands its own to
a background compile); the pair table repacked into the universal layout."""

from __future__ import annotations

import os
import subprocess
import sys
import types
from pathlib import Path

import backend_contract as bc  # tests/backend_contract.py (tests/conftest.py)
import numpy as np
import pytest

import dpm
from dpm import universal_step, warm
from dpm.backends.cpu import CpuBackend
from dpm.errors import ParameterError


def mixed_laws(backend: dict) -> tuple[dpm.Simulation, int]:
    """Three materials, four laws of different parts (Hertz-Mindlin with the EPSD rolling
    spring, Walton-Braun, linear with constant rolling torque, Maw): spheres and
    ellipsoids in a box with a sieve."""
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -9.81), **backend)
    a = dpm.Material("a", density=2500.0, young=5e6, poisson=0.45)
    b = dpm.Material("b", density=2000.0, young=4e6, poisson=0.3)
    s = dpm.Material("s", density=7800.0, young=2e7, poisson=0.3)
    sim.contact(a, a, model="hertz_mindlin", restitution=0.5, friction=0.5,
                rolling_friction=0.05, rolling_model="epsd")
    sim.contact(a, b, model="walton_braun", stiffness=2e3, restitution=0.6, friction=0.4)
    sim.contact(b, b, model="linear_spring_dashpot", stiffness=2e3, restitution=0.7,
                friction=0.3, rolling_friction=0.02)
    sim.contact(a, s, model="maw_linear_spring", restitution=0.5, friction=0.3)
    sim.contact(b, s, model="hertz_mindlin", restitution=0.4, friction=0.6)
    sim.add_boundary("box", material=s, lower=(0, 0, 0), upper=(0.02, 0.02, 0.02))
    sim.add_boundary("sieve", material=s, center=(0.01, 0.01, 0.008), normal=(0, 0, 1),
                     u=(1, 0, 0), half_extents=(0.009, 0.009), thickness=1e-3, hole=3e-3,
                     bar=2e-3)
    rng = np.random.default_rng(3)
    xyz = dpm.lattice((0.002, 0.002, 0.01), (0.018, 0.018, 0.016), 2.6e-3, jitter=5e-5,
                      seed=4)
    v = rng.uniform(-0.3, 0.3, xyz.shape)
    w = rng.uniform(-40, 40, xyz.shape)
    sim.add_particles("sphere", material=a, positions=xyz[0::3], velocities=v[0::3],
                      angular_velocities=w[0::3], radius=1.1e-3)
    sim.add_particles("sphere", material=b, positions=xyz[1::3], velocities=v[1::3],
                      angular_velocities=w[1::3], radius=1e-3)
    sim.add_particles("ellipsoid", material=a, positions=xyz[2::3], velocities=v[2::3],
                      angular_velocities=w[2::3], a=1.2e-3, b=0.7e-3,
                      orientations=rng.normal(size=(len(xyz[2::3]), 4)))
    return sim, 300


SCENES = {"mixed_laws": mixed_laws, **bc.SCENES}


def end_state(name: str, kernels: str) -> tuple[dict, CpuBackend]:
    backend = CpuBackend(threads=1, kernels=kernels)
    sim, steps = SCENES[name]({"device": backend})
    sim.run(steps=steps, progress=False)
    order = np.argsort(sim.bodies.id)
    out = {f: getattr(sim.bodies, f)[order].copy() for f in
           ("position", "velocity", "angular_velocity", "orientation")}
    out["load"] = sim.walls.load.copy()
    out["contacts"] = np.array([sim.contact_count()])
    return out, backend


@pytest.mark.parametrize("name", list(SCENES))
def test_universal_module_gives_the_same_bits(name):
    """Every part function is called with the same arguments in the universal law as in
    the specialised one, and every boundary kind through the same geometry: the end
    states are equal bit for bit (laws, rolling parts, clusters, meshes, sieves, tubes,
    bends, periodic axes, inlets and outlets)."""
    own, be_own = end_state(name, "scene")
    uni, be_uni = end_state(name, "universal")
    assert not be_own.universal and be_uni.universal
    assert be_uni.module.__name__.startswith("dpm_universal_")
    for field, value in own.items():
        assert np.array_equal(value, uni[field]), field
    assert np.abs(own["velocity"]).max() > 0  # (something moved)


def test_universal_table_layout():
    """The repacked row of each material pair: the part codes, the history offsets of the
    scene's layout, and each part's constants (by slot name) in its region."""
    sim, _ = mixed_laws({"device": CpuBackend(threads=1, kernels="scene")})
    sim.run(steps=1, progress=False)
    plan = sim.plan
    table = universal_step.universal_tables(plan.laws, plan.pair_model, plan.pair_params)
    parts, reg = universal_step.builtin_parts(), universal_step.regions()
    assert table.shape[2] == universal_step.WIDTH
    seen = set()
    nm = plan.pair_model.shape[0]
    for i in range(nm):
        for j in range(nm):
            law = plan.laws[plan.pair_model[i, j]]
            row, mine = table[i, j], plan.pair_params[i, j]
            by_kind = {p.kind: p for p in law.parts}
            for c, kind in enumerate(universal_step.KINDS):
                code = int(row[c])
                part = parts[kind][code]
                assert (part is None) == (kind not in by_kind)
                if part is not None:
                    assert part.key() == by_kind[kind].key()
                    for k, slot in enumerate(part.slots):
                        assert row[reg[kind] + k] == mine[law.layout.slots[slot]]
            for c, kind in enumerate(("rolling", "normal", "adhesion")):
                assert row[4 + c] == law.layout.offset.get(kind, 0)
            seen.add(tuple(row[:4]))
    assert len(seen) >= 4  # the five contacts give at least four distinct compositions


def test_quiet_holds_back_the_messages_inside_its_block_only(capsys):
    """``dpm compile``'s throwaway scenes run inside :func:`dpm.warm.quiet`: no compile
    message there, the next one outside is said, and the process's environment is left
    as it was."""
    env = dict(os.environ)
    module = types.ModuleType("dpm_quiet_probe")
    warm._ANNOUNCED.discard(module.__name__)
    with warm.quiet():
        with warm.quiet():
            assert warm._quiet()
        assert warm._quiet()
        warm._announce(module, "held back")
    assert not warm._quiet()
    assert capsys.readouterr().err == ""
    warm._announce(module, "said")
    assert capsys.readouterr().err == "dpm: said\n"
    assert dict(os.environ) == env


def test_auto_takes_the_own_module_when_compiled_else_the_universal(monkeypatch, capsys):
    """"auto": the scene's own module when marked compiled; else the universal one, with
    a message, and the scene's own handed to a background compile, which marks it
    compiled for the next run."""
    end_state("mixed_laws", "scene")  # both compiled (the test above may have run)
    end_state("mixed_laws", "universal")
    assert not warm._quiet()  # (dpm compile's quiet block ended with it)
    monkeypatch.setenv("DPM_BACKGROUND_COMPILE", "1")
    launched = []

    def popen(cmd, **kw):
        launched.append(cmd)
        return types.SimpleNamespace(pid=os.getpid())  # (a living process)

    monkeypatch.setattr(subprocess, "Popen", popen)
    _, be = end_state("mixed_laws", "auto")
    assert not be.universal and not launched
    marker = Path(be.module.__file__).with_suffix(".ready")
    marker.unlink()
    warm._ANNOUNCED.clear()
    _, be = end_state("mixed_laws", "auto")
    assert be.universal
    assert "universal step kernels" in capsys.readouterr().err
    assert len(launched) == 1
    job, busy = launched[0][-2:]
    assert Path(job).exists() and Path(busy).read_text() == str(os.getpid())
    # another scene of the same kind while that compile runs starts none of its own
    _, be = end_state("mixed_laws", "auto")
    assert be.universal and len(launched) == 1
    assert warm.main([job, busy]) == 0  # (what the detached process runs)
    assert marker.exists() and not Path(job).exists() and not Path(busy).exists()
    _, be = end_state("mixed_laws", "auto")
    assert not be.universal


def test_kernels_choice_is_checked(monkeypatch):
    with pytest.raises(ParameterError, match=r"kernels='fast'; allowed: auto, scene, "):
        CpuBackend(kernels="fast")
    monkeypatch.setenv("DPM_KERNELS", "nope")
    with pytest.raises(ParameterError, match="DPM_KERNELS='nope'"):
        CpuBackend()


def test_dpm_compile_names_the_integrators():
    r = subprocess.run([sys.executable, "-m", "dpm.cli", "compile", "--integrator", "rk4"],
                       capture_output=True, text=True)
    assert r.returncode != 0
    assert "integrator 'rk4'; allowed:" in r.stderr + r.stdout
    assert "velocity_verlet" in r.stderr + r.stdout
    assert "backward_euler" not in warm.integrator_modules()  # (implicit: no own module)


def test_a_compile_marker_of_a_dead_process_is_taken_over(tmp_path):
    """The compile-in-progress marker: held while its process lives; a killed compile's
    marker (its process gone) does not block the next one."""
    busy = tmp_path / "m.compiling"
    assert warm._claim(busy)
    busy.write_text(str(os.getpid()))
    assert not warm._claim(busy)  # a living holder
    done = subprocess.Popen([sys.executable, "-c", "pass"])
    done.wait()
    busy.write_text(str(done.pid))
    assert warm._claim(busy)  # a dead one
