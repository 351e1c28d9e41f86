"""JKR adhesion (issue 21) against JKR's closed forms and the energy of its hysteresis loop.

References, derived here from the JKR relations (Johnson, Kendall & Roberts 1971), not
from dpm's code:

    d(a) = a^2/R* - sqrt(2 pi W a/E*),   F(a) = 4 E* a^3/(3 R*) - sqrt(8 pi W E* a^3)

* the force-overlap curve, traced by the contact radius a (no inversion), with the
  pull-off force F_c = 3/2 pi W R*, the critical overlap d_c = -3/4 (pi^2 W^2 R*/E*^2)^(1/3)
  and F(d_c) = -5/9 F_c;
* the zero-load overlap a_0^2/(3 R*), a_0 = (9 pi W R*^2/(2 E*))^(1/3);
* pull-off under a slowly growing pull (force control): attached at 0.99 F_c at the
  equilibrium overlap of the curve, gone at 1.01 F_c;
* an elastic head-on impact: contact at d = 0, rebound along the curve, then the neck
  takes E_loss = -int_{d_c}^{0} F dd (quadrature of the parametric curve), so a pair
  separates iff m* v^2/2 > E_loss, with v_out^2 = v^2 - v_c^2 (Thornton & Ning 1998's
  energy balance; their fitted closed form is not used).
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import dpm
from dpm.errors import ParameterError

R = 1e-3
RHO = 2500.0
YOUNG = 1e7
NU = 0.3
W = 0.1  # J/m2
ESTAR = YOUNG / (2.0 * (1.0 - NU**2))
MASS = 4.0 / 3.0 * math.pi * R**3 * RHO


@pytest.fixture(autouse=True)
def one_thread():
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(threads)


# ------------------------------------------------------------------------ references


def curve(a: float, reff: float) -> tuple[float, float]:
    """(overlap, force) of the JKR curve at contact radius a."""
    d = a * a / reff - math.sqrt(2.0 * math.pi * W * a / ESTAR)
    f = 4.0 * ESTAR * a**3 / (3.0 * reff) - math.sqrt(8.0 * math.pi * W * ESTAR * a**3)
    return d, f


def a_break(reff: float) -> float:
    """Contact radius where d(a) is smallest (the break under displacement control)."""
    return (math.pi * W * reff**2 / (8.0 * ESTAR)) ** (1.0 / 3.0)


def loop_energy(reff: float) -> float:
    """-int_{d_c}^{0} F dd along the curve: the energy the neck takes from a pair."""
    a0 = (2.0 * math.pi * W * reff**2 / ESTAR) ** (1.0 / 3.0)  # d(a0) = 0

    def integrand(a):
        dd = 2.0 * a / reff - 0.5 * math.sqrt(2.0 * math.pi * W / (ESTAR * a))
        return curve(a, reff)[1] * dd

    return -quad(integrand, a_break(reff), a0, epsrel=1e-12, epsabs=0.0)[0]


def scene(dt: float = 2e-7, restitution: float = 1.0, skin: float | None = None,
          gravity=(0.0, 0.0, 0.0)) -> tuple[dpm.Simulation, dpm.Material]:
    sim = dpm.Simulation(dt=dt, gravity=gravity, dt_check="off")
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    sim.contact(mat, mat, model="jkr", restitution=restitution, friction=0.5,
                work_of_adhesion=W)
    if skin is not None:
        sim.skin = skin
    return sim, mat


# ------------------------------------------------------------------------ the law


def test_force_follows_the_jkr_curve_and_breaks_at_the_critical_overlap():
    from dpm.kernels.law_jkr import jkr_attached, jkr_normal

    reff = R / 2
    q = (ESTAR, W, 0.0)
    hist = np.zeros((1, 1))
    af = a_break(reff)
    for a in np.linspace(af, 20 * af, 40):
        d, f = curve(a, reff)
        got, sn = jkr_normal(q, d, 0.0, MASS, reff, 1e-7, hist, 0, 0)
        # (at the branch point d_c the root is double: a to sqrt(machine eps))
        tol = 1e-7 if a < 1.01 * af else 1e-10
        assert got == pytest.approx(f, rel=tol)
        assert sn == pytest.approx(2.0 * ESTAR * a, rel=tol)
    fc = 1.5 * math.pi * W * reff
    dc = curve(af, reff)[0]
    assert dc == pytest.approx(-0.75 * (math.pi**2 * W**2 * reff / ESTAR**2) ** (1 / 3),
                               rel=1e-12)
    assert jkr_normal(q, dc, 0.0, MASS, reff, 1e-7, hist, 0, 0)[0] == pytest.approx(
        -5.0 / 9.0 * fc, rel=1e-6)
    # the largest tension over the curve is the pull-off force
    ds = np.linspace(dc, 0.0, 2001)
    tension = -min(jkr_normal(q, d, 0.0, MASS, reff, 1e-7, hist, 0, 0)[0] for d in ds)
    assert tension == pytest.approx(fc, rel=1e-5)
    # hysteresis: attached only after touching, and only down to d_c
    hist[0, 0] = 0.0
    assert not jkr_attached(q, 0.5 * dc, reff, hist, 0, 0)
    hist[0, 0] = 1.0
    assert jkr_attached(q, 0.999 * dc, reff, hist, 0, 0)
    assert not jkr_attached(q, 1.001 * dc, reff, hist, 0, 0)


def test_friction_limit_includes_twice_the_pull_off_force():
    """Thornton & Yin (1991): a sliding contact carries mu (F_n + 2 F_c)."""
    from dpm.kernels.law_jkr import jkr_normal, jkr_tangential

    reff, mu = R / 2, 0.4
    hist = np.zeros((1, 4))
    fn, sn = jkr_normal((ESTAR, W, 0.0), -1e-7, 0.0, MASS, reff, 1e-7, hist, 0, 3)
    gstar = YOUNG / (4.0 * (2.0 - NU) * (1.0 + NU))
    ft = jkr_tangential((gstar, 0.0, mu, ESTAR, W), fn, sn, -1e-7, 1.0, 0.0, 0.0, 0.0, 0.0,
                        1.0, MASS, reff, 1e-3, hist, 0, 0)
    fc = 1.5 * math.pi * W * reff
    assert fn < 0.0  # attracted, yet friction holds
    assert math.hypot(*ft) == pytest.approx(mu * (fn + 2.0 * fc), rel=1e-12)


# ------------------------------------------------------------------------ in the engine


def test_rest_overlap_and_pull_off_force_on_a_wall():
    """A sphere resting on a wall sits at JKR's zero-load overlap; pulled off by a slowly
    growing body force it stays at 0.99 F_c (on the curve's equilibrium) and leaves at
    1.01 F_c."""
    fc = 1.5 * math.pi * W * R
    dc = curve(a_break(R), R)[0]

    def pulled(fraction: float) -> tuple[float, float]:
        sim, mat = scene(restitution=0.3)
        sim.add_boundary("plane", material=mat, point=(0, 0, 0), normal=(0, 0, 1))
        sim.add_particles("sphere", material=mat, radius=R, positions=[[0, 0, R - 1e-9]])
        sim.run(steps=20000, progress=False)
        rest = R - sim.bodies.position[0, 2]
        for k in range(1, 101):  # the pull grows to its value over 100 x 0.2 ms
            sim.gravity = (0.0, 0.0, fraction * fc / MASS * k / 100)
            sim.run(steps=1000, progress=False)
        sim.run(steps=60000, progress=False)
        return rest, R - sim.bodies.position[0, 2]

    rest, held = pulled(0.99)
    a0 = (9.0 * math.pi * W * R**2 / (2.0 * ESTAR)) ** (1.0 / 3.0)
    assert rest == pytest.approx(a0**2 / (3.0 * R), rel=1e-4)
    # the overlap of the curve's stable branch where F = -0.99 F_c
    a_eq = brentq(lambda a: curve(a, R)[1] + 0.99 * fc,
                  (9.0 * math.pi * W * R**2 / (8.0 * ESTAR)) ** (1 / 3), a0)
    assert held == pytest.approx(curve(a_eq, R)[0], rel=2e-3)
    _, gone = pulled(1.01)
    assert gone < 10 * dc  # released: flying off


@pytest.mark.parametrize("fraction", [0.9, 1.1, 1.5, 2.0])
def test_elastic_impact_sticks_below_the_critical_speed(fraction):
    """Two spheres meet at fraction x v_c (v_c from the loop energy): below it they stay
    stuck; above it they part at sqrt(v^2 - v_c^2)."""
    meff, reff = MASS / 2, R / 2
    vc = math.sqrt(2.0 * loop_energy(reff) / meff)
    v = fraction * vc
    sim, mat = scene()
    gap = 1e-7
    sim.add_particles("sphere", material=mat, radius=R,
                      positions=[[-R - gap / 2, 0, 0], [R + gap / 2, 0, 0]],
                      velocities=[[v / 2, 0, 0], [-v / 2, 0, 0]])
    sim.run(steps=40000, progress=False)
    x, u = sim.bodies.position, sim.bodies.velocity
    separation = x[1, 0] - x[0, 0] - 2 * R
    if fraction < 1.0:
        assert -separation > curve(a_break(reff), reff)[0]  # overlap > d_c: in contact
        assert sim.contacts.active[: sim.contacts.count].sum() == 1
    else:
        assert separation > 5e-6
        assert u[1, 0] - u[0, 0] == pytest.approx(math.sqrt(v * v - vc * vc), rel=2e-3)


def test_contact_beyond_the_skin_is_kept():
    """A skin much thinner than the neck: the lists reach |d_c| further, so a pair pulled
    apart by more than the skin still feels the neck (and parts at the loop energy)."""
    meff, reff = MASS / 2, R / 2
    vc = math.sqrt(2.0 * loop_energy(reff) / meff)
    v = 1.5 * vc
    sim, mat = scene(skin=1e-8)
    sim.add_particles("sphere", material=mat, radius=R,
                      positions=[[-R + 5e-9, 0, 0], [R - 5e-9, 0, 0]],
                      velocities=[[-v / 2, 0, 0], [v / 2, 0, 0]])
    sim.run(steps=40000, progress=False)
    u = sim.bodies.velocity
    assert u[1, 0] - u[0, 0] == pytest.approx(math.sqrt(v * v - vc * vc), rel=5e-3)
    assert sim.plan.reach == pytest.approx(-curve(a_break(R), R)[0], rel=1e-12)


def test_refusals_are_named():
    mat = dpm.Material("m", density=RHO, young=YOUNG, poisson=NU)
    sim = dpm.Simulation(dt=1e-7)
    with pytest.raises(ParameterError, match="work_of_adhesion"):
        sim.contact(mat, mat, model="jkr")
    with pytest.raises(ParameterError, match="rolling_friction"):
        sim.contact(mat, mat, model="jkr", work_of_adhesion=W, rolling_friction=0.1)
    sim = dpm.Simulation(dt=1e-7, integrator="numerov", gravity=(0, 0, 0))
    sim.contact(mat, mat, model="jkr", work_of_adhesion=W)
    sim.add_particles("sphere", material=mat, radius=R, positions=[[0, 0, 0]])
    with pytest.raises(ParameterError, match="implicit"):
        sim.run(steps=1, progress=False)


def test_universal_module_leaves_jkr_to_the_scene_module():
    from dpm import universal_step

    sim, mat = scene()
    sim.add_particles("sphere", material=mat, radius=R, positions=[[0, 0, 0]])
    sim.run(steps=1, progress=False)
    assert not universal_step.covers(sim.plan.laws)
    assert sim.plan.module(False).RANGED
