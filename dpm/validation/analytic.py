"""Analytic cases beside the Chung & Ooi tests (the Hertz impact and the set restitution
are there: CO1-CO3).

* ``sandwich``: a sphere between two planes 2R apart, linear springs k, e = 1, started
  0.15 R off centre at rest: both contacts act at once, x(t) = R + 0.15 R cos(w t) with
  w = sqrt(2k/m) (DPM thesis, Samiei 2012, eq. 3.56: the particle sandwich).
* ``rolling_stop``: a sphere rolling without slip at v0 on a plane under gravity, with the
  constant rolling torque T = mu_r F_n R (Zhou et al. 1999): it decelerates at
  5/7 mu_r g and stops after s = 7 v0^2 / (10 mu_r g).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba

from . import Case, Row, compare, register
from .impacts import BIND


def sandwich(quick: bool, models: Sequence[str]) -> list[Row]:
    """Velocity Verlet on the particle sandwich against the harmonic solution."""
    import dpm
    from dpm.impact.measure import bind

    r, rho, k = 4e-3, 2520.0, 250.0  # the thesis' glass bead (Table 3.1)
    mass = 4.0 / 3.0 * math.pi * r**3 * rho
    w = math.sqrt(2.0 * k / mass)
    period = 2.0 * math.pi / w
    dt = period / (100 if quick else 400)
    sim = dpm.Simulation(dt=dt, gravity=(0.0, 0.0, 0.0), dt_check="off",
                         overlap_tolerance=0.2, max_overlap=2.0)
    bind(sim, BIND)
    m = dpm.Material("glass", density=rho)
    sim.contact(m, m, model="linear_spring_dashpot", stiffness=k, restitution=1.0,
                friction=0.0)
    sim.add_boundary("plane", material=m, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_boundary("plane", material=m, point=(0, 0, 2 * r), normal=(0, 0, -1))
    sim.add_particles("sphere", material=m, radius=r, positions=[[0, 0, 1.15 * r]])
    n = int(round((2 if quick else 5) * period / dt))
    points = []
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        while sim.step_count < n:
            sim.run(steps=min(max(1, n // 200), n - sim.step_count), progress=False)
            exact = r + 0.15 * r * math.cos(w * sim.time)
            points.append((float(sim.bodies.position[0, 2]), exact))
    finally:
        numba.set_num_threads(threads)
    # velocity Verlet's frequency is w (1 + (w dt)^2 / 24): after N periods the phase, so
    # the position in amplitudes, is off by 2 pi N (w dt)^2 / 24; twice that passes
    tol = 2.0 * 2.0 * math.pi * (n * dt / period) * (w * dt) ** 2 / 24.0
    return [compare("sandwich", "linear_spring_dashpot", "position / (0.15 R amplitude)",
                    points, max(tol, 1e-3), "harmonic x = R + 0.15 R cos(w t) (thesis "
                    "eq. 3.56)", scale=0.15 * r)]


def rolling_stop(quick: bool, models: Sequence[str]) -> list[Row]:
    """A rolling sphere stops at 7 v0^2 / (10 mu_r g) under the constant rolling torque."""
    import dpm
    from dpm.impact.measure import bind

    r, rho, young, nu = 1e-3, 2500.0, 1e7, 0.3
    mu_r, v0, g = 0.05, 0.05, 9.81
    s_ref = 7.0 * v0**2 / (10.0 * mu_r * g)
    t_ref = 7.0 * v0 / (5.0 * mu_r * g)
    sim = dpm.Simulation(dt=4e-6, gravity=(0.0, 0.0, -g), dt_check="off")
    bind(sim, BIND)
    mat = dpm.Material("m", density=rho, young=young, poisson=nu)
    kn = 1e4
    sim.contact(mat, mat, model="linear_spring_dashpot", stiffness=kn, restitution=0.3,
                friction=0.8, rolling_friction=mu_r, rolling_model="constant_torque")
    sim.add_boundary("plane", material=mat, point=(0, 0, 0), normal=(0, 0, 1))
    mass = 4.0 / 3.0 * math.pi * r**3 * rho
    d0 = mass * g / kn  # resting overlap
    sim.add_particles("sphere", material=mat, radius=r, positions=[[0, 0, r - d0]],
                      velocities=[[v0, 0, 0]], angular_velocities=[[0, v0 / r, 0]])
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        sim.run(until=0.5 * t_ref, progress=False)
        half = float(sim.bodies.velocity[0, 0])
        sim.run(until=1.3 * t_ref, progress=False)
    finally:
        numba.set_num_threads(threads)
    src = "constant rolling torque: a = 5/7 mu_r g, s = 7 v0^2/(10 mu_r g)"
    return [compare("rolling stop", "linear_spring_dashpot + constant_torque",
                    "speed at t_stop/2 [m/s]", [(half, 0.5 * v0)], 1e-2, src),
            compare("rolling stop", "linear_spring_dashpot + constant_torque",
                    "stop distance [m]", [(float(sim.bodies.position[0, 0]), s_ref)], 5e-3,
                    src)]


register(Case("sandwich", "particle sandwich: harmonic oscillation between two planes",
              ("linear_spring_dashpot",),
              sandwich))
register(Case("rolling_stop", "rolling sphere stopped by the constant rolling torque",
              ("linear_spring_dashpot",),
              rolling_stop))
