"""Tangential spring-dashpot with history and a Coulomb limit (shared by the contact laws).

    s   <- P_n (s + v_t dt)                 (history, projected on the tangent plane)
    F_t  = -k_t s - c_t v_t
    if |F_t| > mu F_n:  F_t <- mu F_n F_t/|F_t|,  s <- -(F_t + c_t v_t) / k_t

Cundall & Strack (1979); the projection and the rescaling of the spring on sliding are
those of LAMMPS/LIGGGHTS ``tangential history``.
"""

import math

from .config import jit


@jit
def spring_coulomb(kt, ct, mu, fn, vtx, vty, vtz, nx, ny, nz, dt, hist, k):
    """Update ``hist[k, 0:3]`` (tangential displacement) and return (ftx, fty, ftz)."""
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
    fmax = mu * fn
    if ft > fmax:
        if ft > 0.0:
            r = fmax / ft
            ftx *= r
            fty *= r
            ftz *= r
        if kt > 0.0:
            sx = -(ftx + ct * vtx) / kt
            sy = -(fty + ct * vty) / kt
            sz = -(ftz + ct * vtz) / kt
        else:
            sx = 0.0
            sy = 0.0
            sz = 0.0
    hist[k, 0] = sx
    hist[k, 1] = sy
    hist[k, 2] = sz
    return ftx, fty, ftz
