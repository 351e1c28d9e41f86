"""Analytic cases beside the Chung & Ooi tests (the Hertz impact and the set restitution
are there: CO1-CO3).

* ``sandwich``: a sphere between two planes 2R apart, linear springs k, e = 1, started
  0.15 R off centre at rest: one plane or the other pushes it back with k (x - R), so
  x(t) = R + 0.15 R cos(w t) with w = sqrt(k/m) (DPM thesis, Samiei 2012, eq. 3.56: the
  particle sandwich).
* ``rolling_stop``: a sphere rolling without slip at v0 on a plane under gravity, with the
  constant rolling torque T = mu_r F_n R (Zhou et al. 1999): it decelerates at
  5/7 mu_r g and stops after s = 7 v0^2 / (10 mu_r g).
* ``flip``: a torque-free body with principal moments I = (1, 2, 3) 1e-9 kg m2 spun near
  its intermediate axis flips over and over (Dzhanibekov); the flip times of the body-frame
  spin against Euler's equations I1 w1' = (I2 - I3) w2 w3 (cyclic) solved by scipy
  (DOP853, rtol 1e-12), and the conservation of angular momentum and energy.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba
import numpy as np

from . import Case, Row, compare, register
from .impacts import BIND


def sandwich(quick: bool, models: Sequence[str]) -> list[Row]:
    """Velocity Verlet on the particle sandwich against the harmonic solution."""
    import dpm
    from dpm.impact.measure import bind

    r, rho, k = 4e-3, 2520.0, 250.0  # the thesis' glass bead (Table 3.1)
    mass = 4.0 / 3.0 * math.pi * r**3 * rho
    w = math.sqrt(k / mass)
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


FLIP_MOMENTS = np.array([1.0, 2.0, 3.0]) * 1e-9  # kg m2
FLIP_MASS = 1e-3


def _spinner():
    """One sphere element at the centre with the asymmetric inertia FLIP_MOMENTS (free
    rotation depends on the inertia only)."""
    import dpm
    from dpm.shapes import BodyBatch

    class Spinner(dpm.Shape):
        name = "spinner"

        def build(self, count, density):
            return BodyBatch(np.full(count, FLIP_MASS), np.tile(FLIP_MOMENTS, (count, 1)),
                             np.ones(count, np.int64), np.zeros((count, 3)),
                             np.full(count, 1e-3), np.full(count, 1e-3))

    return Spinner()


def _crossings(t: np.ndarray, w: np.ndarray) -> np.ndarray:
    s = np.sign(w)
    k = np.nonzero(s[1:] != s[:-1])[0]
    return t[k] - w[k] * (t[k + 1] - t[k]) / (w[k + 1] - w[k])


def flip(quick: bool, models: Sequence[str]) -> list[Row]:
    """Intermediate-axis flips of a free asymmetric body against Euler's equations."""
    from scipy.integrate import solve_ivp

    import dpm
    from dpm.measures import to_body as _to_body

    w0 = np.array([0.05, 10.0, 0.05])
    dt, t_end = 1e-4, (6.0 if quick else 12.0)
    sim = dpm.Simulation(dt=dt, integrator="velocity_verlet", dt_check="off")  # no contact
    m = dpm.Material("m", density=1000, young=1e7, poisson=0.3)
    sim.contact(m, m, model="hertz_mindlin")
    sim.add_particles(_spinner(), material=m, positions=[[0, 0, 0]], angular_velocities=[w0])
    e0, l0 = sim.kinetic_energy(), sim.angular_momentum()
    n = round(t_end / dt)
    every = max(1, n // 2000)
    t, wb, energy, lerr = [], [], [], []
    for _ in range(n // every):
        sim.run(steps=every, progress=False)
        wb.append(_to_body(sim.bodies.orientation, sim.bodies.angular_velocity)[0])
        t.append(sim.time)
        energy.append(sim.kinetic_energy() / e0 - 1.0)
        lerr.append(np.linalg.norm(sim.angular_momentum() - l0) / np.linalg.norm(l0))
    t_a, wb_a = np.array(t), np.array(wb)
    i1, i2, i3 = FLIP_MOMENTS

    def rhs(_, w):
        return [(i2 - i3) / i1 * w[1] * w[2], (i3 - i1) / i2 * w[2] * w[0],
                (i1 - i2) / i3 * w[0] * w[1]]

    ref = solve_ivp(rhs, (0, t_a[-1]), w0, t_eval=t_a, rtol=1e-12, atol=1e-14,
                    method="DOP853").y.T
    flips, ref_flips = _crossings(t_a, wb_a[:, 1]), _crossings(t_a, ref[:, 1])
    k = min(len(flips), len(ref_flips))
    src = "Euler's equations (scipy DOP853)"
    period = float(np.diff(flips).mean()) if len(flips) > 1 else math.nan
    ref_period = float(np.diff(ref_flips).mean())
    return [compare("flip", "velocity_verlet", "number of flips", [(len(flips),
                    len(ref_flips))], 0.0, src),
            compare("flip", "velocity_verlet", "time between flips [s]",
                    [(period, ref_period)], 2e-3, src),
            compare("flip", "velocity_verlet", "flip times / that time",
                    list(zip(flips[:k], ref_flips[:k], strict=True)), 1e-2, src,
                    scale=ref_period),
            compare("flip", "velocity_verlet", "largest drift of L, norm(L - L0) / norm(L0)",
                    [(max(lerr), 0.0)], 1e-9, "conservation", scale=1.0),
            compare("flip", "velocity_verlet", "largest drift of E, E / E0 - 1",
                    [(max(abs(x) for x in energy), 0.0)], 1e-4, "conservation", scale=1.0)]


register(Case("sandwich", "particle sandwich: harmonic oscillation between two planes",
              ("linear_spring_dashpot",),
              sandwich))
register(Case("rolling_stop", "rolling sphere stopped by the constant rolling torque",
              ("linear_spring_dashpot",),
              rolling_stop))
register(Case("flip", "intermediate-axis flips of a free asymmetric body", (), flip))
