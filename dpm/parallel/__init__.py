"""Runs over MPI ranks: domain decomposition (:mod:`dpm.parallel.backend`).

``mpiexec -n 4 python script.py`` (or ``mpiexec -n 4 dpm run scene.toml``) runs the
script's scene cut into four sub-domains, with no change to the script: a
:class:`dpm.Simulation` made without ``device`` takes the ``"mpi"`` backend when the
launcher started several ranks. Whether it did is read from the launcher's environment
(Open MPI's ``OMPI_COMM_WORLD_SIZE``, MPICH's and Intel MPI's ``PMI_SIZE``, MVAPICH2's
``MV2_COMM_WORLD_SIZE``), so that a serial run never imports mpi4py. Under ``srun``, launch
with an MPI plugin that sets one of them (``srun --mpi=pmi2`` sets ``PMI_SIZE``).
"""

from __future__ import annotations

import os
from typing import TextIO

#: environment variables in which MPI launchers give the number of ranks
SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE", "PMIX_SIZE")


def launched_ranks() -> int:
    """The number of ranks the launcher started this process among (1: not launched by
    an MPI launcher, or alone)."""
    for name in SIZE_VARIABLES:
        value = os.environ.get(name)
        if value:
            try:
                return max(1, int(value))
            except ValueError:
                continue
    return 1


def default_device() -> str:
    """``"mpi"`` under an MPI launcher with several ranks, else ``"cpu"``."""
    return "mpi" if launched_ranks() > 1 else "cpu"


def rank() -> int:
    """This process's rank (0 without MPI; mpi4py imported only under a launcher)."""
    if launched_ranks() == 1:
        return 0
    from mpi4py import MPI

    return int(MPI.COMM_WORLD.Get_rank())


def is_root() -> bool:
    """True in the process that prints and writes a script's own files: rank 0 under an
    MPI launcher, the only process otherwise. Every rank runs the whole script and holds
    the whole result after a run (``sim.bodies`` is gathered), so a script that writes a
    JSON summary or a plot guards the write with it: ``if dpm.is_root(): ...``. (The
    run's own output, ``sim.output``, is written by one writer already.)"""
    return rank() == 0


def notice(*objects: object, sep: str = " ", end: str = "\n", file: TextIO | None = None,
           flush: bool = False) -> None:
    """:func:`print` on rank 0 only (as HOOMD-blue's ``Device.notice``): a script's
    messages appear once under ``mpiexec -n 4``, as in a serial run. The arguments are
    print's."""
    if is_root():
        print(*objects, sep=sep, end=end, file=file, flush=flush)


__all__ = ["default_device", "is_root", "launched_ranks", "notice", "rank"]
