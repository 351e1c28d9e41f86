"""Quaternion kernels; q = (w, x, y, z), unit, rotating body frame to world frame."""


from .config import jit


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
