"""Physics of the foundation against independent analytic references.

Every reference here is derived in this file (closed forms from the literature, or scipy
ODE solutions of the contact equations), never taken from dpm's own helpers:

* linear spring-dashpot with the attractive force cut off: restitution and contact time
  (Schwager & Poschel 2007, PRE 75 051304), checked against ``solve_ivp``;
* elastic Hertz impact: contact time, peak overlap and peak force (Johnson 1985, §11.4);
* free fall under gravity (exact for velocity Verlet, discrete formula for symplectic Euler);
* a sphere resting on a plane carries its weight; Hertz / linear static overlap;
* conservation of linear and angular momentum in oblique frictional collisions;
* energy of an elastic frictionless Hertz gas in a box over 1e5 velocity-Verlet steps;
* sticking friction (tangential spring with history): a sphere held between two walls by
  friction, and a sphere rolling without slip down an incline (a = 5/7 g sin theta).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import dpm

# ------------------------------------------------------------------------- references


def sphere_mass(radius: float, density: float) -> float:
    return 4.0 / 3.0 * math.pi * radius**3 * density


def estar(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """Effective Young modulus of two elastic bodies (Johnson 1985, eq. 4.22)."""
    return 1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def gstar(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """Effective shear modulus of Mindlin's no-slip tangential stiffness 8 G* a."""
    g1 = e1 / (2.0 * (1.0 + nu1))
    g2 = e2 / (2.0 * (1.0 + nu2))
    return 1.0 / ((2.0 - nu1) / g1 + (2.0 - nu2) / g2)


def cutoff_closed_form(zeta: float) -> tuple[float, float]:
    """(restitution, contact time * omega0) of m x'' = -max(0, k x + c x'), zeta < 1.

    Schwager & Poschel (2007): the force vanishes at t_c = (pi - 2 atan(beta/omega))/omega,
    beta = zeta omega0, omega = omega0 sqrt(1 - zeta^2); e = exp(-beta t_c).
    """
    w = math.sqrt(1.0 - zeta * zeta)
    tc = (math.pi - 2.0 * math.atan(zeta / w)) / w
    return math.exp(-zeta * tc), tc


def zeta_for_restitution(e: float) -> float:
    """Damping ratio whose cut-off linear contact has restitution e (closed form + brentq)."""
    return brentq(lambda z: math.log(cutoff_closed_form(z)[0]) - math.log(e), 1e-12,
                  1.0 - 1e-12, xtol=1e-15, rtol=1e-15)


def cutoff_ode(zeta: float) -> tuple[float, float]:
    """(restitution, contact time * omega0) by integrating x'' = -max(0, x + 2 zeta x')
    from x = 0, x' = 1 until the force returns to zero (dimensionless: m = k = 1)."""

    def rhs(t, y):
        return [y[1], -max(0.0, y[0] + 2.0 * zeta * y[1])]

    def force_zero(t, y):
        return y[0] + 2.0 * zeta * y[1]

    force_zero.terminal = True
    force_zero.direction = -1
    sol = solve_ivp(rhs, (0.0, 10.0), [0.0, 1.0], method="DOP853", events=force_zero,
                    rtol=1e-12, atol=1e-14)
    t_end = float(sol.t_events[0][0])
    return -float(sol.y_events[0][0][1]), t_end


def hertz_reference(meff: float, reff: float, e_star: float, v: float):
    """(contact time, peak overlap, peak force) of an elastic Hertz impact at speed v."""
    tc = 2.868 * (meff**2 / (reff * e_star**2 * v)) ** 0.2
    dmax = (15.0 * meff * v**2 / (16.0 * e_star * math.sqrt(reff))) ** 0.4
    fmax = 4.0 / 3.0 * e_star * math.sqrt(reff) * dmax**1.5
    return tc, dmax, fmax


