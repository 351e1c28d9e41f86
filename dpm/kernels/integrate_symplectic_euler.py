"""Symplectic (semi-implicit) Euler, first order (Hairer, Lubich & Wanner 2006, §I.1).

    v_{n+1} = v_n + dt F(x_n, v_n) / m        omega_{n+1} = omega_n + dt T_n / I
    x_{n+1} = x_n + dt v_{n+1}                q_{n+1} = exp(omega_{n+1} dt / 2) q_n

All work happens after the force evaluation, which sees the current velocities v_n.
Rotation of isotropic bodies: the same kick-drift in the world frame, exact free rotation.
Other bodies: the DPM thesis' quaternion-derivative form (Euler's equations and
q' = q (x) (0, w_b) / 2 by explicit Euler, q renormalised; :mod:`.rigid_rotation`).

An integrator module gives two per-body functions that the step calls inside its own
parallel loops over bodies: ``pre_force_body`` (before the forces of the step; it also sets
``vf``, ``wf``, the velocities that velocity-dependent forces see) and ``post_force_body``
(after them).
"""

from .config import inline_jit
from .rigid_rotation import rotate_isotropic, rotate_quaternion_derivative


@inline_jit
def pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, vf, wf, aux):
    """Forces see v_n and omega_n."""
    for d in range(3):
        vf[i, d] = vel[i, d]
        wf[i, d] = angvel[i, d]


@inline_jit
def post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    """Kick then drift with the new velocity."""
    im = invmass[i]
    for d in range(3):
        vel[i, d] += dt * force[i, d] * im
        pos[i, d] += dt * vel[i, d]
    i0 = invinertia[i, 0]
    i1 = invinertia[i, 1]
    i2 = invinertia[i, 2]
    q0 = quat[i, 0]
    q1 = quat[i, 1]
    q2 = quat[i, 2]
    q3 = quat[i, 3]
    if i0 == i1 and i1 == i2:
        wx = angvel[i, 0] + dt * torque[i, 0] * i0
        wy = angvel[i, 1] + dt * torque[i, 1] * i0
        wz = angvel[i, 2] + dt * torque[i, 2] * i0
        q0, q1, q2, q3 = rotate_isotropic(q0, q1, q2, q3, wx, wy, wz, dt)
    else:
        q0, q1, q2, q3, wx, wy, wz = rotate_quaternion_derivative(
            q0, q1, q2, q3, angvel[i, 0], angvel[i, 1], angvel[i, 2], torque[i, 0],
            torque[i, 1], torque[i, 2], i0, i1, i2, dt)
    angvel[i, 0] = wx
    angvel[i, 1] = wy
    angvel[i, 2] = wz
    quat[i, 0] = q0
    quat[i, 1] = q1
    quat[i, 2] = q2
    quat[i, 3] = q3
