"""Tangential contact parts: spring-dashpots with history and a Coulomb limit.

Every function here but :func:`spring_coulomb` is the numba function of a tangential part
(:class:`dpm.impact.parts.TangentialPart`), called by the composed law as

    f(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k, h) -> F_t

q: the part's own slots of the pair row (a tuple, in the order the part declares them),
fn: the repulsive normal force (before any adhesion), kn: the normal part's stiffness
(linear laws their k_n, Hertz laws S_n = 2 E* sqrt(R* d)), h: the offset of the part's
history floats in ``hist[k]``. The shared spring:

    s   <- P_n (s + v_t dt)                  (history, projected on the tangent plane)
    s   <- s min(1, mu F_n / (k_t |s|))      (the spring alone never exceeds mu F_n)
    F_t  = -k_t s - c_t v_t,  F_t <- F_t min(1, mu F_n / |F_t|)   (spring + dashpot)

Cundall & Strack (1979). Sliding only ever shortens the spring: it keeps at most the
displacement the relative motion gave it, so the elastic energy it stores, k_t |s|^2 / 2,
is never more than the work it received, and a sliding contact dissipates. The earlier
reset s = -F_t/k_t, with F_t the clipped total (spring + dashpot), lengthened the spring
whenever the dashpot had pushed the total over mu F_n: the spring was loaded with the
dashpot's force, energy the contact never received, and gave it back as the contact
unloaded (a tangential dashpot then added energy to a sliding contact: docs/validation.md,
Findings). LIGGGHTS (``tangential history``) clips the spring the same way, testing the
spring alone against mu F_n, but adds the dashpot only while the spring sticks, unclipped;
here the total is clipped as well, so |F_t| <= mu F_n always. (LAMMPS' older form and
MercuryDPM store s = -(F_t + c_t v_t)/k_t, which loses 11-21 % of the sliding friction
impulse of a Hertz-Mindlin oblique impact: the oblique-impact tests of
tests/physics/test_impact_models.py fail with it.)
"""

import math

from .config import inline_jit

SQRT_5_6 = math.sqrt(5.0 / 6.0)


@inline_jit
def spring_coulomb(kt, ct, mu, fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k):
    """:func:`spring_coulomb_at` with the spring in ``hist[k, 0:3]`` (the fixed layout of
    monolithic laws)."""
    return spring_coulomb_at(kt, ct, mu, fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k, 0)


@inline_jit
def spring_coulomb_at(kt, ct, mu, fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k, h):
    """Tangential spring-dashpot with history in ``hist[k, h:h+3]`` and Coulomb limit.

        s   <- P_n (s + v_t dt)                   (projected on the tangent plane)
        s   <- s min(1, mu F_n / (k_t |s|))       (sliding shortens the spring, never
                                                   lengthens it)
        F_t  = -k_t s - c_t v_t,  F_t <- F_t min(1, mu F_n / |F_t|)
    """
    sx = hist[k, h] + vtx * dt
    sy = hist[k, h + 1] + vty * dt
    sz = hist[k, h + 2] + vtz * dt
    sn = sx * nx + sy * ny + sz * nz
    sx -= sn * nx
    sy -= sn * ny
    sz -= sn * nz
    fmax = mu * max(fn, 0.0)
    fmax2 = fmax * fmax
    ks2 = kt * kt * (sx * sx + sy * sy + sz * sz)
    if ks2 > fmax2:  # the spring alone exceeds the limit: shorten it to carry mu F_n
        r = fmax / math.sqrt(ks2)
        sx *= r
        sy *= r
        sz *= r
    ftx = -kt * sx - ct * vtx
    fty = -kt * sy - ct * vty
    ftz = -kt * sz - ct * vtz
    ft2 = ftx * ftx + fty * fty + ftz * ftz
    if ft2 > fmax2:  # (squares: a sticking contact needs no square root)
        r = fmax / math.sqrt(ft2)
        ftx *= r
        fty *= r
        ftz *= r
    hist[k, h] = sx
    hist[k, h + 1] = sy
    hist[k, h + 2] = sz
    return ftx, fty, ftz


@inline_jit
def linear_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k, h):
    """Linear spring-dashpot family (Cundall & Strack 1979; DPM thesis §2.6.1):
    k_t = kappa k_n, c_t = 2 zeta_t sqrt(m* k_n), Coulomb limit mu F_n.
    q = (mu, kappa, zeta_t); history: the spring (3 floats)."""
    return spring_coulomb_at(q[1] * kn, 2.0 * q[2] * math.sqrt(meff * kn), q[0], fn, vtx, vty,
                             vtz, nx, ny, nz, dt, hist, k, h)


@inline_jit
def maw_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k, h):
    """Maw's tangential spring-dashpot (DPM thesis eqs. 2.33-2.34): k_t = kappa k_n,
    c_t = 2 zeta_t sqrt(m* k_t), Coulomb limit mu F_n. q = (mu, kappa, zeta_t)."""
    kt = q[1] * kn
    return spring_coulomb_at(kt, 2.0 * q[2] * math.sqrt(meff * kt), q[0], fn, vtx, vty, vtz,
                             nx, ny, nz, dt, hist, k, h)


@inline_jit
def mindlin_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k,
                       h):
    """Mindlin no-slip spring (Mindlin 1949) k_t = 8 G* sqrt(R* d) with the dashpot
    c_t = 2 zeta_t sqrt(m* k_t), Coulomb limit mu F_n. q = (G*, mu, zeta_t)."""
    kt = 8.0 * q[0] * math.sqrt(reff * delta)
    return spring_coulomb_at(kt, 2.0 * q[2] * math.sqrt(kt * meff), q[1], fn, vtx, vty, vtz,
                             nx, ny, nz, dt, hist, k, h)


@inline_jit
def mindlin_tsuji_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist,
                             k, h):
    """Mindlin spring k_t = 8 G* sqrt(R* d) with Tsuji's dashpot c_t = 2 sqrt(5/6) beta
    sqrt(k_t m*) (Tsuji et al. 1992; LIGGGHTS ``tangential history``), Coulomb limit mu F_n.
    q = (G*, beta, mu)."""
    kt = 8.0 * q[0] * math.sqrt(reff * delta)
    ct = 2.0 * SQRT_5_6 * q[1] * math.sqrt(kt * meff)
    return spring_coulomb_at(kt, ct, q[2], fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k, h)
