"""JKR adhesion against the JKR relations (Johnson, Kendall & Roberts 1971):

    d(a) = a^2/R* - sqrt(2 pi W a/E*),   F(a) = 4 E* a^3/(3 R*) - sqrt(8 pi W E* a^3)

* ``jkr_pull_off``: a sphere resting on a wall, pulled by a body force that grows in
  0.25 % steps of F_c = 3/2 pi W R* (each held 8 ms): the first pull under which it
  leaves, against F_c; and its rest overlap without load, a_0^2/(3 R*).
* ``jkr_sticking``: two spheres meeting head-on (elastic, e = 1): the energy the neck
  takes, E_loss = -int_{d_c}^{0} F dd (quadrature of the parametric curve), gives the
  critical speed v_c = sqrt(2 E_loss/m*); below it the pair stays stuck, above it parts
  at sqrt(v^2 - v_c^2) (Thornton & Ning 1998's energy balance).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba
from scipy.integrate import quad

from . import Case, Row, compare, register

R, RHO, YOUNG, NU, W = 1e-3, 2500.0, 1e7, 0.3, 0.1
ESTAR = YOUNG / (2.0 * (1.0 - NU**2))
MASS = 4.0 / 3.0 * math.pi * R**3 * RHO
SOURCE = "JKR relations (Johnson, Kendall & Roberts 1971)"


def _curve(a: float, reff: float) -> tuple[float, float]:
    return (a * a / reff - math.sqrt(2.0 * math.pi * W * a / ESTAR),
            4.0 * ESTAR * a**3 / (3.0 * reff) - math.sqrt(8.0 * math.pi * W * ESTAR * a**3))


def loop_energy(reff: float) -> float:
    """-int_{d_c}^{0} F dd along the JKR curve, by the contact radius a."""
    a_f = (math.pi * W * reff**2 / (8.0 * ESTAR)) ** (1.0 / 3.0)
    a_0 = (2.0 * math.pi * W * reff**2 / ESTAR) ** (1.0 / 3.0)

    def integrand(a: float) -> float:
        dd = 2.0 * a / reff - 0.5 * math.sqrt(2.0 * math.pi * W / (ESTAR * a))
        return _curve(a, reff)[1] * dd

    return -quad(integrand, a_f, a_0, epsrel=1e-12, epsabs=0.0)[0]


def _scene(restitution: float):
    import dpm

    sim = dpm.Simulation(dt=2e-7, gravity=(0.0, 0.0, 0.0), dt_check="off")
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    sim.contact(mat, mat, model="jkr", restitution=restitution, friction=0.5,
                work_of_adhesion=W)
    return sim, mat


def pull_off(quick: bool, models: Sequence[str]) -> list[Row]:
    fc = 1.5 * math.pi * W * R
    a_f = (math.pi * W * R**2 / (8.0 * ESTAR)) ** (1.0 / 3.0)
    d_c = _curve(a_f, R)[0]
    sim, mat = _scene(0.3)
    sim.add_boundary("plane", material=mat, point=(0, 0, 0), normal=(0, 0, 1))
    sim.add_particles("sphere", material=mat, radius=R, positions=[[0, 0, R - 1e-9]])
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    left = math.nan
    try:
        sim.run(steps=20000, progress=False)
        rest = R - float(sim.bodies.position[0, 2])
        for k in range(1, 101):  # to 0.97 F_c over 20 ms
            sim.gravity = (0.0, 0.0, 0.97 * fc / MASS * k / 100)
            sim.run(steps=1000, progress=False)
        f = 0.97
        while f < 1.1:
            f += 0.0025
            sim.gravity = (0.0, 0.0, f * fc / MASS)
            sim.run(steps=40000, progress=False)
            if R - float(sim.bodies.position[0, 2]) < d_c:
                left = f * fc
                break
    finally:
        numba.set_num_threads(threads)
    a_0 = (9.0 * math.pi * W * R**2 / (2.0 * ESTAR)) ** (1.0 / 3.0)
    return [compare("jkr_pull_off", "jkr", "rest overlap without load [m]",
                    [(rest, a_0**2 / (3.0 * R))], 1e-3, SOURCE + ": a_0^2/(3 R*)"),
            compare("jkr_pull_off", "jkr", "pull under which the sphere leaves [N]",
                    [(left, fc)], 1e-2, SOURCE + ": F_c = 3/2 pi W R* (0.25 % steps)")]


def sticking(quick: bool, models: Sequence[str]) -> list[Row]:
    meff, reff = MASS / 2.0, R / 2.0
    vc = math.sqrt(2.0 * loop_energy(reff) / meff)
    d_c = _curve((math.pi * W * reff**2 / (8.0 * ESTAR)) ** (1.0 / 3.0), reff)[0]
    out, stuck = [], []
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        for fraction in (0.95, 1.05, 1.5, 3.0):
            v = fraction * vc
            sim, mat = _scene(1.0)
            sim.add_particles("sphere", material=mat, radius=R,
                              positions=[[-R - 5e-8, 0, 0], [R + 5e-8, 0, 0]],
                              velocities=[[v / 2, 0, 0], [-v / 2, 0, 0]])
            sim.run(steps=40000, progress=False)
            x, u = sim.bodies.position, sim.bodies.velocity
            overlap = 2.0 * R - float(x[1, 0] - x[0, 0])
            if fraction < 1.0:
                stuck.append((float(overlap > d_c), 1.0))
            else:
                out.append((float(u[1, 0] - u[0, 0]), math.sqrt(v * v - vc * vc)))
    finally:
        numba.set_num_threads(threads)
    src = SOURCE + ": v_c = sqrt(2 E_loss/m*), E_loss by quadrature of the curve"
    return [compare("jkr_sticking", "jkr", "stuck at 0.95 v_c (1 = yes)", stuck, 0.0, src),
            compare("jkr_sticking", "jkr", "parting speed at 1.05, 1.5, 3 v_c [m/s]", out,
                    5e-3, src + "; sqrt(v^2 - v_c^2)")]


register(Case("jkr_pull_off", "JKR sphere on a wall: rest overlap and pull-off force", ("jkr",),
              pull_off))
register(Case("jkr_sticking", "JKR head-on impacts around the critical sticking speed",
              ("jkr",), sticking))
