"""Hertz-Mindlin contact law with Tsuji-type damping (as in LIGGGHTS ``hertz``/``history``).

Normal (Hertz 1882; damping Tsuji et al. 1992, Antypov & Elliott 2011):
    a      = sqrt(R* delta)
    k_n    = 4/3 E* a           F_n = max(0, k_n delta + c_n delta')
    S_n    = 2 E* a             c_n = 2 sqrt(5/6) beta sqrt(S_n m*)
Tangential (Mindlin 1949, no-slip stiffness):
    k_t    = 8 G* a             c_t = 2 sqrt(5/6) beta sqrt(k_t m*)
    spring with history and Coulomb limit mu F_n (:func:`spring_coulomb_slip`)
beta is solved in the object layer so that the restitution with the attractive force cut
off is the one set (:func:`dpm.impact.collision.tsuji_beta_for_restitution`).

Sliding: when |-(k_t s + c_t v_t)| exceeds mu F_n the force is set to the Coulomb limit and
the spring to s = -F_t / k_t, i.e. the spring alone carries the sliding force and the
dashpot rests, as in LIGGGHTS ``tangential history`` and Yade's Mindlin law.
(:func:`dpm.kernels.tangential.spring_coulomb`, LAMMPS' form, stores s = -(F_t + c_t v_t)/k_t;
with k_t and c_t growing with the overlap the stored spring then pulls the force below the
limit while the contact slides: an oblique impact far in the sliding regime, tan(psi) = 8 x
the sticking limit, lost 11 % of its friction impulse at e = 0.5.)

pair_params row: [E*, G*, beta, mu, 0, 0, rolling model, mu_r]
(slots 6, 7: rolling resistance model and coefficient, read by the step)
"""

import math

from .config import jit

SQRT_5_6 = math.sqrt(5.0 / 6.0)


@jit
def spring_coulomb_slip(kt, ct, mu, fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k):
    """Tangential spring-dashpot with history in ``hist[k, 0:3]`` and Coulomb limit.

        s   <- P_n (s + v_t dt)                   (projected on the tangent plane)
        F_t  = -k_t s - c_t v_t
        if |F_t| > mu F_n:  F_t <- mu F_n F_t/|F_t|,  s <- -F_t / k_t   (sliding)
    """
    sx = hist[k, 0] + vtx * dt
    sy = hist[k, 1] + vty * dt
    sz = hist[k, 2] + vtz * dt
    sn = sx * nx + sy * ny + sz * nz
    sx -= sn * nx
    sy -= sn * ny
    sz -= sn * nz
    ftx = -kt * sx - ct * vtx
    fty = -kt * sy - ct * vty
    ftz = -kt * sz - ct * vtz
    ft = math.sqrt(ftx * ftx + fty * fty + ftz * ftz)
    fmax = mu * max(fn, 0.0)
    if ft > fmax:
        r = fmax / ft
        ftx *= r
        fty *= r
        ftz *= r
        if kt > 0.0:
            sx = -ftx / kt
            sy = -fty / kt
            sz = -ftz / kt
        else:
            sx = 0.0
            sy = 0.0
            sz = 0.0
    hist[k, 0] = sx
    hist[k, 1] = sy
    hist[k, 2] = sz
    return ftx, fty, ftz


@jit
def hertz_mindlin(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    """Return (F_n, F_t x, y, z) on element i for overlap ``delta`` and rate ``ddelta``."""
    a = math.sqrt(reff * delta)
    kn = 4.0 / 3.0 * p[0] * a
    cn = 2.0 * SQRT_5_6 * p[2] * math.sqrt(2.0 * p[0] * a * meff)
    fn = kn * delta + cn * ddelta
    if fn < 0.0:
        fn = 0.0
    kt = 8.0 * p[1] * a
    ct = 2.0 * SQRT_5_6 * p[2] * math.sqrt(kt * meff)
    ftx, fty, ftz = spring_coulomb_slip(kt, ct, p[3], fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k)
    return fn, ftx, fty, ftz