def hertz_ode(meff: float, reff: float, e_star: float, v: float):
    """Same quantities from solve_ivp of m* d'' = -4/3 E* sqrt(R*) d^(3/2)."""
    kh = 4.0 / 3.0 * e_star * math.sqrt(reff)

    def rhs(t, y):
        return [y[1], -kh * max(y[0], 0.0) ** 1.5 / meff]

    def out(t, y):
        return y[0]

    def peak(t, y):
        return y[1]

    out.terminal = True
    out.direction = -1
    scale = (meff**2 / (reff * e_star**2 * v)) ** 0.2
    sol = solve_ivp(rhs, (0.0, 10 * scale), [0.0, v], method="DOP853", events=(out, peak),
                    rtol=1e-12, atol=1e-20 * v)
    tc = float(sol.t_events[0][0])
    dmax = float(sol.y_events[1][0][0])
    return tc, dmax, kh * dmax**1.5


def crossing(t: np.ndarray, f: np.ndarray, i: int) -> float:
    """Time where f changes sign between samples i and i + 1 (linear interpolation)."""
    return float(t[i] + (t[i + 1] - t[i]) * f[i] / (f[i] - f[i + 1]))


# ------------------------------------------------------------------------- the references


@pytest.mark.parametrize("e", [0.2, 0.5, 0.9])
def test_reference_cutoff_linear_contact_is_consistent(e):
    """The closed form and the ODE agree: the reference used below is right."""
    zeta = zeta_for_restitution(e)
    e_ode, tc_ode = cutoff_ode(zeta)
    e_cf, tc_cf = cutoff_closed_form(zeta)
    assert e_ode == pytest.approx(e, rel=1e-9)
    assert tc_ode == pytest.approx(tc_cf, rel=1e-9)


def test_reference_hertz_is_consistent():
    """2.868 (m*^2/(R* E*^2 v))^(1/5) and delta_max agree with an ODE solution."""
    ref = hertz_reference(2e-5, 4e-4, 3e6, 0.3)
    ode = hertz_ode(2e-5, 4e-4, 3e6, 0.3)
    assert ode[0] == pytest.approx(ref[0], rel=2e-4)  # 2.868 is rounded (2.86827)
    assert ode[1] == pytest.approx(ref[1], rel=1e-8)
    assert ode[2] == pytest.approx(ref[2], rel=1e-8)


# ------------------------------------------------------------------------- linear law

LINEAR_K = 1e3  # N/m
GLASS = dict(density=2500.0, young=5e6, poisson=0.45)
STEEL = dict(density=7800.0, young=2e7, poisson=0.3)

def _linear_collision(e: float, against: str, steps_per_contact: int = 100):
    """Head-on cut-off linear spring-dashpot collision that starts on a step.

    The contact starts at t = 0 with a negligible overlap (1e-9 r), so the jump of the
    dashpot force at first touch falls on a step and the measurement sees the law and the
    integrator only. Returns (measured e, measured contact time, reference contact time).
    """
    r1, r2 = 1e-3, 1.4e-3
    m1 = sphere_mass(r1, GLASS["density"])
    m2 = sphere_mass(r2, STEEL["density"])
    meff = m1 if against == "wall" else m1 * m2 / (m1 + m2)
    zeta = zeta_for_restitution(e)
    omega0 = math.sqrt(LINEAR_K / meff)
    tc_ref = cutoff_closed_form(zeta)[1] / omega0
    c = 2.0 * zeta * math.sqrt(meff * LINEAR_K)
    dt = tc_ref / steps_per_contact
    v = 0.1
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, 0))
    a = dpm.Material("a", **GLASS)
    b = dpm.Material("b", **STEEL)
    for p, q in ((a, a), (a, b), (b, b)):
        sim.contact(p, q, model="linear_spring_dashpot", stiffness=LINEAR_K, restitution=e,
                    friction=0.5)
    n = np.array([1.0, 2.0, -0.5]) / math.sqrt(5.25)  # line of centres, not along an axis
    eps = 1e-9 * r1
    if against == "wall":
        sim.add_boundary("plane", material=b, point=(0, 0, 0), normal=n)
        sim.add_particles("sphere", material=a, radius=r1, positions=[(r1 - eps) * n],
                          velocities=[-v * n])
    else:
        # centre of mass at rest; 1 approaches 2 along -n
        sim.add_particles("sphere", material=a, radius=r1, positions=[(0, 0, 0)],
                          velocities=[v * m2 / (m1 + m2) * -n])
        sim.add_particles("sphere", material=b, radius=r2,
                          positions=[-(r1 + r2 - eps) * n], velocities=[v * m1 / (m1 + m2) * n])

    def overlap_and_rate():
        if against == "wall":
            x, u = sim.bodies.position[0], sim.bodies.velocity[0]
            return r1 - x @ n, -(u @ n)
        x = sim.bodies.position[0] - sim.bodies.position[1]
        u = sim.bodies.velocity[0] - sim.bodies.velocity[1]
        return r1 + r2 - x @ n, -(u @ n)

    f_lin = [LINEAR_K * eps + c * v]  # k d + c d' at t = 0 (before the attractive cut-off)
    t = [0.0]
    for _ in range(int(1.3 * steps_per_contact)):
        sim.run(steps=1, progress=False)
        d, dd = overlap_and_rate()
        f_lin.append(LINEAR_K * d + c * dd)
        t.append(sim.time)
    f_lin = np.array(f_lin)
    i_end = int(np.argmax(f_lin < 0.0)) - 1
    assert i_end > 0
    tc = crossing(np.array(t), f_lin, i_end)
    e_meas = -overlap_and_rate()[1] / v
    return e_meas, tc, tc_ref


