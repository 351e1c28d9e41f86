"""Rotation of rigid bodies with principal moments of inertia (I1, I2, I3).

The body frame is the principal frame; q (w, x, y, z) rotates it into the world frame,
omega is kept in the world frame. Two schemes:

- :func:`kick_and_rotate_dlm` (used by velocity Verlet): the symmetric splitting of the free
  rigid body of Dullweber, Leimkuhler & McLachlan (1997, J. Chem. Phys. 107, 5840),
      R1(dt/2) R2(dt/2) R3(dt) R2(dt/2) R1(dt/2),
  where Rk(t) is the exact flow of the kinetic energy term L_k^2 / (2 I_k): a rotation of
  the body about its principal axis k by L_k t / I_k, with L (body frame) rotated back by the
  same angle. Symplectic, time-reversible, second order; conserves |L| exactly and the
  energy to O(dt^2) without drift.
- :func:`rotate_quaternion_derivative` (used by symplectic Euler): the DPM thesis form
  (Samiei 2012, §2.3): Euler's equations  I w_b' = T_b - w_b x (I w_b)  and
  q' = 1/2 q (x) (0, w_b), both advanced by explicit Euler, q renormalised each step
  (first order, not symplectic; the thesis' explicit scheme).

Isotropic bodies (spheres, cubes, regular tetrahedra: I1 = I2 = I3) take the exact world
frame update w += dt T / I, q <- exp(w dt / 2) q in both integrators.
"""

import math

from .config import jit
from .quaternion import rotate_vector


@jit
def isotropic(invinertia, i):
    return invinertia[i, 0] == invinertia[i, 1] and invinertia[i, 1] == invinertia[i, 2]


@jit
def to_body(quat, i, vx, vy, vz):
    """R(q_i)^T v (world to body frame)."""
    w = quat[i, 0]
    x = -quat[i, 1]
    y = -quat[i, 2]
    z = -quat[i, 3]
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty),
            vy + w * ty + (z * tx - x * tz),
            vz + w * tz + (x * ty - y * tx))


@jit
def _about_axis(quat, i, k, angle):
    """q_i <- q_i (x) (cos(a/2), sin(a/2) e_k): rotate the body about its own axis k."""
    c = math.cos(0.5 * angle)
    s = math.sin(0.5 * angle)
    q0 = quat[i, 0]
    q1 = quat[i, 1]
    q2 = quat[i, 2]
    q3 = quat[i, 3]
    if k == 0:
        quat[i, 0] = q0 * c - q1 * s
        quat[i, 1] = q1 * c + q0 * s
        quat[i, 2] = q2 * c + q3 * s
        quat[i, 3] = q3 * c - q2 * s
    elif k == 1:
        quat[i, 0] = q0 * c - q2 * s
        quat[i, 1] = q1 * c - q3 * s
        quat[i, 2] = q2 * c + q0 * s
        quat[i, 3] = q3 * c + q1 * s
    else:
        quat[i, 0] = q0 * c - q3 * s
        quat[i, 1] = q1 * c + q2 * s
        quat[i, 2] = q2 * c - q1 * s
        quat[i, 3] = q3 * c + q0 * s


@jit
def _free_flow(quat, i, k, l0, l1, l2, invinertia, t):
    """Exact flow of L_k^2/(2 I_k) for time t: the body turns by phi = L_k t / I_k about its
    axis k, and the body-frame angular momentum by -phi about the same axis."""
    lk = l0 if k == 0 else (l1 if k == 1 else l2)
    phi = lk * invinertia[i, k] * t
    _about_axis(quat, i, k, phi)
    c = math.cos(phi)
    s = math.sin(phi)
    if k == 0:
        return l0, c * l1 + s * l2, -s * l1 + c * l2
    if k == 1:
        return -s * l2 + c * l0, l1, c * l2 + s * l0
    return c * l0 + s * l1, -s * l0 + c * l1, l2


@jit
def body_momentum(quat, angvel, invinertia, i):
    """Body-frame angular momentum L_b = I R^T omega."""
    wx, wy, wz = to_body(quat, i, angvel[i, 0], angvel[i, 1], angvel[i, 2])
    return wx / invinertia[i, 0], wy / invinertia[i, 1], wz / invinertia[i, 2]


@jit
def set_world_omega(quat, angvel, invinertia, i, l0, l1, l2):
    """omega = R I^-1 L_b."""
    ox, oy, oz = rotate_vector(quat, i, l0 * invinertia[i, 0], l1 * invinertia[i, 1],
                               l2 * invinertia[i, 2])
    angvel[i, 0] = ox
    angvel[i, 1] = oy
    angvel[i, 2] = oz


