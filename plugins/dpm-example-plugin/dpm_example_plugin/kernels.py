"""numba kernel of the linear_viscous law (imports only math, numba and dpm's kernel config).

    F_n = max(0, k_n d + 2 zeta sqrt(m* k_n) d')
    F_t = -min(c_t |v_t|, mu F_n) v_t / |v_t|,   c_t = 2 zeta_t sqrt(m* k_n)

pair_params row: [k_n, zeta, mu, zeta_t, 0, 0, rolling model, mu_r]
"""

import math

from dpm.kernels.config import inline_jit


@inline_jit
def linear_viscous(p, delta, ddelta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k):
    kn = p[0]
    root = math.sqrt(meff * kn)
    fn = kn * delta + 2.0 * p[1] * root * ddelta
    if fn < 0.0:
        fn = 0.0
    vt = math.sqrt(vtx * vtx + vty * vty + vtz * vtz)
    if vt == 0.0:
        return fn, 0.0, 0.0, 0.0
    ft = min(2.0 * p[3] * root * vt, p[2] * fn)
    return fn, -ft * vtx / vt, -ft * vty / vt, -ft * vtz / vt