@pytest.mark.parametrize("against", ["sphere", "wall"])
@pytest.mark.parametrize("e", [0.2, 0.5, 0.9])
def test_linear_spring_dashpot_restitution(e, against):
    """The cut-off linear law reproduces the set restitution to 1e-3 (relative) with 100
    steps per contact, and the contact time t_c = (pi - 2 atan(beta/omega))/omega."""
    e_meas, tc, tc_ref = _linear_collision(e, against)
    assert e_meas == pytest.approx(e, rel=1e-3)
    assert tc == pytest.approx(tc_ref, rel=1e-3)


@pytest.mark.parametrize("e", [0.2, 0.5, 0.9])
def test_linear_spring_dashpot_converges_to_reference(e):
    """Whatever the order of the scheme, the restitution and contact time measured at 100,
    200 and 400 steps per contact extrapolate (quadratic in dt) to the references within
    1e-4: the law (damping solved for the cut-off restitution) is right."""
    runs = [_linear_collision(e, "wall", n) for n in (100, 200, 400)]
    e_h, e_h2, e_h4 = (run[0] for run in runs)
    t_h, t_h2, t_h4 = (run[1] for run in runs)
    tc_ref = runs[0][2]
    assert (8 * e_h4 - 6 * e_h2 + e_h) / 3 == pytest.approx(e, rel=1e-4)
    assert (8 * t_h4 - 6 * t_h2 + t_h) / 3 == pytest.approx(tc_ref, rel=1e-4)
    # and the error shrinks with the step
    assert abs(e_h4 - e) < 0.5 * abs(e_h - e) + 1e-6 * e
    assert abs(t_h4 - tc_ref) < 0.5 * abs(t_h - tc_ref) + 1e-6 * tc_ref


# ------------------------------------------------------------------------- Hertz