@jit
def _kicked_momentum(quat, angvel, torque, invinertia, i, h_kick):
    l0, l1, l2 = body_momentum(quat, angvel, invinertia, i)
    tx, ty, tz = to_body(quat, i, torque[i, 0], torque[i, 1], torque[i, 2])
    return l0 + h_kick * tx, l1 + h_kick * ty, l2 + h_kick * tz


@jit
def kick_and_rotate_dlm(quat, angvel, torque, invinertia, i, h_kick, dt):
    """Half kick L += h_kick T (world), then the DLM free rotation over dt."""
    l0, l1, l2 = _kicked_momentum(quat, angvel, torque, invinertia, i, h_kick)
    l0, l1, l2 = _free_flow(quat, i, 0, l0, l1, l2, invinertia, 0.5 * dt)
    l0, l1, l2 = _free_flow(quat, i, 1, l0, l1, l2, invinertia, 0.5 * dt)
    l0, l1, l2 = _free_flow(quat, i, 2, l0, l1, l2, invinertia, dt)
    l0, l1, l2 = _free_flow(quat, i, 1, l0, l1, l2, invinertia, 0.5 * dt)
    l0, l1, l2 = _free_flow(quat, i, 0, l0, l1, l2, invinertia, 0.5 * dt)
    n = 1.0 / math.sqrt(quat[i, 0] ** 2 + quat[i, 1] ** 2 + quat[i, 2] ** 2 + quat[i, 3] ** 2)
    for c in range(4):
        quat[i, c] *= n
    set_world_omega(quat, angvel, invinertia, i, l0, l1, l2)


@jit
def kick(quat, angvel, torque, invinertia, i, h_kick):
    """L += h_kick T (world frame); omega follows at fixed orientation."""
    l0, l1, l2 = _kicked_momentum(quat, angvel, torque, invinertia, i, h_kick)
    set_world_omega(quat, angvel, invinertia, i, l0, l1, l2)


@jit
def kicked_omega(quat, angvel, torque, invinertia, i, h_kick):
    """omega after a further kick by h_kick T at fixed orientation (not stored)."""
    tx, ty, tz = to_body(quat, i, torque[i, 0], torque[i, 1], torque[i, 2])
    dx, dy, dz = rotate_vector(quat, i, h_kick * tx * invinertia[i, 0],
                               h_kick * ty * invinertia[i, 1], h_kick * tz * invinertia[i, 2])
    return angvel[i, 0] + dx, angvel[i, 1] + dy, angvel[i, 2] + dz


@jit
def rotate_quaternion_derivative(quat, angvel, torque, invinertia, i, dt):
    """One explicit Euler step of Euler's equations and of q' = q (x) (0, w_b) / 2."""
    wx, wy, wz = to_body(quat, i, angvel[i, 0], angvel[i, 1], angvel[i, 2])
    tx, ty, tz = to_body(quat, i, torque[i, 0], torque[i, 1], torque[i, 2])
    i1 = 1.0 / invinertia[i, 0]
    i2 = 1.0 / invinertia[i, 1]
    i3 = 1.0 / invinertia[i, 2]
    # q' = 1/2 q (x) (0, w_b) with the current w_b
    q0 = quat[i, 0]
    q1 = quat[i, 1]
    q2 = quat[i, 2]
    q3 = quat[i, 3]
    h = 0.5 * dt
    quat[i, 0] = q0 + h * (-q1 * wx - q2 * wy - q3 * wz)
    quat[i, 1] = q1 + h * (q0 * wx + q2 * wz - q3 * wy)
    quat[i, 2] = q2 + h * (q0 * wy + q3 * wx - q1 * wz)
    quat[i, 3] = q3 + h * (q0 * wz + q1 * wy - q2 * wx)
    n = 1.0 / math.sqrt(quat[i, 0] ** 2 + quat[i, 1] ** 2 + quat[i, 2] ** 2 + quat[i, 3] ** 2)
    for c in range(4):
        quat[i, c] *= n
    # Euler's equations
    nwx = wx + dt * (tx - (i3 - i2) * wy * wz) / i1
    nwy = wy + dt * (ty - (i1 - i3) * wz * wx) / i2
    nwz = wz + dt * (tz - (i2 - i1) * wx * wy) / i3
    ox, oy, oz = rotate_vector(quat, i, nwx, nwy, nwz)
    angvel[i, 0] = ox
    angvel[i, 1] = oy
    angvel[i, 2] = oz
