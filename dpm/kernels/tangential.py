"""Tangential spring-dashpot with history and a Coulomb limit (shared by the contact laws).

    s   <- P_n (s + v_t dt)                 (history, projected on the tangent plane)
    F_t  = -k_t s - c_t v_t
    if |F_t| > mu F_n:  F_t <- mu F_n F_t/|F_t|,  s <- -F_t / k_t   (sliding)

Cundall & Strack (1979). While sliding the spring alone carries mu F_n and the dashpot
rests, as in LIGGGHTS and Yade. (LAMMPS' older form stores s = -(F_t + c_t v_t)/k_t, which
loses 11-21 % of the sliding friction impulse of a Hertz-Mindlin oblique impact: the
oblique-impact tests of tests/test_impact_models.py fail with it.)
"""

import math

from .config import inline_jit


@inline_jit
def spring_coulomb(kt, ct, mu, fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k):
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
    ft2 = ftx * ftx + fty * fty + ftz * ftz
    fmax = mu * max(fn, 0.0)
    if ft2 > fmax * fmax:  # (squares: a sticking contact needs no square root)
        r = fmax / math.sqrt(ft2)
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