@pytest.mark.parametrize("against", ["sphere", "wall"])
def test_elastic_hertz_impact(against):
    """Elastic, frictionless Hertz impact: contact time 2.868 (m*^2/(R* E*^2 v))^(1/5),
    peak overlap (15 m* v^2 / (16 E* sqrt(R*)))^(2/5) and peak force within 1 %
    (measured well inside: ~1e-4), restitution 1."""
    a = dpm.Material("a", **GLASS)
    b = dpm.Material("b", **STEEL)
    r1, r2 = 1e-3, 0.7e-3
    m1, m2 = sphere_mass(r1, a.density), sphere_mass(r2, b.density)
    e_star = estar(a.young, a.poisson, b.young, b.poisson)
    if against == "wall":
        meff, reff = m1, r1
    else:
        meff, reff = m1 * m2 / (m1 + m2), r1 * r2 / (r1 + r2)
    v = 0.2
    tc_ref, dmax_ref, fmax_ref = hertz_reference(meff, reff, e_star, v)
    steps = 400
    dt = tc_ref / steps
    sim = dpm.Simulation(dt=dt, gravity=(0, 0, 0))
    for p, q in ((a, a), (a, b), (b, b)):
        sim.contact(p, q, model="hertz_mindlin", restitution=1.0, friction=0.0)
    n = np.array([0.0, -0.6, 0.8])
    gap = 3.3 * v * dt  # contact starts between steps: both crossings interpolated
    if against == "wall":
        sim.add_boundary("plane", material=b, point=(0, 0, 0), normal=n)
        sim.add_particles("sphere", material=a, radius=r1, positions=[(r1 + gap) * n],
                          velocities=[-v * n])
    else:
        sim.add_particles("sphere", material=a, radius=r1, positions=[(0, 0, 0)],
                          velocities=[-v * m2 / (m1 + m2) * n])
        sim.add_particles("sphere", material=b, radius=r2, positions=[-(r1 + r2 + gap) * n],
                          velocities=[v * m1 / (m1 + m2) * n])

    def overlap():
        if against == "wall":
            return r1 - sim.bodies.position[0] @ n
        return r1 + r2 - (sim.bodies.position[0] - sim.bodies.position[1]) @ n

    t, d, f, f_wall = [0.0], [overlap()], [0.0], [0.0]
    for _ in range(int(1.2 * steps) + 10):
        sim.run(steps=1, progress=False)
        t.append(sim.time)
        d.append(overlap())
        f.append(np.linalg.norm(sim.bodies.force[0]))
        if against == "wall":
            # the particle pushes the wall along -n with the contact force
            f_wall.append(-sim.boundaries[0].force @ n)
    t, d, f = map(np.array, (t, d, f))
    inside = np.nonzero(d > 0)[0]
    assert inside[-1] < len(d) - 1, "the contact did not end"
    tc = crossing(t, d, inside[-1]) - crossing(t, d, inside[0] - 1)
    assert tc == pytest.approx(tc_ref, rel=1e-2)
    assert d.max() == pytest.approx(dmax_ref, rel=1e-2)
    assert f.max() == pytest.approx(fmax_ref, rel=1e-2)
    # the measurement is far better than the required 1 %
    assert tc == pytest.approx(tc_ref, rel=1e-3)
    assert d.max() == pytest.approx(dmax_ref, rel=1e-4)
    assert f.max() == pytest.approx(fmax_ref, rel=1e-4)
    if against == "wall":
        vn = sim.bodies.velocity[0] @ n
        np.testing.assert_allclose(f_wall, f, rtol=1e-12, atol=1e-12 * fmax_ref)
    else:
        vn = (sim.bodies.velocity[0] - sim.bodies.velocity[1]) @ n
    assert vn == pytest.approx(v, rel=1e-5)


# ------------------------------------------------------------------------- free fall


@pytest.mark.parametrize("integrator", ["velocity_verlet", "symplectic_euler"])
def test_free_fall(integrator):
    """Velocity Verlet is exact for constant gravity: x = x0 + v0 t + g t^2/2 to round-off.
    Symplectic Euler follows its discrete solution x_n = x0 + n dt v0 + g dt^2 n(n+1)/2."""
    g = np.array([0.3, -0.2, -9.81])
    x0 = np.array([0.01, 0.02, 0.5])
    v0 = np.array([0.1, 0.05, 0.2])
    w0 = np.array([3.0, -1.0, 2.0])
    dt = 1e-4
    sim = dpm.Simulation(dt=dt, gravity=g, integrator=integrator)
    a = dpm.Material("a", **GLASS)
    sim.contact(a, a, model="hertz_mindlin")  # needed by the scene check, never used
    sim.add_particles("sphere", material=a, radius=0.01, positions=[x0], velocities=[v0],
                      angular_velocities=[w0])
    n = 0
    for _ in range(10):
        sim.run(steps=200, progress=False)
        n += 200
        t = n * dt
        if integrator == "velocity_verlet":
            x = x0 + v0 * t + 0.5 * g * t * t
        else:
            x = x0 + n * dt * v0 + g * dt * dt * n * (n + 1) / 2
        np.testing.assert_allclose(sim.bodies.position[0], x, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sim.bodies.velocity[0], v0 + g * t, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sim.bodies.angular_velocity[0], w0, rtol=0, atol=0)
        assert sim.time == pytest.approx(t, rel=1e-14)
    assert sim.step_count == 2000


