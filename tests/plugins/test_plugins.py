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


def _fake_dist(root, dist, module, source):
    """A distribution ``dist`` with module ``module`` (``source``) and entry point."""
    (root / f"{module}.py").write_text(source)
    info = root / f"{module}-0.2.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.2\n")
    (info / "entry_points.txt").write_text(f"[dpm]\n{module} = {module}\n")


RIVAL_SRC = textwrap.dedent('''
    import dpm

    class Pebble(dpm.shapes.Sphere):
        """Another pebble."""

    class Trouble:
        @dpm.hookimpl
        def dpm_after_step(self, sim):
            if sim.step_count == 2:
                raise ZeroDivisionError("no room left")

    @dpm.hookimpl
    def dpm_register_shapes(register):
        register("pebble", Pebble)
        register("rival_only", Pebble)
''')


@pytest.fixture
def two_pebbles(fake_distribution, tmp_path, monkeypatch):
    """fake-dpm-plugin and rival-dpm-plugin both register the shape 'pebble'."""
    _fake_dist(tmp_path, "rival-dpm-plugin", "rival_dpm_plugin", RIVAL_SRC)
    importlib.invalidate_caches()
    yield plugins.registry(reload=True)
    sys.modules.pop("rival_dpm_plugin", None)


def test_two_plugins_registering_one_name_is_a_conflict_naming_both(two_pebbles, capsys):
    reg = two_pebbles
    with pytest.raises(plugins.PluginConflictError) as err:
        reg.lookup("shape", "pebble", "sim.add_particles()")
    msg = str(err.value)
    assert "shape 'pebble' is registered by fake-dpm-plugin" in msg
    assert "and by rival-dpm-plugin" in msg and "DPM_BLOCK_PLUGINS=" in msg
    assert reg.lookup("shape", "rival_only") is not None  # its other names work
    main(["plugins"])
    assert "CONFLICT shape 'pebble': registered by fake-dpm-plugin:fake and by " \
           "rival-dpm-plugin:rival_dpm_plugin" in capsys.readouterr().out


def test_a_blocked_plugin_is_not_loaded(two_pebbles, monkeypatch, capsys):
    monkeypatch.setenv("DPM_BLOCK_PLUGINS", "rival-dpm-plugin, no-such-plugin")
    reg = plugins.registry(reload=True)
    assert reg.entries["shape"]["pebble"].source == "fake-dpm-plugin:fake"
    assert "rival_only" not in reg.entries["shape"]
    assert reg.blocked == ["rival-dpm-plugin:rival_dpm_plugin"]
    reg.lookup("shape", "pebble")  # no conflict once one is blocked
    main(["plugins"])
    assert "BLOCKED plugin rival-dpm-plugin:rival_dpm_plugin" in capsys.readouterr().out
    monkeypatch.setenv("DPM_BLOCK_PLUGINS", "builtin,dpm")  # the built-ins stay
    assert "sphere" in plugins.registry(reload=True).entries["shape"]


def test_a_hook_that_raises_stops_the_run_naming_the_plugin(tmp_path):
    sim = dpm.Simulation(dt=1e-5)
    m = dpm.Material("m", density=1000, young=1e7, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin")
    sim.add_particles("sphere", material=m, radius=1e-3, positions=[[0, 0, 0]])
    sim.output(tmp_path / "hook.h5", every_steps=1)
    ns = {}
    exec(RIVAL_SRC, ns)
    trouble = ns["Trouble"]()
    sim._registry.manager.register(trouble, name="trouble-plugin")
    try:
        with pytest.raises(plugins.PluginError, match=r"plugin trouble-plugin: its "
                           r"dpm_after_step hook raised ZeroDivisionError: no room left"):
            sim.run(steps=5, progress=False)
    finally:
        sim._registry.manager.unregister(trouble)
    assert sim.step_count == 2
    assert len(dpm.load(tmp_path / "hook.h5").times) == 2  # frames 0, 1 stay readable


def test_plugins_lists_every_kind_with_a_clean_summary_and_version(capsys):
    main(["plugins"])
    out = capsys.readouterr().out
    lines = {tuple(line.split()[:2]): line for line in out.splitlines()[1:]}
    for kind, name in [("motion", "rotation"), ("motion", "tumbling"), ("region", "box"),
                       ("region", "cylinder"), ("rolling_model", "epsd"),
                       ("rolling_model", "constant_torque"), ("backend", "mpi")]:
        assert (kind, name) in lines, (kind, name)
        assert f" {dpm.__version__} " in lines[(kind, name)]
    assert "``" not in out and ":class:" not in out
    # whole first sentences: "eq. 2.53" does not end one
    assert "(DPM thesis eq. 2.53 with the unit vector; Zhou et al. 1999)." in \
        lines[("rolling_model", "constant_torque")]
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.strip() == f"dpm {dpm.__version__}"
