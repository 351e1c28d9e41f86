"""Gear predictor-corrector for x'' = F(x, v)/m, 4 and 5 values (Gear 1971, *Numerical
Initial Value Problems in ODEs*, §9.2; Allen & Tildesley 1987, *Computer Simulation of
Liquids*, §3.2 and appendix E; DPM thesis, Samiei 2012, §2.7.5).

Nordsieck vector of scaled derivatives r_k = dt^k/k! d^k x/dt^k, k = 0..q-1.
Predictor (Taylor, Pascal's triangle):  r_k^p = sum_{l>=k} C(l, k) r_l
Force at the predicted state:           a^e = F(x^p, v^p) / m
Corrector:                               r_k = r_k^p + c_k D,   D = dt^2/2 (a^e - a^p)

Gear's corrector coefficients c_k for second-order equations (one correction):

    values q | c_0      c_1      c_2  c_3     c_4     c_5
    4 (gear4)| 1/6      5/6      1    1/3
    5 (gear5)| 19/120   3/4      1    1/2     1/12
    (6       | 3/20     251/360  1    11/18   1/6     1/60)

In unscaled form (gear4 = the thesis' eqs. 2.72-2.78; its Table 2.2 prints 11/12 for the
third-derivative term of the velocity, a slip: see shared/seeds/ERRATA.md):
    x += c_0 dt^2/2 (a^e - a^p),   v += c_1 dt/2 (a^e - a^p),   a = a^e,
    j += 3 c_3 (a^e - a^p)/dt,     s += 12 c_4 (a^e - a^p)/dt^2.
A trajectory that is a polynomial of degree q-1 (cubic for gear4, quartic for gear5) is
integrated exactly (tests/physics/test_integrators.py).

``aux[i]``: 0:3 the predicted acceleration a^p, 3:6 the third derivative j, 6:9 (gear5) the
fourth s. The acceleration a_n is F_n/m (c_2 = 1). Higher derivatives start at zero.
Forces see the predicted velocity v^p. Position and velocity are corrected after the
forces, so the state a step ends with is not the one its forces were computed at.

Rotation: Gear's correction is not applied to orientations here; bodies rotate with
velocity Verlet's kick-rotate-kick of the angular momentum (exact isotropic rotation, DLM
splitting for other bodies; :mod:`.integrate_common`), which keeps the quaternion a unit
quaternion and the free-rotation energy bounded (a Gear step on the quaternion components
drifts off the unit sphere and needs a constraint).
"""

from .config import inline_jit
from .integrate_common import rotation_first_half, rotation_second_half

G4 = (1.0 / 6.0, 5.0 / 6.0, 1.0, 1.0 / 3.0)
G5 = (19.0 / 120.0, 3.0 / 4.0, 1.0, 1.0 / 2.0, 1.0 / 12.0)


@inline_jit
def predict4(i, pos, vel, force, invmass, dt, vf, aux):
    im = invmass[i]
    h = 0.5 * dt
    for d in range(3):
        a = force[i, d] * im
        j = aux[i, 3 + d]
        pos[i, d] += dt * (vel[i, d] + dt * (0.5 * a + dt * j / 6.0))
        vel[i, d] += dt * (a + h * j)
        vf[i, d] = vel[i, d]
        aux[i, d] = a + dt * j


@inline_jit
def correct4(i, pos, vel, force, invmass, dt, aux):
    im = invmass[i]
    for d in range(3):
        da = force[i, d] * im - aux[i, d]
        pos[i, d] += G4[0] * 0.5 * dt * dt * da
        vel[i, d] += G4[1] * 0.5 * dt * da
        aux[i, 3 + d] += 3.0 * G4[3] * da / dt


@inline_jit
def predict5(i, pos, vel, force, invmass, dt, vf, aux):
    im = invmass[i]
    for d in range(3):
        a = force[i, d] * im
        j = aux[i, 3 + d]
        s = aux[i, 6 + d]
        pos[i, d] += dt * (vel[i, d] + dt * (0.5 * a + dt * (j / 6.0 + dt * s / 24.0)))
        vel[i, d] += dt * (a + dt * (0.5 * j + dt * s / 6.0))
        vf[i, d] = vel[i, d]
        aux[i, d] = a + dt * (j + 0.5 * dt * s)
        aux[i, 3 + d] = j + dt * s


@inline_jit
def correct5(i, pos, vel, force, invmass, dt, aux):
    im = invmass[i]
    for d in range(3):
        da = force[i, d] * im - aux[i, d]
        pos[i, d] += G5[0] * 0.5 * dt * dt * da
        vel[i, d] += G5[1] * 0.5 * dt * da
        aux[i, 3 + d] += 3.0 * G5[3] * da / dt
        aux[i, 6 + d] += 12.0 * G5[4] * da / (dt * dt)


@inline_jit
def gear4_pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt,
                         vf, wf, aux):
    predict4(i, pos, vel, force, invmass, dt, vf, aux)
    rotation_first_half(i, quat, angvel, torque, invinertia, dt, wf)


@inline_jit
def gear4_post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    correct4(i, pos, vel, force, invmass, dt, aux)
    rotation_second_half(i, quat, angvel, torque, invinertia, dt)


@inline_jit
def gear5_pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt,
                         vf, wf, aux):
    predict5(i, pos, vel, force, invmass, dt, vf, aux)
    rotation_first_half(i, quat, angvel, torque, invinertia, dt, wf)


@inline_jit
def gear5_post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    correct5(i, pos, vel, force, invmass, dt, aux)
    rotation_second_half(i, quat, angvel, torque, invinertia, dt)
