"""JKR adhesive elastic contact (Johnson, Kendall & Roberts 1971) with Tsuji-type damping and
the Thornton & Yin (1991) friction limit.

The contact radius a and the overlap d are tied by (E* effective Young's modulus, R*
effective radius, W the work of adhesion, 2 gamma for two like surfaces)::

    d   = a^2 / R* - sqrt(2 pi W a / E*)                       (JKR, stable branch)
    F_e = 4 E* a^3 / (3 R*) - sqrt(8 pi W E* a^3)               (positive: repulsive)

Under force control the pair separates at the largest tension, the pull-off force
F_c = 3/2 pi W R* (at a_c = (9 pi W R*^2 / (8 E*))^(1/3)); under displacement control it
breaks at the critical negative overlap

    d_c = -3 a_f^2 / R* = -3/4 (pi^2 W^2 R* / E*^2)^(1/3),   a_f = (pi W R*^2 / (8 E*))^(1/3),

with F(d_c) = -5/9 F_c. Approaching bodies make contact at d = 0 (the neck snaps on: the
force jumps to F(0) = -8/9 F_c) and keep it, at negative overlap, until d < d_c: the force
is hysteretic, so a pair carries a flag in its history (set while attached), and the
engine looks for contacts as far as the scene's largest |d_c| beyond touching (the
interaction range of :class:`dpm.impact.jkr.JKRNormal`). The energy lost in one loop,
-int_{d_c}^{0} F dd, sets the critical sticking speed of an elastic impact
(Thornton & Ning 1998).

a(d) is the root x^2 of x^4 / R* - c x - d = 0 (x = sqrt(a), c = sqrt(2 pi W / E*)) on the
stable branch x >= x_f (4 x_f^3 = R* c): Newton from the right, x0 = (R* max(d, 0))^(1/4) +
(R* c)^(1/3), where the quartic is convex and increasing, so the iterates fall
monotonically to the root.

Damping (EDEM's "Hertz-Mindlin with JKR"; Tsuji et al. 1992 with the contact radius):
F_d = 2 sqrt(5/6) beta sqrt(S_n m*) d', S_n = 2 E* a, beta from the restitution as in
Hertz-Mindlin. Tangential: Mindlin's spring k_t = 8 G* a, dashpot 2 sqrt(5/6) beta
sqrt(k_t m*), Coulomb limit mu (F_n + 2 F_c) (Thornton & Yin 1991: friction sees the
load the adhesive neck adds).

Parts (:mod:`dpm.impact.parts`): normal ``jkr_normal`` q = (E*, W, beta), history 1 float
(the attached flag); ``jkr_attached`` q the same; tangential ``jkr_tangential``
q = (G*, beta, mu, E*, W).
"""

import math

from .config import inline_jit
from .tangential import spring_coulomb_at

SQRT_5_6 = math.sqrt(5.0 / 6.0)


@inline_jit
def jkr_contact_radius(delta, reff, estar, w):
    """Contact radius a of the JKR stable branch at overlap ``delta`` (delta >= d_c)."""
    c = math.sqrt(2.0 * math.pi * w / estar)
    x = (reff * max(delta, 0.0)) ** 0.25 + (reff * c) ** (1.0 / 3.0)
    for _ in range(60):
        x3 = x * x * x
        f = x3 * x / reff - c * x - delta
        g = 4.0 * x3 / reff - c
        if g <= 0.0:  # at the branch point (delta = d_c): the root is x_f
            break
        dx = f / g
        x -= dx
        if dx <= 1e-15 * x:
            break
    return x * x


@inline_jit
def jkr_critical_overlap(estar, w, reff):
    """d_c = -3/4 (pi^2 W^2 R* / E*^2)^(1/3) (negative)."""
    return -0.75 * (math.pi * math.pi * w * w * reff / (estar * estar)) ** (1.0 / 3.0)


@inline_jit
def jkr_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """F_n = 4 E* a^3/(3 R*) - sqrt(8 pi W E* a^3) + 2 sqrt(5/6) beta sqrt(2 E* a m*) d';
    q = (E*, W, beta); k_n = S_n = 2 E* a. Marks the pair attached (hist[k, h] = 1)."""
    estar = q[0]
    w = q[1]
    a = jkr_contact_radius(delta, reff, estar, w)
    a3 = a * a * a
    sn = 2.0 * estar * a
    fn = 4.0 * estar * a3 / (3.0 * reff) - math.sqrt(8.0 * math.pi * w * estar * a3)
    fn += 2.0 * SQRT_5_6 * q[2] * math.sqrt(sn * meff) * ddelta
    hist[k, h] = 1.0
    return fn, sn


@inline_jit
def jkr_attached(q, delta, reff, hist, k, h):
    """Whether a pair at negative overlap ``delta`` is still in contact: it touched since it
    last separated (the flag) and delta > d_c."""
    return hist[k, h] != 0.0 and delta > jkr_critical_overlap(q[0], q[1], reff)


@inline_jit
def jkr_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k, h):
    """Mindlin spring k_t = 8 G* a (a = S_n / (2 E*)), Tsuji dashpot, Coulomb limit
    mu (F_n + 2 F_c), F_c = 3/2 pi W R* (Thornton & Yin 1991). q = (G*, beta, mu, E*, W)."""
    a = kn / (2.0 * q[3])
    kt = 8.0 * q[0] * a
    ct = 2.0 * SQRT_5_6 * q[1] * math.sqrt(kt * meff)
    load = fn + 3.0 * math.pi * q[4] * reff
    return spring_coulomb_at(kt, ct, q[2], load, vtx, vty, vtz, nx, ny, nz, dt, hist, k, h)
