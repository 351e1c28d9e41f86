"""The registry: built-ins through entry points, a third-party distribution, broken plugins."""

import importlib
import sys
import textwrap

import numpy as np
import pytest

import dpm
from dpm import plugins
from dpm.cli import main

PLUGIN_SRC = textwrap.dedent('''
    import numpy as np
    import dpm
    from dpm.shapes import BodyBatch

    class Pebble(dpm.Shape):
        """A sphere given by its diameter."""
        name = "pebble"
        parameters = {"diameter": dpm.parameters.Parameter(low=0.0, low_open=True)}

        def build(self, count, density):
            r = np.full(count, self.params["diameter"] / 2)
            m = 4 / 3 * np.pi * r**3 * density
            return BodyBatch(m, np.repeat((0.4 * m * r**2)[:, None], 3, 1),
                             np.ones(count, np.int64), np.zeros((count, 3)), r, r)

    @dpm.hookimpl
    def dpm_register_shapes(register):
        register("pebble", Pebble)

    calls = []

    @dpm.hookimpl
    def dpm_after_step(sim):
        calls.append(sim.step_count)
''')


@pytest.fixture
def fake_distribution(tmp_path, monkeypatch):
    (tmp_path / "fake_dpm_plugin.py").write_text(PLUGIN_SRC)
    info = tmp_path / "fake_dpm_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: fake-dpm-plugin\n"
                                   "Version: 0.1\n")
    (info / "entry_points.txt").write_text("[dpm]\nfake = fake_dpm_plugin\n"
                                           "broken = no_such_module_xyz\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    reg = plugins.registry(reload=True)
    yield reg
    monkeypatch.undo()
    sys.modules.pop("fake_dpm_plugin", None)
    importlib.invalidate_caches()
    plugins.registry(reload=True)


def test_builtins_come_from_the_entry_point():
    reg = plugins.registry()
    for kind, name in [("shape", "sphere"), ("boundary", "plane"), ("boundary", "box"),
                       ("impact_model", "hertz_mindlin"),
                       ("impact_model", "linear_spring_dashpot"),
                       ("integrator", "velocity_verlet"), ("integrator", "symplectic_euler")]:
        assert reg.entries[kind][name].source == "dpm:builtin"


def test_unknown_name_lists_registered():
    with pytest.raises(dpm.UnknownNameError, match=r"unknown integrator 'leapfrogg'.*"
                                                   r"symplectic_euler.*velocity_verlet"):
        dpm.Simulation(dt=1e-5, integrator="leapfrogg")


def test_third_party_distribution_and_broken_plugin(fake_distribution, capsys):
    reg = fake_distribution
    assert reg.entries["shape"]["pebble"].source == "fake-dpm-plugin:fake"
    assert any(src == "fake-dpm-plugin:broken" and "no_such_module_xyz" in why
               for src, why in reg.broken)
    assert "sphere" in reg.entries["shape"]  # the broken one did not stop the others
    main(["plugins"])
    out = capsys.readouterr().out
    assert "pebble" in out and "fake-dpm-plugin:fake" in out
    assert "BROKEN plugin fake-dpm-plugin:broken" in out
    # the plugin's shape and its per-step hook work in a run
    sim = dpm.Simulation(dt=1e-5)
    m = dpm.Material("m", density=1000, young=1e7, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin")
    ids = sim.add_particles("pebble", material=m, diameter=2e-3, positions=[[0, 0, 0]])
    np.testing.assert_allclose(sim.bodies.mass[ids], 4 / 3 * np.pi * 1e-9 * 1000)
    sim.run(steps=3, progress=False)
    assert sys.modules["fake_dpm_plugin"].calls == [1, 2, 3]


def test_runtime_registration_of_a_script_subclass():
    class Bigger(dpm.shapes.Sphere):
        name = "bigger_sphere"

    dpm.register("shape", "bigger_sphere", Bigger)
    assert plugins.registry().lookup("shape", "bigger_sphere") is Bigger
    with pytest.raises(dpm.ParameterError, match="lower_snake_case"):
        dpm.register("shape", "Bad Name", Bigger)
