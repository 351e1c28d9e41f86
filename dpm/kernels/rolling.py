"""Rolling resistance parts, and the torque of monolithic laws' fixed slots 5-7.

:func:`constant_torque` and :func:`epsd` are the numba functions of the rolling parts
(:class:`dpm.impact.parts.RollingPart`), called by a composed law as
``f(q, fn, reff, meff, wx, wy, wz, dt, hist, k, h) -> torque on i`` (q: the part's slots of
the pair row, h: the offset of its history). :func:`rolling_torque` serves monolithic laws
(``ImpactModel.kernel``): their pair row carries the model in slot 6.

Model 1, constant torque (DPM thesis eq. 2.53 with the unit vector, Zhou et al. 1999):
    T_r = -mu_r F_n R* w_rel / |w_rel|,   w_rel = w_i - w_j
A rolling sphere decelerates at 5/7 mu_r g and stops after 7 v0^2 / (10 mu_r g), but at rest
the torque keeps flipping with the sign of w (it never lets a heap settle exactly).

Model 2, elastic-plastic spring-dashpot (EPSD, "type C" of Ai, Chen, Rotter & Ooi 2011,
Powder Technol. 206, 269; Iwashita & Oda 1998 for the spring):
    k_r  = 2.25 mu_r^2 R*^2 k_n                       rolling stiffness
    M_k <- M_k - k_r w_rel dt,  |M_k| <= M_m = mu_r R* max(F_n, 0)   (spring, plastic limit)
    M_d  = -eta_r C_crit w_rel while |M_k| < M_m, 0 at the plastic limit,
    C_crit = 2 sqrt(I_r k_r),  I_r = 7/5 m* R*^2 (exact for a sphere on a wall)
    T_r  = M_k + M_d
Under full mobilisation it is the constant torque of model 1; below it a spring that holds a
static moment, so a sphere on a slope tan(theta) < mu_r and a heap come to rest.
Part slots: constant torque (mu_r); EPSD (mu_r, k_n, eta_r), k_n a representative normal
stiffness from the impact model's normal part; history: M_k (3 floats). Monolithic laws:
slot 5 k_n, slot 6 the model (2 + eta_r for EPSD), slot 7 mu_r; history 3..5 M_k.
The kernel sees the whole relative angular velocity (the contact normal is not passed), so
the spring also resists twisting, as model 1 does.
"""

import math

from .config import inline_jit

ROLLING_NONE = 0
ROLLING_CONSTANT_TORQUE = 1
ROLLING_EPSD = 2


@inline_jit
def constant_torque(q, fn, reff, meff, wx, wy, wz, dt, hist, k, h):
    """Model 1: T_r = -mu_r F_n R* w_rel / |w_rel|. q = (mu_r,)."""
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    if w == 0.0 or fn <= 0.0:
        return 0.0, 0.0, 0.0
    t = q[0] * fn * reff / w
    return -t * wx, -t * wy, -t * wz


@inline_jit
def epsd(q, fn, reff, meff, wx, wy, wz, dt, hist, k, h):
    """Model 2, elastic-plastic spring-dashpot; q = (mu_r, k_n, eta_r), M_k in
    ``hist[k, h:h+3]``."""
    mu_r = q[0]
    kr = 2.25 * mu_r * mu_r * reff * reff * q[1]
    mx = hist[k, h] - kr * wx * dt
    my = hist[k, h + 1] - kr * wy * dt
    mz = hist[k, h + 2] - kr * wz * dt
    mm = mu_r * reff * max(fn, 0.0)
    mk = math.sqrt(mx * mx + my * my + mz * mz)
    cr = 0.0
    if mk >= mm:
        if mk > 0.0:
            r = mm / mk
            mx *= r
            my *= r
            mz *= r
    else:
        cr = 2.0 * q[2] * math.sqrt(1.4 * meff * reff * reff * kr)
    hist[k, h] = mx
    hist[k, h + 1] = my
    hist[k, h + 2] = mz
    return mx - cr * wx, my - cr * wy, mz - cr * wz


@inline_jit
def rolling_torque(p, fn, reff, meff, wx, wy, wz, dt, hist, k):
    """Torque (x, y, z) on element i's body from the rolling resistance of a monolithic
    law's pair row ``p`` (model in slot 6); j gets the opposite."""
    model = int(p[6])
    if model == ROLLING_CONSTANT_TORQUE:
        return constant_torque((p[7],), fn, reff, meff, wx, wy, wz, dt, hist, k, 3)
    if model == ROLLING_EPSD:
        return epsd((p[7], p[5], p[6] - ROLLING_EPSD), fn, reff, meff, wx, wy, wz, dt, hist, k,
                    3)
    return 0.0, 0.0, 0.0
