"""Velocity Verlet (Swope et al. 1982), second order, symplectic for conservative forces.

    v_{n+1/2} = v_n + dt/2 F_n / m            omega_{n+1/2} = omega_n + dt/2 T_n / I
    x_{n+1}   = x_n + dt v_{n+1/2}            q_{n+1} = exp(omega_{n+1/2} dt / 2) q_n
    F_{n+1}   = F(x_{n+1}, v_{n+1/2})         (velocity-dependent forces see v_{n+1/2})
    v_{n+1}   = v_{n+1/2} + dt/2 F_{n+1} / m  omega_{n+1} = omega_{n+1/2} + dt/2 T_{n+1} / I

The same splitting as LAMMPS/LIGGGHTS ``nve/sphere``. Exact for constant acceleration.
Rotation in the world frame with a scalar moment of inertia (spheres).
"""

from .config import jit
from .quaternion import rotate_by_angular_velocity


@jit
def pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt):
    """Half kick and drift."""
    h = 0.5 * dt
    im = invmass[i]
    for d in range(3):
        vel[i, d] += h * force[i, d] * im
        pos[i, d] += dt * vel[i, d]
    ii = invinertia[i, 0]
    for d in range(3):
        angvel[i, d] += h * torque[i, d] * ii
    rotate_by_angular_velocity(quat, i, angvel[i, 0], angvel[i, 1], angvel[i, 2], dt)


@jit
def post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt):
    """Second half kick."""
    h = 0.5 * dt
    im = invmass[i]
    ii = invinertia[i, 0]
    for d in range(3):
        vel[i, d] += h * force[i, d] * im
        angvel[i, d] += h * torque[i, d] * ii
