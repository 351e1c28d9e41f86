"""Velocity Verlet (Swope et al. 1982), second order, symplectic for conservative forces.

Translation:
    v_{n+1/2} = v_n + dt/2 F_n / m
    x_{n+1}   = x_n + dt v_{n+1/2}
    F_{n+1}   = F(x_{n+1}, v~_{n+1}),          v~_{n+1} = v_{n+1/2} + dt/2 F_n / m
    v_{n+1}   = v_{n+1/2} + dt/2 F_{n+1} / m
Rotation, the same kick-drift-kick on the angular momentum L = R I R^T omega:
    L_{n+1/2} = L_n + dt/2 T_n;  free rotation over dt;  L_{n+1} = L_{n+1/2} + dt/2 T_{n+1}
The free rotation is exact for isotropic bodies (q <- exp(omega dt / 2) q) and the
symplectic DLM splitting otherwise (:mod:`.rigid_rotation`).

The splitting of LAMMPS/LIGGGHTS ``nve/sphere``, exact for constant acceleration. Forces
that depend on velocity (dashpots, friction) see the predicted velocities v~_{n+1},
omega~_{n+1} ("velocity Verlet with prediction", Groot & Warren 1997, lambda = 1/2): with the
plain half-step velocity, as in LIGGGHTS, the dashpot is only first-order accurate (the
restitution of a linear contact at e = 0.2 is off by 0.9 % at 100 steps per contact; with
the prediction the error is second order).
"""

from .config import inline_jit
from .integrate_common import rotation_first_half, rotation_second_half


@inline_jit
def kick_and_drift(i, pos, vel, force, invmass, dt, vf):
    """v += dt/2 F/m, x += dt v, and the predicted velocity v + dt/2 F/m for the forces."""
    h = 0.5 * dt
    im = invmass[i]
    for d in range(3):
        dv = h * force[i, d] * im
        vel[i, d] += dv
        pos[i, d] += dt * vel[i, d]
        vf[i, d] = vel[i, d] + dv


@inline_jit
def pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, vf, wf, aux):
    """Half kick and drift; predicted velocities for the forces."""
    kick_and_drift(i, pos, vel, force, invmass, dt, vf)
    rotation_first_half(i, quat, angvel, torque, invinertia, dt, wf)


@inline_jit
def pre_force_sphere(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, vf, wf,
                     aux):
    """:func:`pre_force_body` for a single sphere whose orientation is not tracked: the
    same half kicks and drift, bit for bit, without the quaternion update (no force depends
    on a sphere's orientation; LIGGGHTS' ``nve/sphere`` does the same)."""
    kick_and_drift(i, pos, vel, force, invmass, dt, vf)
    h = 0.5 * dt
    i0 = invinertia[i, 0]
    for d in range(3):
        dw = h * torque[i, d] * i0
        angvel[i, d] += dw
        wf[i, d] = angvel[i, d] + dw


@inline_jit
def post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    """Second half kick."""
    h = 0.5 * dt
    im = invmass[i]
    for d in range(3):
        vel[i, d] += h * force[i, d] * im
    rotation_second_half(i, quat, angvel, torque, invinertia, dt)
