"""Quaternion kernels; q = (w, x, y, z), unit, rotating body frame to world frame."""

import math

from .config import jit


@jit
def rotate_by_angular_velocity(quat, i, wx, wy, wz, dt):
    """q_i <- exp(omega dt / 2) (x) q_i for a world-frame angular velocity, then renormalise.

    Exact for constant omega over the step (rotation by |omega| dt about omega/|omega|);
    the renormalisation removes round-off drift. For a rotation angle below 0.1 rad per step
    cos and sin are replaced by their Taylor series to the h^8 term (relative error below
    1e-16), which spares two transcendental calls per body and step.
    """
    w2 = wx * wx + wy * wy + wz * wz
    if w2 == 0.0:
        return
    h2 = 0.25 * w2 * dt * dt  # (half angle)^2
    if h2 < 0.0025:  # half angle < 0.05 rad
        a0 = 1.0 - h2 / 2.0 * (1.0 - h2 / 12.0 * (1.0 - h2 / 30.0 * (1.0 - h2 / 56.0)))
        s = 0.5 * dt * (1.0 - h2 / 6.0 * (1.0 - h2 / 20.0 * (1.0 - h2 / 42.0
                                                           * (1.0 - h2 / 72.0))))
    else:
        w = math.sqrt(w2)
        half = 0.5 * w * dt
        s = math.sin(half) / w
        a0 = math.cos(half)
    a1 = wx * s
    a2 = wy * s
    a3 = wz * s
    b0 = quat[i, 0]
    b1 = quat[i, 1]
    b2 = quat[i, 2]
    b3 = quat[i, 3]
    q0 = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    q1 = a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2
    q2 = a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1
    q3 = a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0
    n = 1.0 / math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    quat[i, 0] = q0 * n
    quat[i, 1] = q1 * n
    quat[i, 2] = q2 * n
    quat[i, 3] = q3 * n


@jit
def rotate_vector(quat, i, vx, vy, vz):
    """Return R(q_i) v (body frame to world frame)."""
    w = quat[i, 0]
    x = quat[i, 1]
    y = quat[i, 2]
    z = quat[i, 3]
    # t = 2 q_vec x v ; v' = v + w t + q_vec x t
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty),
            vy + w * ty + (z * tx - x * tz),
            vz + w * tz + (x * ty - y * tx))
