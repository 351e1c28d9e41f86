"""plugins/dpm-contrib-example, installed for real: discovered after installation and
absent before, its own fast tests pass, and a scene uses all four of its classes by name.

The package is installed with pip into a temporary target (``pip install --no-deps
--target``; its build backend comes from the package index, ~5 s) that is put on sys.path;
where pip cannot build it (no index reachable), its files and the metadata pip would write
(``dist-info`` with ``entry_points.txt`` from its pyproject) are laid out by hand instead.

The scene (slow: one step module for clustered bodies on a plane with the plugin's law,
1-3 minutes cold): five spherocylinders dropped on a plane table that the ``orbit``
motion moves on a circle, ``kelvin_voigt`` contacts. References: the capsule's
closed-form mass; the table's origin and velocity that the hook wrote into the output
equal the orbit's closed form at the frame times (and what the hook recorded); once the
capsules rest on the table they stick to it along their axis and roll across it at
I_x / (I_x + m r^2) of its velocity (angular momentum about the contact line conserved),
and the table carries their weight; the TOML scene file gives the same run bit for bit.
"""

from __future__ import annotations

import importlib
import importlib.metadata as md
import math
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import dpm
from dpm import plugins

ROOT = Path(__file__).resolve().parents[2]
PKG = ROOT / "plugins" / "dpm-contrib-example"
NAMES = (("impact_model", "kelvin_voigt"), ("shape", "spherocylinder"), ("motion", "orbit"))
SOURCE = "dpm-contrib-example:contrib"


def _install(target: Path) -> str:
    """Install the package into ``target``; return how."""
    cmd = [sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--retries", "1",
           "--timeout", "10", "--disable-pip-version-check", "--target", str(target), str(PKG)]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    if r.returncode == 0:
        return "pip"
    _lay_out(target)
    return "by hand (pip: " + (r.stderr.strip().splitlines() or ["?"])[-1] + ")"


def _lay_out(target: Path) -> None:
    """The files and metadata pip would write (where no build backend is reachable)."""
    shutil.copytree(PKG / "dpm_contrib_example", target / "dpm_contrib_example",
                    ignore=shutil.ignore_patterns("__pycache__"))
    meta = tomllib.loads((PKG / "pyproject.toml").read_text())["project"]
    info = target / f"dpm_contrib_example-{meta['version']}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {meta['name']}\n"
                                   f"Version: {meta['version']}\n")
    eps = meta["entry-points"]["dpm"]
    (info / "entry_points.txt").write_text(
        "[dpm]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items()))


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """The registry before installation, then the package installed and the registry
    reloaded; undone afterwards."""
    before = plugins.registry(reload=True)
    absent = {(k, n): n in before.entries[k] for k, n in NAMES}
    target = tmp_path_factory.mktemp("site")
    how = _install(target)
    sys.path.insert(0, str(target))
    importlib.invalidate_caches()
    try:
        yield {"before": absent, "registry": plugins.registry(reload=True), "how": how,
               "target": target}
    finally:
        sys.path.remove(str(target))
        for mod in [m for m in sys.modules if m.startswith("dpm_contrib_example")]:
            del sys.modules[mod]
        importlib.invalidate_caches()
        plugins.registry(reload=True)


def test_discovered_after_installation_absent_before(installed):
    assert not any(installed["before"].values()), installed["before"]
    reg = installed["registry"]
    for kind, name in NAMES:
        assert reg.entries[kind][name].source == SOURCE
        assert reg.entries[kind][name].version == "0.1.0"
    assert not reg.broken and not reg.conflicts
    impl = [p for p in reg.manager.get_plugins() if reg.manager.get_name(p) == SOURCE]
    assert impl and hasattr(impl[0], "dpm_on_output")
    # the dpm plugins listing shows them with their source
    out = subprocess.run([sys.executable, "-m", "dpm.cli", "plugins"], capture_output=True,
                         text=True, timeout=120,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(
                             [str(installed["target"]), os.environ.get("PYTHONPATH", "")])})
    assert out.returncode == 0, out.stderr
    for _, name in NAMES:
        assert name in out.stdout
    assert "dpm-contrib-example" in out.stdout


def test_by_hand_layout_is_what_pip_writes(installed, tmp_path):
    """The fallback layout has pip's package files and entry points."""
    if installed["how"] != "pip":
        pytest.skip(f"installed {installed['how']}")
    _lay_out(tmp_path)
    target = installed["target"]

    def files(root):
        return sorted(str(p.relative_to(root)) for p in (root / "dpm_contrib_example").rglob(
            "*.py"))

    assert files(tmp_path) == files(target)
    for name in files(target):
        assert (tmp_path / name).read_bytes() == (target / name).read_bytes()
    mine = list(md.distributions(path=[str(tmp_path)]))
    pips = list(md.distributions(path=[str(target)]))
    assert [d.metadata["Name"] for d in mine] == [d.metadata["Name"] for d in pips]
    assert [d.version for d in mine] == [d.version for d in pips]
    assert ({(e.group, e.name, e.value) for e in mine[0].entry_points}
            == {(e.group, e.name, e.value) for e in pips[0].entry_points})


def test_blocked_plugin_is_absent(installed, monkeypatch):
    monkeypatch.setenv("DPM_BLOCK_PLUGINS", "dpm-contrib-example")
    try:
        reg = plugins.registry(reload=True)
        assert SOURCE in reg.blocked
        assert all(n not in reg.entries[k] for k, n in NAMES)
    finally:
        monkeypatch.delenv("DPM_BLOCK_PLUGINS")
        plugins.registry(reload=True)


