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

from .config import jit
from .quaternion import rotate_by_angular_velocity
from .rigid_rotation import isotropic, rotate_quaternion_derivative


@jit
def pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, vf, wf):
    """Forces see v_n and omega_n."""
    for d in range(3):
        vf[i, d] = vel[i, d]
        wf[i, d] = angvel[i, d]


@jit
def post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt):
    """Kick then drift with the new velocity."""
    im = invmass[i]
    for d in range(3):
        vel[i, d] += dt * force[i, d] * im
        pos[i, d] += dt * vel[i, d]
    if isotropic(invinertia, i):
        ii = invinertia[i, 0]
        for d in range(3):
            angvel[i, d] += dt * torque[i, d] * ii
        rotate_by_angular_velocity(quat, i, angvel[i, 0], angvel[i, 1], angvel[i, 2], dt)
    else:
        rotate_quaternion_derivative(quat, angvel, torque, invinertia, i, dt)
