"""The numba finding of benchmarks/NOTES.md row 13: the same per-body loop compiled as a
plain ``@jit`` function and as the body of a ``prange`` loop, one thread.

Times velocity Verlet's ``post_force_body`` over 10,000 bodies: a serial loop in an
``@njit`` function, the same loop in a ``parallel=True`` function without ``prange``, a
``prange`` over the bodies, and a serial loop inside a one-iteration ``prange`` (the form
the fused force pass uses). Prints microseconds per call.

    python benchmarks/numba_serial_loops.py
"""

from __future__ import annotations

import time
import warnings

import numba
import numpy as np
from numba import njit, prange

from dpm.kernels.config import JIT
from dpm.kernels.integrate_velocity_verlet import post_force_body


@njit(**JIT)
def serial(pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    for b in range(pos.shape[0]):
        post_force_body(b, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux)


@njit(**JIT, parallel=True)
def serial_in_parallel_function(pos, vel, quat, angvel, force, torque, invmass, invinertia,
                                dt, aux):
    for b in range(pos.shape[0]):
        post_force_body(b, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux)


@njit(**JIT, parallel=True)
def prange_over_bodies(pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    for b in prange(pos.shape[0]):
        post_force_body(b, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux)


@njit(**JIT, parallel=True)
def serial_in_one_prange(pos, vel, quat, angvel, force, torque, invmass, invinertia, dt, aux):
    for _ in prange(1):
        for b in range(pos.shape[0]):
            post_force_body(b, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt,
                            aux)


def main() -> None:
    warnings.simplefilter("ignore", numba.NumbaPerformanceWarning)  # (no prange: meant)
    numba.set_num_threads(1)
    n = 10_000
    rng = np.random.default_rng(0)
    q = rng.random((n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    args = (rng.random((n, 3)), rng.random((n, 3)), q, rng.random((n, 3)), rng.random((n, 3)),
            rng.random((n, 3)), rng.random(n), np.ones((n, 3)), 1e-6, np.zeros((n, 0)))
    for fn in (serial, serial_in_parallel_function, prange_over_bodies, serial_in_one_prange):
        fn(*args)  # compile
        t = time.perf_counter()
        for _ in range(200):
            fn(*args)
        print(f"{fn.__name__:30s} {(time.perf_counter() - t) / 200 * 1e6:7.1f} us per call")


if __name__ == "__main__":
    main()