def test_plugin_own_fast_tests_pass(installed):
    """The package's own tests (those that run no simulation) pass against the installed
    package, in a fresh process."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(installed["target"]), os.environ.get("PYTHONPATH", "")])}
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                        "-p", "no:xdist", "-k", "not engine", str(PKG / "tests")],
                       capture_output=True, text=True, timeout=600, cwd=installed["target"],
                       env=env)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    assert " passed" in r.stdout and "failed" not in r.stdout


RADIUS, LENGTH, RHO = 1e-3, 2e-3, 2500.0
ORBIT = {"radius": 2e-3, "frequency": 5.0}
POSITIONS = [[0, y, 1.2e-3] for y in (-6e-3, -3e-3, 0.0, 3e-3, 6e-3)]


def scene(output: Path) -> dpm.Simulation:
    """The scene of examples/orbit_table.toml, in the order the scene loader builds it."""
    sim = dpm.Simulation(dt=1.5e-5, gravity=(0, 0, -9.81))
    m = dpm.Material("grain", density=RHO)
    sim.contact(m, m, model="kelvin_voigt", stiffness=500.0, restitution=0.3, friction=0.5)
    orbit = dpm.registry().lookup("motion", "orbit")(**ORBIT)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1), motion=orbit)
    sim.add_particles("spherocylinder", material=m, radius=RADIUS, length=LENGTH,
                      positions=POSITIONS)
    sim.output(output, every=0.01)
    return sim


@pytest.mark.slow
def test_scene_uses_all_four_by_name(installed, tmp_path, monkeypatch):
    import h5py
    from dpm_contrib_example.recorder import GROUP, recorded

    from dpm.io.scene import load_scene

    sim = scene(tmp_path / "run.h5")
    vol = math.pi * RADIUS**2 * LENGTH + 4 / 3 * math.pi * RADIUS**3
    np.testing.assert_allclose(sim.bodies.mass, RHO * vol, rtol=1e-14)
    sim.run(until=0.2, progress=False)
    sim.close()
    orbit = sim.boundaries[0].motion
    rec = recorded(sim)
    with h5py.File(tmp_path / "run.h5", "r") as f:
        g = f[GROUP]
        data = {k: g[k][:] for k in ("time", "origin", "velocity")}
        frame_times = f["frames/time"][:]
        floor_force = f["boundaries/force"][:, 0]
    assert len(frame_times) == 20  # every 667 steps of 1.5e-5 s
    for k, v in data.items():
        np.testing.assert_array_equal(v, rec[k])  # the file holds what the hook recorded
    np.testing.assert_array_equal(data["time"], frame_times)
    a_omega = ORBIT["radius"] * 2 * math.pi * ORBIT["frequency"]
    # the engine moved the table by the orbit's closed form
    np.testing.assert_allclose(data["origin"][:, 0], orbit.origin(frame_times), rtol=0,
                               atol=1e-9 * ORBIT["radius"])
    np.testing.assert_allclose(data["velocity"][:, 0], orbit.rates(frame_times)[0], rtol=0,
                               atol=1e-9 * a_omega)
    # resting capsules, lying along x, stick to the table along x and roll across it: the
    # friction keeps their angular momentum about the contact line, m v_y - I_x w_x / r,
    # at its value before landing (0), so with no slip v_y = kappa v_table,y, kappa =
    # I_x / (I_x + m r^2) = 0.315, and v_y + r w_x = v_table,y (viscous slip ~0.2 %)
    table_v = orbit.rates(np.array([sim.time]))[0][0]
    v, w = sim.bodies.velocity, sim.bodies.angular_velocity
    m = sim.bodies.mass[0]
    ix = m * (0.5 * LENGTH * RADIUS**2 + 0.4 * 4 / 3 * RADIUS**3) / (LENGTH + 4 / 3 * RADIUS)
    kappa = ix / (ix + m * RADIUS**2)
    assert abs(table_v[1]) > 0.5 * a_omega  # (the test's time: the table moving across)
    np.testing.assert_allclose(v[:, 0], table_v[0], rtol=0, atol=0.01 * a_omega)
    np.testing.assert_allclose(v[:, 1], kappa * table_v[1], rtol=0, atol=0.01 * a_omega)
    np.testing.assert_allclose(v[:, 1] + RADIUS * w[:, 0], table_v[1], rtol=0,
                               atol=0.01 * a_omega)
    assert np.all(np.abs(v[:, 2]) < 1e-3 * a_omega)
    # ... and it carries their weight (last 5 frames)
    weight = float(sim.bodies.mass.sum()) * 9.81
    np.testing.assert_allclose(-floor_force[-5:, 2], weight, rtol=0.01)

    # the same scene from the TOML file: the same run, bit for bit
    monkeypatch.chdir(tmp_path)
    text = (PKG / "examples" / "orbit_table.toml").read_text()
    (tmp_path / "orbit_table.toml").write_text(text)
    toml_sim, run_kw = load_scene(tmp_path / "orbit_table.toml")
    assert run_kw == {"until": 0.2}
    toml_sim.run(**run_kw, progress=False)
    toml_sim.close()
    np.testing.assert_array_equal(toml_sim.bodies.position, sim.bodies.position)
    np.testing.assert_array_equal(toml_sim.bodies.velocity, sim.bodies.velocity)
    with h5py.File(tmp_path / "orbit_table.h5", "r") as f:
        np.testing.assert_array_equal(f[GROUP]["origin"][:], data["origin"])