# ------------------------------------------------------------------------- resting sphere


@pytest.mark.parametrize("model", ["hertz_mindlin", "linear_spring_dashpot"])
@pytest.mark.parametrize("boundary", ["plane", "box"])
def test_resting_sphere_carries_its_weight(model, boundary):
    """A sphere settled on a floor pushes it with exactly m g, at the static overlap
    (3 m g / (4 E* sqrt(r)))^(2/3) (Hertz) or m g / k (linear)."""
    r, g = 1e-3, 9.81
    a = dpm.Material("a", **GLASS)
    b = dpm.Material("b", **STEEL)
    m = sphere_mass(r, a.density)
    if model == "hertz_mindlin":
        kw = {}
        d_static = (3 * m * g / (4 * estar(a.young, a.poisson, b.young, b.poisson)
                                 * math.sqrt(r))) ** (2 / 3)
    else:
        kw = {"stiffness": LINEAR_K}
        d_static = m * g / LINEAR_K
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -g))
    sim.contact(a, a, model=model, restitution=0.3, friction=0.5, **kw)
    sim.contact(a, b, model=model, restitution=0.3, friction=0.5, **kw)
    if boundary == "plane":
        sim.add_boundary("plane", material=b, point=(0, 0, 0), normal=(0, 0, 1))
    else:
        sim.add_boundary("box", material=b, lower=(-5 * r, -5 * r, 0), upper=(5 * r, 5 * r, 1),
                         open=("+z",))
    sim.add_particles("sphere", material=a, radius=r, positions=[(0.5e-3, -1e-3, r)])
    sim.run(until=0.03, progress=False)
    np.testing.assert_allclose(sim.boundaries[0].force, [0, 0, -m * g], rtol=0,
                               atol=1e-9 * m * g)
    assert r - sim.bodies.position[0, 2] == pytest.approx(d_static, rel=1e-8)
    np.testing.assert_allclose(sim.bodies.position[0, :2], [0.5e-3, -1e-3], rtol=0, atol=1e-15)


# ------------------------------------------------------------------------- momentum


