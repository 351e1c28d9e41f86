"""Rotation parts shared by integrators that rotate like velocity Verlet.

Kick-rotate-kick on the angular momentum (see :mod:`.integrate_velocity_verlet`): the exact
world-frame rotation for isotropic bodies, the DLM splitting otherwise (:mod:`.rigid_rotation`).
Velocity Verlet, position Verlet and the Gear predictor-correctors all take their
rotation from this module.
"""

from .config import inline_jit
from .rigid_rotation import kick, kick_and_rotate_dlm, rotate_isotropic


@inline_jit
def rotation_first_half(i, quat, angvel, torque, invinertia, dt, wf):
    """Half kick of L with T_n, free rotation over dt; wf[i] = predicted omega_{n+1}."""
    h = 0.5 * dt
    i0 = invinertia[i, 0]
    i1 = invinertia[i, 1]
    i2 = invinertia[i, 2]
    tx = torque[i, 0]
    ty = torque[i, 1]
    tz = torque[i, 2]
    q0 = quat[i, 0]
    q1 = quat[i, 1]
    q2 = quat[i, 2]
    q3 = quat[i, 3]
    if i0 == i1 and i1 == i2:
        wx = angvel[i, 0] + h * tx * i0
        wy = angvel[i, 1] + h * ty * i0
        wz = angvel[i, 2] + h * tz * i0
        q0, q1, q2, q3 = rotate_isotropic(q0, q1, q2, q3, wx, wy, wz, dt)
        px = wx + h * tx * i0
        py = wy + h * ty * i0
        pz = wz + h * tz * i0
    else:
        q0, q1, q2, q3, wx, wy, wz = kick_and_rotate_dlm(
            q0, q1, q2, q3, angvel[i, 0], angvel[i, 1], angvel[i, 2], tx, ty, tz, i0, i1, i2,
            h, dt)
        px, py, pz = kick(q0, q1, q2, q3, wx, wy, wz, tx, ty, tz, i0, i1, i2, h)
    angvel[i, 0] = wx
    angvel[i, 1] = wy
    angvel[i, 2] = wz
    wf[i, 0] = px
    wf[i, 1] = py
    wf[i, 2] = pz
    quat[i, 0] = q0
    quat[i, 1] = q1
    quat[i, 2] = q2
    quat[i, 3] = q3


@inline_jit
def rotation_second_half(i, quat, angvel, torque, invinertia, dt):
    """Second half kick of L with T_{n+1}."""
    h = 0.5 * dt
    i0 = invinertia[i, 0]
    i1 = invinertia[i, 1]
    i2 = invinertia[i, 2]
    if i0 == i1 and i1 == i2:
        for d in range(3):
            angvel[i, d] += h * torque[i, d] * i0
    else:
        wx, wy, wz = kick(quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3], angvel[i, 0],
                          angvel[i, 1], angvel[i, 2], torque[i, 0], torque[i, 1],
                          torque[i, 2], i0, i1, i2, h)
        angvel[i, 0] = wx
        angvel[i, 1] = wy
        angvel[i, 2] = wz
