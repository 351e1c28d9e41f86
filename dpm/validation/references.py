"""Closed-form references of the validation cases (no engine code is used here).

* Hertz (1882) head-on impact of elastic spheres (or a sphere and a rigid plane), with
  m* = m1 m2/(m1 + m2), R* = R1 R2/(R1 + R2), 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 and
  the approach speed v::

      F = 4/3 E* sqrt(R*) d^(3/2)
      d_max = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5)
      F_max = 4/3 E* sqrt(R*) d_max^(3/2)
      T     = 2 (d_max / v) int_0^1 dx / sqrt(1 - x^(5/2)) = (4/5) B(2/5, 1/2) d_max / v
            = 2.9432 d_max / v

  (energy: 1/2 m* v^2 = 8/15 E* sqrt(R*) d_max^(5/2); the duration integral from
  m* d'^2 / 2 = m* v^2/2 - 8/15 E* sqrt(R*) d^(5/2)).

* Rigid-body impact with Coulomb friction that slides for the whole contact (Maw, Barber
  & Fawcett 1976, their large-angle limit; Walton 1993; Thornton et al.): the normal
  impulse J_n = (1 + e) u_n / A with A = 1/m1 + 1/m2, the tangential impulse mu J_n against
  the contact point's slip u_t, as long as abs(u_t) >= mu J_n B with
  B = 1/m1 + 1/m2 + R1^2/I1 + R2^2/I2 (a plane: A = 1/m, B = 7/(2m) for a solid sphere).
  Sphere i then changes its tangential velocity by -+ mu J_n / m_i and the surface speed of
  its contact point by -+ mu J_n R_i^2 / I_i.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: int_0^1 (1 - x^(5/2))^(-1/2) dx = (2/5) B(2/5, 1/2)
HERTZ_INTEGRAL = 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)


def effective_young(e1: float, nu1: float, e2: float = math.inf, nu2: float = 0.0) -> float:
    """E* of two elastic bodies; ``e2 = inf`` (default) is a rigid plane."""
    inv = (1.0 - nu1 * nu1) / e1 + (0.0 if math.isinf(e2) else (1.0 - nu2 * nu2) / e2)
    return 1.0 / inv


def sphere_mass(radius: float, density: float) -> float:
    return 4.0 / 3.0 * math.pi * radius**3 * density


@dataclass(frozen=True)
class Hertz:
    """Hertz's head-on impact: largest overlap [m], largest force [N], duration [s]."""

    max_overlap: float
    max_force: float
    duration: float


def hertz_impact(meff: float, reff: float, estar: float, speed: float) -> Hertz:
    """The elastic Hertz impact at approach speed ``speed`` (module docstring)."""
    k = 4.0 / 3.0 * estar * math.sqrt(reff)
    dmax = (15.0 * meff * speed**2 / (16.0 * estar * math.sqrt(reff))) ** 0.4
    return Hertz(max_overlap=dmax, max_force=k * dmax**1.5,
                 duration=2.0 * HERTZ_INTEGRAL * dmax / speed)


@dataclass(frozen=True)
class Sliding:
    """Rigid-body Coulomb impact: the tangential impulse, whether sliding lasts the whole
    contact, and the changes of the two spheres' tangential and surface speeds."""

    normal_impulse: float    #: J_n [N s]
    tangential_impulse: float  #: mu J_n [N s] (its sign: against the slip)
    margin: float            #: abs(u_t) / (mu J_n B): >= 1 slides throughout
    dv1: float               #: change of sphere 1's tangential velocity [m/s]
    dsurf1: float            #: change of sphere 1's contact-point surface speed [m/s]
    dv2: float               #: same for sphere 2 (0 for a plane)
    dsurf2: float


def rigid_sliding(un: float, ut: float, e: float, mu: float, m1: float, r1: float,
                  i1: float, m2: float = math.inf, r2: float = 0.0,
                  i2: float = math.inf) -> Sliding:
    """Sliding impact of sphere 1 on sphere 2 (default: a rigid plane).

    ``un`` > 0 the approach speed, ``ut`` the slip of sphere 1's contact point relative to
    sphere 2's (tangential, signed). Sphere 2's changes are given in the same tangential
    direction (its contact point is on the side facing sphere 1).
    """
    inv2 = 0.0 if math.isinf(m2) else 1.0 / m2
    a = 1.0 / m1 + inv2
    b = a + r1 * r1 / i1 + (0.0 if math.isinf(i2) else r2 * r2 / i2)
    jn = (1.0 + e) * un / a
    jt = mu * jn
    s = 1.0 if ut > 0 else -1.0
    margin = abs(ut) / (jt * b) if jt > 0 else math.inf
    return Sliding(normal_impulse=jn, tangential_impulse=jt, margin=margin,
                   dv1=-s * jt / m1, dsurf1=-s * jt * r1 * r1 / i1,
                   dv2=s * jt * inv2,
                   dsurf2=0.0 if math.isinf(i2) else s * jt * r2 * r2 / i2)


def effective_shear(e1: float, nu1: float, e2: float = math.inf, nu2: float = 0.0) -> float:
    """G* = 1 / (2 (2 - nu1)(1 + nu1)/E1 + 2 (2 - nu2)(1 + nu2)/E2) (Mindlin's; a rigid
    plane by default)."""
    inv = 2.0 * (2.0 - nu1) * (1.0 + nu1) / e1
    if not math.isinf(e2):
        inv += 2.0 * (2.0 - nu2) * (1.0 + nu2) / e2
    return 1.0 / inv


def mindlin_no_slip(mass: float, radius: float, estar: float, gstar: float,
                    speed: float, arm: float = 0.5) -> float:
    """Slip after / slip before of a sphere hitting a rigid plane with a Hertz normal force
    and a Mindlin tangential spring that never slides (mu -> infinity), no damping.

    The ODE (scipy, DOP853, rtol 1e-11): m d'' = -4/3 E* sqrt(R) d^(3/2); the spring
    s' = v_t - w a collects the contact point's slip, F_t = -8 G* sqrt(R d) s acts on the
    sphere at the contact point, a = R - ``arm`` d from the centre (dpm puts it at
    R - d/2): m v_t' = F_t, I w' = -a F_t, I = 2/5 m R^2. The answer does not depend on the
    initial slip (the problem is linear in it).
    """
    from scipy.integrate import solve_ivp

    inertia = 0.4 * mass * radius**2
    kn = 4.0 / 3.0 * estar * math.sqrt(radius)

    def rhs(_, y):
        d, dd, s, vt, w = y
        dp = max(d, 0.0)
        a = radius - arm * dp
        ft = -8.0 * gstar * math.sqrt(radius * dp) * s
        return [dd, -kn * dp**1.5 / mass, vt - w * a, ft / mass, -a * ft / inertia]

    def end(_, y):
        return y[0]

    end.terminal, end.direction = True, -1
    t = hertz_impact(mass, radius, estar, speed).duration
    sol = solve_ivp(rhs, (0.0, 2.0 * t), [1e-30 * radius, speed, 0.0, 1.0, 0.0], events=end,
                    rtol=1e-11, atol=1e-20, max_step=t / 2000, method="DOP853")
    return float(sol.y[3][-1] - sol.y[4][-1] * radius)
