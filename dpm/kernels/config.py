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



@inline_jit
def pair_row(pair_params, a, b):
    """The constants of material pair (a, b) as a tuple of N_PAIR_PARAMS floats (what the
    contact laws and the rolling resistance receive as ``p``).

    A tuple, not the row view ``pair_params[a, b]``: numba reference-counts an array view
    with two atomic operations (and spills every live float register around those calls),
    once per touching pair; that was 3.5 % of box_settle's settled step in the atomics
    alone.
    """
    return (pair_params[a, b, 0], pair_params[a, b, 1], pair_params[a, b, 2],
            pair_params[a, b, 3], pair_params[a, b, 4], pair_params[a, b, 5],
            pair_params[a, b, 6], pair_params[a, b, 7])


assert N_PAIR_PARAMS == 8  # pair_row spells the slots out


@inline_jit
def pair_row16(pair_params, a, b):
    """:func:`pair_row` for the scenes whose composed laws need more than 8 slots (their
    table is 16 wide)."""
    return (pair_params[a, b, 0], pair_params[a, b, 1], pair_params[a, b, 2],
            pair_params[a, b, 3], pair_params[a, b, 4], pair_params[a, b, 5],
            pair_params[a, b, 6], pair_params[a, b, 7], pair_params[a, b, 8],
            pair_params[a, b, 9], pair_params[a, b, 10], pair_params[a, b, 11],
            pair_params[a, b, 12], pair_params[a, b, 13], pair_params[a, b, 14],
            pair_params[a, b, 15])


@inline_jit
def row18(a, k):
    """Row ``k`` of an (n, 18) array as a tuple (a boundary frame row; see
    :func:`pair_row` for why a tuple and not the view ``a[k]``)."""
    return (a[k, 0], a[k, 1], a[k, 2], a[k, 3], a[k, 4], a[k, 5], a[k, 6], a[k, 7], a[k, 8],
            a[k, 9], a[k, 10], a[k, 11], a[k, 12], a[k, 13], a[k, 14], a[k, 15], a[k, 16],
            a[k, 17])


@inline_jit
def row20(a, k):
    """Row ``k`` of an (n, 20) array as a tuple (a boundary primitive's geometry)."""
    return (a[k, 0], a[k, 1], a[k, 2], a[k, 3], a[k, 4], a[k, 5], a[k, 6], a[k, 7], a[k, 8],
            a[k, 9], a[k, 10], a[k, 11], a[k, 12], a[k, 13], a[k, 14], a[k, 15], a[k, 16],
            a[k, 17], a[k, 18], a[k, 19])

#: the same two for the functions of the generated step modules (cached on disk)
step_jit = njit(**STEP_JIT)
step_pjit = njit(**STEP_JIT, parallel=True)
