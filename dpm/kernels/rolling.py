"""Rolling resistance torques, chosen per material pair by ``pair_params[a, b, 6]``.

Model 1, constant torque (DPM thesis eq. 2.53 with the unit vector, Zhou et al. 1999):
    T_r = -mu_r F_n R* w_rel / |w_rel|,   w_rel = w_i - w_j
Slot 7 holds mu_r; history slots 3..5 of a contact are reserved for rolling models with a
spring (elastic-plastic spring-dashpot models).
"""

import math

from .config import jit

ROLLING_NONE = 0
ROLLING_CONSTANT_TORQUE = 1


@jit
def rolling_torque(p, fn, reff, meff, wx, wy, wz, dt, hist, k):
    """Torque (x, y, z) on element i's body from rolling resistance; j gets the opposite."""
    model = int(p[6])
    if model == ROLLING_CONSTANT_TORQUE:
        w = math.sqrt(wx * wx + wy * wy + wz * wz)
        if w == 0.0 or fn <= 0.0:
            return 0.0, 0.0, 0.0
        t = p[7] * fn * reff / w
        return -t * wx, -t * wy, -t * wz
    return 0.0, 0.0, 0.0
