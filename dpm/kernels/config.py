"""Options shared by every kernel."""

from numba import njit

#: compile options of every dpm kernel: cached on disk; the numpy error model gives
#: inf/NaN instead of raising, and the step loop reports NaN counts as a flag.
JIT = dict(cache=True, error_model="numpy", nogil=True)

#: number of float slots in a material-pair constants row (pair_params[a, b, :])
N_PAIR_PARAMS = 8

#: number of floats of contact history per contact (tangential spring 3 + rolling 3)
N_HISTORY = 6

jit = njit(**JIT)
