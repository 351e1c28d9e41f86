"""Quaternion kernels; q = (w, x, y, z), unit, rotating body frame to world frame."""

import math

from .config import jit


@jit
def rotate_by_angular_velocity(quat, i, wx, wy, wz, dt):
    """q_i <- exp(omega dt / 2) (x) q_i for a world-frame angular velocity, then renormalise.

    Exact for constant omega over the step; the renormalisation removes round-off drift.
    """
    w = math.sqrt(wx * wx + wy * wy + wz * wz)
    if w == 0.0:
        return
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
