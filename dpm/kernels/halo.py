"""Halo packing: what a ghost needs of its owner's state, from chosen body rows into one
contiguous message buffer and back (the MPI backend's ghost update, :mod:`dpm.parallel`).

The halo travels after the integrator's pre-force part and before the forces (LAMMPS'
forward communication): only owners integrate, and a ghost takes what the force pass
reads of it. One row of a buffer holds a body's position (3), quaternion (4) and the
velocities its forces see (3 + 3): ``HALO_WIDTH`` floats. Unpacking places the ghost's
elements from its position and quaternion (clustered bodies; single spheres share their
position with their element).
"""

from .config import jit
from .rigid_rotation import place_elements

#: floats per body row of a halo message
HALO_WIDTH = 13


@jit
def pack_halo(rows, pos, quat, vf, wf, out):
    """out[k] = the halo row of body rows[k] (the layout of the module docstring)."""
    for k in range(rows.shape[0]):
        b = rows[k]
        for d in range(3):
            out[k, d] = pos[b, d]
            out[k, 7 + d] = vf[b, d]
            out[k, 10 + d] = wf[b, d]
        for d in range(4):
            out[k, 3 + d] = quat[b, d]


@jit
def unpack_halo(first, buf, pos, quat, vf, wf, estart, e_offset, e_pos, place):
    """Body rows first, first + 1, ... take the rows of ``buf`` (the inverse of
    :func:`pack_halo`); with ``place``, their elements are placed, x_e = X_b + R(q_b)
    offset_e."""
    for k in range(buf.shape[0]):
        b = first + k
        for d in range(3):
            pos[b, d] = buf[k, d]
            vf[b, d] = buf[k, 7 + d]
            wf[b, d] = buf[k, 10 + d]
        for d in range(4):
            quat[b, d] = buf[k, 3 + d]
        if place:
            place_elements(b, pos, quat, estart, e_offset, e_pos)