@pytest.mark.parametrize("model, integrator", [
    ("hertz_mindlin", "velocity_verlet"), ("linear_spring_dashpot", "velocity_verlet"),
    ("hertz_mindlin", "symplectic_euler"),  # (each law x integrator pair costs a compile)
])
def test_momentum_conserved_in_oblique_frictional_collision(model, integrator):
    """Unequal spheres, oblique impact with spin, friction and rolling friction: total
    linear momentum (to 1e-12) and angular momentum about the origin, sum of m r x v + I w
    (to 1e-10), stay constant at every step, while the collision exchanges a lot of both."""
    a = dpm.Material("a", **GLASS)
    b = dpm.Material("b", **STEEL)
    r1, r2 = 1e-3, 0.6e-3
    m1, m2 = sphere_mass(r1, a.density), sphere_mass(r2, b.density)
    i1, i2 = 0.4 * m1 * r1**2, 0.4 * m2 * r2**2
    kw = {"stiffness": LINEAR_K} if model == "linear_spring_dashpot" else {}
    sim = dpm.Simulation(dt=2e-7, gravity=(0, 0, 0), integrator=integrator)
    for p, q in ((a, a), (a, b), (b, b)):
        sim.contact(p, q, model=model, restitution=0.6, friction=0.4, rolling_friction=0.05,
                    **kw)
    x = np.array([[0.0, 0.0, 0.0], [1.52e-3, 0.55e-3, 0.25e-3]])  # 36 um apart, oblique
    v = np.array([[0.15, 0.02, -0.01], [-0.2, 0.05, 0.03]])
    w = np.array([[0.0, 0.0, 300.0], [-200.0, 100.0, 0.0]])
    sim.add_particles("sphere", material=a, radius=r1, positions=x[:1], velocities=v[:1],
                      angular_velocities=w[:1])
    sim.add_particles("sphere", material=b, radius=r2, positions=x[1:], velocities=v[1:],
                      angular_velocities=w[1:])
    mass = np.array([m1, m2])
    inertia = np.array([i1, i2])

    def momenta():
        bx, bv, bw = sim.bodies.position, sim.bodies.velocity, sim.bodies.angular_velocity
        lin = mass[:, None] * np.cross(bx, bv)
        spin = inertia[:, None] * bw
        return (mass[:, None] * bv).sum(axis=0), (lin + spin).sum(axis=0)

    p0, l0 = momenta()
    scale_p = float(np.sum(mass * np.linalg.norm(v, axis=1)))
    scale_l = float(np.sum(mass * np.linalg.norm(np.cross(x, v), axis=1))
                    + np.sum(inertia * np.linalg.norm(w, axis=1)))
    np.testing.assert_allclose(sim.momentum(), p0, rtol=1e-14)
    touched = False
    for _ in range(2000):
        sim.run(steps=10, progress=False)
        p, l_tot = momenta()
        assert np.max(np.abs(p - p0)) <= 1e-12 * scale_p
        assert np.max(np.abs(l_tot - l0)) <= 1e-10 * scale_l
        gap = np.linalg.norm(sim.bodies.position[0] - sim.bodies.position[1]) - r1 - r2
        touched |= gap < 0
        if touched and gap > 1e-6:
            break
    assert touched and gap > 0, "the collision should have happened and be over"
    # the collision was real: momentum and spin were exchanged, with friction
    dp = m1 * np.linalg.norm(sim.bodies.velocity[0] - v[0])
    assert dp > 0.3 * scale_p
    assert np.linalg.norm(sim.bodies.angular_velocity[0] - w[0]) > 0.1 * np.linalg.norm(w[0])
    assert np.linalg.norm(sim.bodies.angular_velocity[1] - w[1]) > 0.1 * np.linalg.norm(w[1])


# ------------------------------------------------------------------------- energy


