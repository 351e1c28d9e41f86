"""The records the step kernels take: a few named tuples of arrays instead of 47 arguments.

Each record groups the arrays of one container of the state (:mod:`dpm.state`), built by
the backend for each kernel call (a named tuple of existing arrays: no copy). numba types a
named tuple of arrays as a struct of array structs; a driver takes its fields out once per
call and hands plain arrays to the per-contact functions, so the hot loops see exactly the
arrays they saw before (taking an array out of a tuple costs numba a reference count, two
atomic operations: once per pass, never per contact).

A new array the kernels need (a ghost flag, an adhesion state) is one new field here, filled
in one place (``dpm.backends.cpu.CpuBackend.records``), instead of an edit of every driver
signature. The kernels import nothing of this module (the kernel layer imports only numpy,
numba and math): they read the fields by name.
"""

from collections import namedtuple

#: per-body arrays: position, velocity (n, 3); quaternion (n, 4) (w, x, y, z); angular
#: velocity, force, torque (n, 3); mass, inverse mass (n,); inverse principal inertia
#: (n, 3); the velocities the forces see (set by the integrator's pre-force part, n x 3
#: each); the integrator's auxiliary state (n, k); element ranges (n + 1,)
BodyArrays = namedtuple("BodyArrays", ["pos", "vel", "quat", "angvel", "force", "torque",
                                       "mass", "invmass", "invinertia", "vf", "wf", "aux",
                                       "estart"])

#: per-element arrays: owner body, body-frame offset (n, 3), radius, material index, world
#: position and the position at the last rebuild (n, 3); ``worst``: scratch (squared
#: displacement since the rebuild, then largest overlap / radius); ``count``: touching
#: contacts of the last force evaluation
ElementArrays = namedtuple("ElementArrays", ["owner", "offset", "radius", "mat", "pos", "ref",
                                             "worst", "count"])

#: the half neighbour list (CSR): start (n + 1,), partner key, history rows, active flags,
#: force rows, the transposed index (t_start, t_pair)
PairList = namedtuple("PairList", ["start", "key", "hist", "active", "force", "t_start",
                                   "t_pair"])

#: the element-boundary-primitive list (CSR): start, primitive key, history, active flags,
#: force rows, per-entry scratch tag
WallList = namedtuple("WallList", ["start", "key", "hist", "active", "force", "tag"])

#: the packed boundary table (:class:`dpm.state.BoundaryTable`)
BoundaryArrays = namedtuple("BoundaryArrays", ["kind", "par", "owner", "material", "ids",
                                               "frame", "frame_ref", "extent", "load",
                                               "grid_int", "grid_flt", "cell_start",
                                               "cell_items", "prim_cells"])

#: scene constants of a call: gravity (3,), skin [m], the overlap / radius that stops a run,
#: whether element positions are computed from their bodies (False: every body one sphere),
#: the number of chunks of the fused force pass (0: two passes), whether single spheres
#: skip their quaternion update, the material-pair tables, the periodic box (lower corner
#: [0:3], period [3:6], 0 = not periodic); ``n_owned``: bodies [0, n_owned) are owned
#: and integrated, the rest are ghosts (copies of bodies owned elsewhere: their elements
#: take part in the contacts, their force and torque sums are what they receive here, to
#: be handed back to their owners; :attr:`dpm.state.Bodies.ghosts`); ``reach`` [m]: how far
#: beyond touching a contact law keeps contacts (JKR's |d_c|; 0: touching only), by which
#: the neighbour and boundary lists extend
SceneConstants = namedtuple("SceneConstants", ["gravity", "skin", "max_overlap",
                                               "update_elements", "fused", "spin_only",
                                               "pair_model", "pair_params", "period",
                                               "n_owned", "reach"], defaults=(0.0,))
