"""Position (Stormer) Verlet, second order (Verlet 1967; DPM thesis, Samiei 2012, §2.7.3).

    x_{n+1} = 2 x_n - x_{n-1} + dt^2 F_n / m                               (eq. 2.67)

in the summed form that keeps round-off low (Hairer, Lubich & Wanner 2003, Acta Numerica
12, eq. 1.6): d_{n+1} = d_n + dt^2 F_n / m, x_{n+1} = x_n + d_{n+1}, with d_n = x_n - x_{n-1}
kept per body in ``aux[i, 0:3]``. The scheme itself has no velocity; the thesis' central
difference (x_{n+1} - x_{n-1}) / 2 dt (eq. 2.68) is one step behind the positions. Here the
velocity at the new positions is the second-order backward difference of the positions,

    v_{n+1} = (3 x_{n+1} - 4 x_n + x_{n-1}) / (2 dt) = (3 d_{n+1} - d_n) / (2 dt),

known before the forces of step n+1, so dashpots and friction see it; it uses positions
only (no force), which keeps the scheme distinct from velocity Verlet (whose positions
are the same in exact arithmetic). Start: d_0 = dt v_0 - dt^2/2 F_0/m (Taylor), set by
:meth:`dpm.integrators.PositionVerlet.start`; when the velocity found in ``vel`` is not the
one the scheme wrote (``aux[i, 3:6]``: the user changed it between runs), d is restarted
the same way.

Rotation: velocity Verlet's kick-rotate-kick of the angular momentum (exact isotropic
rotation, DLM splitting otherwise; :mod:`.integrate_common`), the rotational analogue of
these positions. Stable for omega dt < 2 (undamped).
"""

from .config import inline_jit
from .integrate_common import rotation_first_half, rotation_second_half


@inline_jit
def pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, vf, wf, aux):
    """Stormer step of the positions and the backward-difference velocity."""
    im = invmass[i]
    dt2 = dt * dt
    if vel[i, 0] != aux[i, 3] or vel[i, 1] != aux[i, 4] or vel[i, 2] != aux[i, 5]:
        for d in range(3):
            aux[i, d] = dt * vel[i, d] - 0.5 * dt2 * force[i, d] * im
    for d in range(3):
        old = aux[i, d]
        new = old + dt2 * force[i, d] * im
        pos[i, d] += new
        v = (3.0 * new - old) / (2.0 * dt)
        vel[i, d] = v
        vf[i, d] = v
        aux[i, d] = new
        aux[i, 3 + d] = v
    rotation_first_half(i, quat, angvel, torque, invinertia, dt, wf)


@inline_jit
def post_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    """Second half kick of the rotation."""
    rotation_second_half(i, quat, angvel, torque, invinertia, dt)