def _hertz_gas(n_particles: int, steps: int, seed: int = 1, per_contact: int = 600):
    a = dpm.Material("a", **GLASS)
    r, size = 1e-3, 0.012
    m = sphere_mass(r, a.density)
    e_pp = estar(a.young, a.poisson, a.young, a.poisson)
    rng = np.random.default_rng(seed)
    grid = np.arange(4) * 2.6e-3 + 2e-3
    x = np.array([(i, j, k) for i in grid for j in grid for k in grid])[:n_particles]
    x = x + rng.uniform(-2e-4, 2e-4, x.shape)
    v = rng.normal(0.0, 0.1, x.shape)
    vmax = 2.0 * float(np.linalg.norm(v, axis=1).max())
    tc = 2.868 * ((m / 2) ** 2 / ((r / 2) * e_pp**2 * vmax)) ** 0.2  # fastest head-on contact
    sim = dpm.Simulation(dt=tc / per_contact, gravity=(0, 0, 0), integrator="velocity_verlet")
    sim.contact(a, a, model="hertz_mindlin", restitution=1.0, friction=0.0)
    sim.add_boundary("box", material=a, lower=(0, 0, 0), upper=(size, size, size))
    sim.add_particles("sphere", material=a, radius=r, positions=x, velocities=v)

    def energy():
        p, u = sim.bodies.position, sim.bodies.velocity
        kinetic = 0.5 * m * float(np.sum(u * u))
        iu = np.triu_indices(len(p), 1)
        d = r + r - np.linalg.norm(p[:, None] - p[None], axis=2)[iu]
        d = d[d > 0]
        pot = float(np.sum(8 / 15 * e_pp * math.sqrt(r / 2) * d**2.5))
        for axis in range(3):
            for dw in (r - p[:, axis], r - (size - p[:, axis])):
                dw = dw[dw > 0]
                pot += float(np.sum(8 / 15 * e_pp * math.sqrt(r) * dw**2.5))
        return kinetic + pot, kinetic

    e0, k0 = energy()
    assert k0 == pytest.approx(sim.kinetic_energy(), rel=1e-14)
    worst = 0.0
    chunk = 1000
    for _ in range(steps // chunk):
        sim.run(steps=chunk, progress=False)
        e, _ = energy()
        worst = max(worst, abs(e / e0 - 1.0))
    changed = np.linalg.norm(sim.bodies.velocity - v, axis=1) > 0.3 * np.linalg.norm(v, axis=1)
    return worst, float(np.mean(changed))


def test_elastic_hertz_gas_conserves_energy():
    """60 elastic frictionless spheres in a box: kinetic + Hertz potential energy
    (8/15 E* sqrt(R*) d^(5/2) per overlap, walls included) stays within 1e-6 of its start
    over 1e5 velocity-Verlet steps (600 steps per fastest contact), while nearly every
    particle has collided."""
    worst, collided = _hertz_gas(60, 100_000, per_contact=600)
    assert collided > 0.8
    assert worst < 1e-6


@pytest.mark.slow
def test_elastic_hertz_gas_conserves_energy_long():
    """As above over 1e6 steps."""
    worst, collided = _hertz_gas(60, 1_000_000, seed=2, per_contact=600)
    assert collided > 0.9
    assert worst < 1e-6


# ------------------------------------------------------------------------- friction


def test_friction_holds_sphere_between_walls():
    """A sphere squeezed between two vertical walls (overlap 0.002 r each) hangs on static
    friction (m g / 2 per wall < mu N): it sags by exactly the Mindlin spring stretch
    m g / (2 * 8 G* sqrt(r d)) and stays there, without rotating. With mu below the limit
    it slides down at a = g - 2 mu N / m. This needs a tangential spring with history."""
    a = dpm.Material("a", **GLASS)
    r, g = 1e-3, 9.81
    m = sphere_mass(r, a.density)
    d0 = 0.002 * r
    e_w = estar(a.young, a.poisson, a.young, a.poisson)
    g_w = gstar(a.young, a.poisson, a.young, a.poisson)
    normal = 4 / 3 * e_w * math.sqrt(r) * d0**1.5
    kt = 8 * g_w * math.sqrt(r * d0)
    sag = m * g / (2 * kt)
    assert m * g / 2 < 0.5 * normal  # sticks with mu = 0.5
    results = {}
    for mu in (0.5, 0.02):
        sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -g))
        sim.contact(a, a, model="hertz_mindlin", restitution=0.3, friction=mu)
        sim.add_boundary("box", material=a, lower=(0, -1, -1), upper=(2 * r - 2 * d0, 1, 1),
                         open=("-y", "+y", "-z", "+z"))
        sim.add_particles("sphere", material=a, radius=r, positions=[(r - d0, 0, 0)])
        t, z, vz = [], [], []
        for _ in range(50):
            sim.run(steps=200, progress=False)
            t.append(sim.time)
            z.append(sim.bodies.position[0, 2])
            vz.append(sim.bodies.velocity[0, 2])
        results[mu] = (np.array(t), np.array(z), np.array(vz), sim.bodies.position[0].copy(),
                       sim.bodies.angular_velocity[0].copy(), sim.boundaries[0].force.copy())
    t, z, vz, x, omega, wall = results[0.5]
    assert np.max(np.abs(z)) < 1.2 * sag  # bounded: the spring only stretches
    # settles at the static stretch; the history integrates the predicted velocity of
    # velocity Verlet, which differs from the drift velocity by O(dt a) during the sag
    assert -z[-1] == pytest.approx(sag, rel=1e-4)
    assert np.max(np.abs(z[-10:] - z[-1])) < 1e-6 * sag
    assert np.max(np.abs(vz[-10:])) < 1e-9
    assert x[0] == pytest.approx(r - d0, rel=1e-12)
    assert np.linalg.norm(omega) < 1e-9
    np.testing.assert_allclose(wall, [0, 0, -m * g], rtol=0, atol=1e-9 * m * g)
    t, z, vz, x, omega, wall = results[0.02]
    acc = g - 2 * 0.02 * normal / m
    np.testing.assert_allclose(np.diff(vz[5:]) / np.diff(t[5:]), -acc, rtol=1e-6)
    assert -wall[2] == pytest.approx(2 * 0.02 * normal, rel=1e-6)
    assert np.linalg.norm(omega) < 1e-9  # the two friction torques cancel


