"""Halo packing: the dynamic state of chosen body rows into one contiguous message buffer
and back (the MPI backend's ghost update, :mod:`dpm.parallel`).

One row of a buffer holds a body's position (3), velocity (3), quaternion (4), angular
velocity (3), force (3), torque (3), the velocities its forces see (3 + 3) and the
integrator's auxiliary row (``aux`` columns): ``STATE_WIDTH + aux`` floats. A ghost that
receives this row every step is stepped by its copy of the integrator's pre-force part to
the same bits as its owner (:mod:`dpm.parallel.backend`).
"""

from .config import jit

#: floats per body before the integrator's auxiliary columns
STATE_WIDTH = 25


@jit
def pack_state(rows, pos, vel, quat, angvel, force, torque, vf, wf, aux, out):
    """out[k] = the state of body rows[k] (the layout of the module docstring)."""
    na = aux.shape[1]
    for k in range(rows.shape[0]):
        b = rows[k]
        for d in range(3):
            out[k, d] = pos[b, d]
            out[k, 3 + d] = vel[b, d]
            out[k, 10 + d] = angvel[b, d]
            out[k, 13 + d] = force[b, d]
            out[k, 16 + d] = torque[b, d]
            out[k, 19 + d] = vf[b, d]
            out[k, 22 + d] = wf[b, d]
        for d in range(4):
            out[k, 6 + d] = quat[b, d]
        for c in range(na):
            out[k, STATE_WIDTH + c] = aux[b, c]


@jit
def unpack_state(first, buf, pos, vel, quat, angvel, force, torque, vf, wf, aux):
    """Body rows first, first + 1, ... take the rows of ``buf`` (the inverse of
    :func:`pack_state`)."""
    na = aux.shape[1]
    for k in range(buf.shape[0]):
        b = first + k
        for d in range(3):
            pos[b, d] = buf[k, d]
            vel[b, d] = buf[k, 3 + d]
            angvel[b, d] = buf[k, 10 + d]
            force[b, d] = buf[k, 13 + d]
            torque[b, d] = buf[k, 16 + d]
            vf[b, d] = buf[k, 19 + d]
            wf[b, d] = buf[k, 22 + d]
        for d in range(4):
            quat[b, d] = buf[k, 6 + d]
        for c in range(na):
            aux[b, c] = buf[k, STATE_WIDTH + c]
