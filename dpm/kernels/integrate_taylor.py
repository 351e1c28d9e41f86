"""Taylor integrator, first order (DPM thesis, Samiei 2012, §2.7.2, eqs. 2.59-2.60).

    x_{n+1} = x_n + dt v_n + dt^2/2 F_n / m          (Taylor polynomial of degree two)
    v_{n+1} = v_n + dt F_n / m                        (degree one)

The acceleration is taken constant over the step at its value at the start (constant
acceleration motion). The forces of step n+1 see v_{n+1}, known before they are computed, so
all the work happens before the force evaluation. First order: the velocity is forward Euler.

Rotation, the same constant-acceleration step:
    isotropic bodies:  q_{n+1} = exp((omega_n + dt/2 alpha_n) dt / 2) q_n,
                       omega_{n+1} = omega_n + dt alpha_n,   alpha = T / I
    other bodies:      explicit Euler of Euler's equations and of q' = q (x) (0, w_b)/2,
                       q renormalised (:func:`.rigid_rotation.rotate_quaternion_derivative`).
Stability: the undamped oscillator grows by |1 + (omega dt)^2/2 ...| > 1 per step: the
energy of a linear contact rises by a factor ~ 1 + (omega dt)^2 / 2 per step in contact, so it
needs the most steps per contact of all schemes here.
"""

from .config import inline_jit
from .rigid_rotation import rotate_isotropic, rotate_quaternion_derivative


@inline_jit
def pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, vf, wf, aux):
    """The whole step: drift with constant acceleration, kick; forces then see v_{n+1}."""
    im = invmass[i]
    h = 0.5 * dt
    for d in range(3):
        a = force[i, d] * im
        pos[i, d] += dt * (vel[i, d] + h * a)
        vel[i, d] += dt * a
        vf[i, d] = vel[i, d]
    i0 = invinertia[i, 0]
    i1 = invinertia[i, 1]
    i2 = invinertia[i, 2]
    q0 = quat[i, 0]
    q1 = quat[i, 1]
    q2 = quat[i, 2]
    q3 = quat[i, 3]
    if i0 == i1 and i1 == i2:
        ax = torque[i, 0] * i0
        ay = torque[i, 1] * i0
        az = torque[i, 2] * i0
        q0, q1, q2, q3 = rotate_isotropic(q0, q1, q2, q3, angvel[i, 0] + h * ax,
                                          angvel[i, 1] + h * ay, angvel[i, 2] + h * az, dt)
        wx = angvel[i, 0] + dt * ax
        wy = angvel[i, 1] + dt * ay
        wz = angvel[i, 2] + dt * az
    else:
        q0, q1, q2, q3, wx, wy, wz = rotate_quaternion_derivative(
            q0, q1, q2, q3, angvel[i, 0], angvel[i, 1], angvel[i, 2], torque[i, 0],
            torque[i, 1], torque[i, 2], i0, i1, i2, dt)
    angvel[i, 0] = wx
    angvel[i, 1] = wy
    angvel[i, 2] = wz
    wf[i, 0] = wx
    wf[i, 1] = wy
    wf[i, 2] = wz
    quat[i, 0] = q0
    quat[i, 1] = q1
    quat[i, 2] = q2
    quat[i, 3] = q3


@inline_jit
def post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    """Nothing: the step was done before the forces."""
    return