@pytest.mark.parametrize("mu", [0.5, 0.05, 0.0])
def test_sphere_on_incline(mu):
    """A sphere released on a plane tilted by theta = 20 deg (below atan(0.5)).

    mu = 0.5: the contact sticks and the sphere rolls without slipping,
    a = g sin / (1 + I / (m l^2)) (= 5/7 g sin for l = r; l = r - d/2 is the lever arm to
    dpm's contact point, the middle of the overlap), w l = v, the slip stays within the
    tangential spring stretch. mu = 0.05 < 2/7 tan(theta): it slides, a = g (sin - mu cos),
    dw/dt = mu m g cos l / I. Frictionless: a = g sin, no spin. The plane carries
    m g cos(theta) normally and the friction force tangentially."""
    a = dpm.Material("a", **GLASS)
    r, g, th = 1e-3, 9.81, math.radians(20.0)
    m = sphere_mass(r, a.density)
    inertia = 0.4 * m * r**2
    n = np.array([-math.sin(th), 0.0, math.cos(th)])
    down = -np.array([math.cos(th), 0.0, math.sin(th)])
    axis = np.cross(n, down)  # rolling downhill turns about n x down
    e_w = estar(a.young, a.poisson, a.young, a.poisson)
    d_n = (3 * m * g * math.cos(th) / (4 * e_w * math.sqrt(r))) ** (2 / 3)
    arm = r - d_n / 2
    normal = m * g * math.cos(th)
    sim = dpm.Simulation(dt=2e-6, gravity=(0, 0, -g))
    sim.contact(a, a, model="hertz_mindlin", restitution=0.3, friction=mu)
    sim.add_boundary("plane", material=a, point=(0, 0, 0), normal=n)
    x0 = (r - d_n) * n
    sim.add_particles("sphere", material=a, radius=r, positions=[x0])
    t, v, w, slip, fn, ft = [], [], [], [], [], []
    for _ in range(30):
        sim.run(steps=500, progress=False)
        q = sim.bodies.orientation[0]
        angle = 2 * math.atan2(q[1:] @ axis, q[0])
        force = sim.boundaries[0].force
        t.append(sim.time)
        v.append(sim.bodies.velocity[0] @ down)
        w.append(sim.bodies.angular_velocity[0] @ axis)
        slip.append((sim.bodies.position[0] - x0) @ down - arm * angle)
        fn.append(-force @ n)
        ft.append(force @ down)  # the sphere drags the plane downhill
    t, v, w, slip, fn, ft = map(np.array, (t, v, w, slip, fn, ft))
    late = slice(5, None)  # after the first 5 ms (the tangential spring loads at first)
    acc = np.diff(v[late]) / np.diff(t[late])
    spin = np.diff(w[late]) / np.diff(t[late])
    if mu == 0.5:
        acc_ref = g * math.sin(th) / (1 + inertia / (m * arm**2))
        friction = inertia * acc_ref / arm**2
        kt = 8 * gstar(a.young, a.poisson, a.young, a.poisson) * math.sqrt(r * d_n)
        assert friction < mu * normal
        assert acc_ref == pytest.approx(5 / 7 * g * math.sin(th), rel=1e-3)
        assert np.max(np.abs(slip)) < 1.5 * friction / kt  # sticks: only the spring stretches
        np.testing.assert_allclose(w[late] * arm, v[late], rtol=1e-6)
        np.testing.assert_allclose(spin * arm, acc, rtol=1e-6)
    else:
        acc_ref = g * (math.sin(th) - mu * math.cos(th))
        friction = mu * normal
        np.testing.assert_allclose(spin, friction * arm / inertia, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(acc, acc_ref, rtol=1e-6)
    np.testing.assert_allclose(fn, normal, rtol=1e-6)
    np.testing.assert_allclose(ft[late], friction, rtol=1e-6, atol=1e-12 * normal)
    assert np.max(np.abs((sim.bodies.position[0] - x0) @ n)) < 1e-3 * d_n  # stays on it
