"""The example third-party package in plugins/ registers through its entry point and runs."""

import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import dpm
from dpm import plugins

PKG = Path(__file__).resolve().parents[2] / "plugins" / "dpm-example-plugin"


@pytest.fixture
def example_installed(tmp_path, monkeypatch):
    """The package on sys.path with its entry point metadata, as pip would install it."""
    info = tmp_path / "dpm_example_plugin-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: dpm-example-plugin\n"
                                   "Version: 0.1.0\n")
    ep = [line for line in (PKG / "pyproject.toml").read_text().splitlines()
          if line.startswith("example =")]
    (info / "entry_points.txt").write_text("[dpm]\n" + ep[0].replace('"', "") + "\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.syspath_prepend(str(PKG))
    importlib.invalidate_caches()
    yield plugins.registry(reload=True)
    monkeypatch.undo()
    for mod in [m for m in sys.modules if m.startswith("dpm_example_plugin")]:
        del sys.modules[mod]
    importlib.invalidate_caches()
    plugins.registry(reload=True)


def test_entry_point_registers_shape_and_model(example_installed):
    reg = example_installed
    assert reg.entries["shape"]["dimer"].source == "dpm-example-plugin:example"
    assert reg.entries["impact_model"]["linear_viscous"].source == "dpm-example-plugin:example"


def test_dimer_mass_and_resting_on_both_spheres(example_installed):
    r, s, rho = 1e-3, 1.2e-3, 2500.0
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -9.81))
    m = dpm.Material("m", density=rho)
    sim.contact(m, m, model="linear_viscous", stiffness=500.0, restitution=0.3, friction=0.5)
    floor = sim.add_boundary("plane", material=m)
    sim.add_particles("dimer", material=m, radius=r, separation=s, positions=[[0, 0, 1.3e-3]])
    lens = math.pi * (4 * r + s) * (2 * r - s) ** 2 / 12  # volume the two spheres share
    volume = 2 * 4 / 3 * math.pi * r**3 - lens
    assert sim.bodies.mass[0] == pytest.approx(volume * rho, rel=1e-5)
    sim.run(until=0.05, progress=False)
    weight = sim.bodies.mass[0] * 9.81
    np.testing.assert_allclose(floor.force, [0, 0, -weight], atol=1e-6 * weight)
    assert int(sim.backend.diag[6]) == 2


def test_linear_viscous_restitution_and_sliding_friction(example_installed):
    r, rho, k, e, mu = 1e-3, 2500.0, 500.0, 0.5, 0.3
    mat = dpm.Material("m", density=rho)
    sim = dpm.Simulation(dt=1e-6)
    sim.contact(mat, mat, model="linear_viscous", stiffness=k, restitution=e, friction=mu,
                tangential_damping_ratio=50.0)  # sliding all through the contact
    sim.add_boundary("plane", material=mat)
    v = np.array([0.2, 0.0, -0.1])
    sim.add_particles("sphere", material=mat, radius=r, positions=[[0, 0, r]], velocities=[v])
    sim.run(until=0.01, progress=False)
    out = sim.bodies.velocity[0]
    assert out[2] == pytest.approx(e * 0.1, rel=2e-3)  # the set restitution
    # Coulomb sliding: the tangential impulse is mu times the normal impulse
    m = sim.bodies.mass[0]
    normal_impulse = m * (out[2] + 0.1)
    assert m * (v[0] - out[0]) == pytest.approx(mu * normal_impulse, rel=2e-3)
