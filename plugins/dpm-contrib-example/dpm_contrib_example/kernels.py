"""numba functions of the contributed contact parts (imports only math and dpm's kernel
config: this code becomes part of the step module dpm generates for a scene).

Normal part (``f(q, delta, ddelta, meff, reff, dt, hist, k, h) -> (F_n, k_n)``):

    F_n = k_n d + 2 zeta sqrt(m* k_n) d'        (Kelvin-Voigt; not cut off at zero)

Tangential part (``f(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt, hist, k,
h) -> F_t``):

    F_t = -min(2 zeta_t sqrt(m* k_n) |v_t|, mu max(F_n, 0)) v_t / |v_t|
"""

import math

from dpm.kernels.config import inline_jit


@inline_jit
def kelvin_voigt_normal(q, delta, ddelta, meff, reff, dt, hist, k, h):
    """q = (k_n, zeta); returns (F_n, k_n)."""
    kn = q[0]
    return kn * delta + 2.0 * q[1] * math.sqrt(meff * kn) * ddelta, kn


@inline_jit
def viscous_coulomb_tangential(q, fn, kn, delta, vtx, vty, vtz, nx, ny, nz, meff, reff, dt,
                               hist, k, h):
    """q = (zeta_t, mu); no history."""
    vt = math.sqrt(vtx * vtx + vty * vty + vtz * vtz)
    if vt == 0.0:
        return 0.0, 0.0, 0.0
    ft = min(2.0 * q[0] * math.sqrt(meff * kn) * vt, q[1] * max(fn, 0.0))
    return -ft * vtx / vt, -ft * vty / vt, -ft * vtz / vt
