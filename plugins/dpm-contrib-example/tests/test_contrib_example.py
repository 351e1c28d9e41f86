"""The contributed classes against dpm.testing's contracts and closed forms.

Run with the package installed (``pip install -e plugins/dpm-contrib-example``): the
classes are looked up by their registered names. Tests whose name contains ``engine``
run simulations (a step module to compile for each scene type, 1-3 minutes cold).
"""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pytest
from dpm_contrib_example.models import damping_ratio
from dpm_contrib_example.motions import Orbit
from dpm_contrib_example.recorder import GROUP, recorded

import dpm
import dpm.testing
from dpm.motion import Motion

HERE = Path(__file__).resolve().parent
SCENE = HERE.parent / "examples" / "orbit_table.toml"


def test_registered_by_the_entry_point():
    reg = dpm.registry()
    for kind, name in (("impact_model", "kelvin_voigt"), ("shape", "spherocylinder"),
                       ("motion", "orbit")):
        assert reg.entries[kind][name].source == "dpm-contrib-example:contrib"


class TestKelvinVoigt(dpm.testing.ImpactModelContract):
    model = "kelvin_voigt"
    params = {"stiffness": 500.0, "restitution": 0.6, "friction": 0.4}
    restitution_tolerance = 0.01


def test_damping_ratio_closed_form():
    """e = exp(-pi zeta / sqrt(1 - zeta^2)) inverted."""
    for e in (0.1, 0.5, 0.9, 1.0):
        z = damping_ratio(e)
        assert math.exp(-math.pi * z / math.sqrt(1 - z * z)) == pytest.approx(e, rel=1e-13)


R, L = 1e-3, 3e-3


class TestSpherocylinder(dpm.testing.ShapeContract):
    shape = "spherocylinder"
    params = {"radius": R, "length": L}
    density = 2500.0

    def inside(self, p):  # the capsule: within R of the axis segment
        t = np.clip(p[:, 0], -L / 2, L / 2)
        return np.linalg.norm(p - np.column_stack([t, 0 * t, 0 * t]), axis=1) <= R

    def bounds(self):
        return -np.array([L / 2 + R, R, R]), np.array([L / 2 + R, R, R])


def test_spherocylinder_limits():
    """No cylinder: a sphere (mass 4/3 pi r^3 rho, inertia 2/5 m r^2); elements cover the
    axis at the spacing asked."""
    b = dpm.registry().lookup("shape", "spherocylinder")(radius=R, length=0.0).build(1, 1.0)
    m = 4 / 3 * math.pi * R**3
    assert b.mass[0] == pytest.approx(m, rel=1e-14)
    np.testing.assert_allclose(b.inertia[0], 0.4 * m * R * R, rtol=1e-14)
    s = dpm.registry().lookup("shape", "spherocylinder")(radius=R, length=L, spacing=0.25)
    x = s.centres()[:, 0]
    assert x[0] == -L / 2 and x[-1] == L / 2 and np.max(np.diff(x)) <= 0.25 * R * (1 + 1e-12)


def test_orbit_closed_form():
    """|o(t) - centre| = a about the centre -a u; closed-form rates = central differences
    of the pose (dpm.Motion's default)."""
    m = Orbit(radius=2e-3, frequency=5.0, axis=(0, 1, 1), start=(1, 0, 0))
    t = np.linspace(0, 0.3, 31)
    r, o = m.pose(t)
    np.testing.assert_array_equal(r, np.broadcast_to(np.eye(3), r.shape))
    np.testing.assert_allclose(np.linalg.norm(o + 2e-3 * m.u, axis=1), 2e-3, rtol=1e-13)
    assert np.allclose(o @ np.array([0, 1, 1]), 0.0, atol=1e-18)
    v, w = m.rates(t)
    vd, wd = Motion.rates(m, t)
    np.testing.assert_allclose(v, vd, atol=1e-8 * np.abs(v).max())
    np.testing.assert_allclose(w, wd, atol=1e-8)
    with pytest.raises(dpm.ParameterError, match="parallel"):
        Orbit(radius=1e-3, frequency=1.0, axis=(0, 0, 1), start=(0, 0, 2))


def test_engine_scene_file_uses_all_four(tmp_path, monkeypatch):
    """The example scene by name: the hook's dataset in the file is what it recorded, and
    the table's origin there is the orbit's closed form at the frame times."""
    from dpm.io.scene import load_scene

    monkeypatch.chdir(tmp_path)
    sim, run_kw = load_scene(SCENE)
    sim.run(until=0.05, progress=False)
    sim.close()
    rec = recorded(sim)
    with h5py.File(tmp_path / "orbit_table.h5", "r") as f:
        g = f[GROUP]
        np.testing.assert_array_equal(g["origin"][:], rec["origin"])
        np.testing.assert_array_equal(g["time"][:], rec["time"])
        times = f["frames/time"][:]
    np.testing.assert_array_equal(rec["time"], times)
    orbit = sim.boundaries[0].motion
    np.testing.assert_allclose(rec["origin"][:, 0], orbit.origin(rec["time"]), rtol=0,
                               atol=1e-12)
    np.testing.assert_allclose(rec["velocity"][:, 0], orbit.rates(rec["time"])[0], rtol=0,
                               atol=1e-12)
