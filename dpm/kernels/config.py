"""Options shared by every kernel."""

from numba import njit

#: compile options of every dpm kernel: cached on disk; the numpy error model gives
#: inf/NaN instead of raising, and the step loop reports NaN counts as a flag.
JIT = dict(cache=True, error_model="numpy", nogil=True)

#: number of float slots in a material-pair constants row (pair_params[a, b, :])
N_PAIR_PARAMS = 8

#: floats of history per contact: 0-2 tangential spring, 3-5 rolling spring,
#: 6-7 state of the normal law (e.g. plastic overlap)
N_HISTORY = 8

jit = njit(**JIT)
