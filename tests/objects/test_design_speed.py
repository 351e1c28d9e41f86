"""A law's design speed against the scene's falls (dpm.impact.design_speed).

maw_linear_spring sizes its spring for impact_velocity V: an impact at v overlaps
v sqrt(m*/k_n) (undamped). A scene whose bodies fall further than V allows gets a warning
before the first step that names the parameter, its value, the fall height and speed and
the overlap; the overlap guard's message names the approach speed its overlap needs. The
scene (a meshed floor, spheres from an inlet 1 m above it) uses the law and integrator of
tests/physics/test_mesh_reference.py, so it shares that step module.
"""

import math
import warnings

import numpy as np
import pytest

import dpm
from dpm.errors import UnstableRunError

R = 0.004


def scene(v: float, height: float = 1.0):
    sim = dpm.Simulation(dt=5e-5, gravity=(0.0, 0.0, -9.81), sphere_orientation=False)
    m = dpm.Material("beads", density=2500.0, young=5e6, poisson=0.45)
    sim.contact(m, m, model="maw_linear_spring", restitution=0.7, friction=0.05,
                impact_velocity=v, tangential_stiffness_ratio=1.0)
    sim.add_boundary("mesh", material=m, vertices=[(-0.05, -0.05, 0), (0.05, -0.05, 0),
                                                   (0.05, 0.05, 0), (-0.05, 0.05, 0)],
                     faces=[(0, 1, 2), (0, 2, 3)], side="both")
    sim.add_inlet(dpm.BoxRegion((-0.01, -0.01, height - 0.01), (0.01, 0.01, height)), m,
                  rate=100.0, radius=R, every=0.01, stop=0.01)
    return sim, m


def test_warning_names_the_design_speed_and_the_fall():
    sim, m = scene(1.0)
    with pytest.warns(UserWarning) as got:
        sim.run(steps=1, progress=False)
    text = " ".join(str(w.message) for w in got)
    v_fall = math.sqrt(2 * 9.81 * 1.0)
    assert "impact_velocity=1 m/s" in text and "(1 m: 4.43 m/s)" in text, text
    assert f"{v_fall / 1.0:.2g} times as far" in text
    sim2, _ = scene(5.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim2.run(steps=1, progress=False)  # 5 m/s covers a 1 m fall: no warning


def test_guard_names_the_approach_speed():
    """A sphere falls 1 m onto the floor (4.43 m/s) with a spring sized for 1 m/s: the
    undamped bound of its overlap is 4.43 sqrt(m/k); the guard, set below what it
    reaches, stops the run and its message turns the overlap back into a speed above the
    design speed."""
    sim, m = scene(1.0)
    sim.max_overlap = 0.2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(UnstableRunError) as err:
            sim.run(until=0.6, progress=False)
    msg = str(err.value)
    assert "needs an approach speed of about" in msg and "impact_velocity=1 m/s" in msg
    speed = float(msg.split("needs an approach speed of about ")[1].split(" m/s")[0])
    mass = float(sim.bodies.mass[0])
    kn = sim._contacts[(0, 0)].stiffness(m, m, mass, R, 1.0)
    # the hint's speed is the overlap the guard saw, 0.2-0.3 r, turned into a speed
    assert 0.2 * R / np.sqrt(mass / kn) <= speed <= 4.43
