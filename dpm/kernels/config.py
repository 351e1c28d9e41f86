"""Options shared by every kernel."""

from numba import njit

#: compile options of every dpm kernel. The numpy error model gives inf/NaN instead of
#: raising; the step reports NaN as a status. Library kernels are not cached on their own:
#: numba's cache of a function does not notice when a function it calls in another file
#: changes (numba #1833). The step module that dpm.plan generates per scene is cached
#: (``STEP_JIT``) under a name hashing every kernel source, and its cache holds the code of
#: every kernel it calls, so a warm start loads one module and stale code cannot happen.
JIT = dict(cache=False, error_model="numpy", nogil=True)
STEP_JIT = dict(JIT, cache=True)

#: number of float slots in a material-pair constants row (pair_params[a, b, :])
N_PAIR_PARAMS = 8

#: floats of history per contact: 0-2 tangential spring, 3-5 rolling spring,
#: 6-7 state of the normal law (e.g. plastic overlap)
N_HISTORY = 8

jit = njit(**JIT)

#: for the small functions called per body or per contact from the loops of the step
#: (integrator parts, contact laws, the tangential spring): inlined into the loop at
#: numba-IR level. Left to LLVM, a call passing a dozen arrays costs ~50 ns, more than the
#: arithmetic of a body's update (measured: 77 ns -> 22 ns per body for velocity Verlet).
inline_jit = njit(**JIT, inline="always")

#: kernels whose outer loop is a ``prange``: each iteration writes only its own rows, so
#: the result does not depend on the number of threads
pjit = njit(**JIT, parallel=True)

#: the same two for the functions of the generated step modules (cached on disk)
step_jit = njit(**STEP_JIT)
step_pjit = njit(**STEP_JIT, parallel=True)
