"""The Backend protocol: what the run loop of :class:`dpm.Simulation` drives.

A backend owns where and how the state is stepped: the CPU backend (numba threads, this
package), later an MPI backend (one sub-domain per rank, halo exchange) and a CUDA backend
(state resident on the device). The script does not change between them (the model is
HOOMD-blue's ``Simulation(device=...)``): ``dpm.Simulation(..., device="cpu")``.

Order of one step, as the operations are called (:func:`step_by_parts`):

1. :meth:`pre_force`  integrator pre-force part, element positions, displacements
2. :meth:`needs_rebuild`  does any element (or boundary) need new lists? (collective over
   ranks in an MPI backend: every rank rebuilds or none)
3. :meth:`rebuild`  neighbour and boundary lists, history carried over by pair
4. :meth:`forces`  gravity and contact forces (an MPI backend hands ghost forces back here)
5. :meth:`post_force`  integrator post-force part

:meth:`advance` runs ``n`` such steps; a backend may fuse them (the CPU backend runs many
steps in one compiled call when nothing needs control between steps) provided the result
is the same bit for bit as ``n`` calls of :meth:`step`.

Reductions (:meth:`max_speed`, :meth:`max_overlap`, :meth:`nan_count`,
:meth:`boundary_loads`, :meth:`contact_count`) are what the run loop asks between calls;
an MPI backend reduces them over ranks, a GPU backend on the device. ``sync_host()``
brings ``sim.bodies`` up to date where calls leave the host behind (an MPI backend
gathers the ranks' rows only when the run loop needs them: output, flow events, hooks, a
run's end), with ``host_stale`` saying whether they did; ``guard_hits(nonfinite,
box)`` and ``energies(gravity)`` answer the run-time guards and the energy book from the
backend's own state. :meth:`to_host` and
:meth:`from_host` move the state to and from ``sim.bodies`` (and the other containers) for
output, hooks, flow events and checkpoints; for the CPU backend they are no-ops (the host
arrays are the state).

Every member the run loop and the rest of dpm call is declared here; nothing asks a
backend with ``getattr`` whether it has one. :class:`BackendBase` gives the defaults of a
backend on one process whose host arrays are its state (the communicator's members:
``rank``, ``ranks``, ``root``, ``agree_chunk``, ``agree_any``; no renumbering; no sync):
the CPU backend derives from it, and the MPI and CUDA backends from the CPU backend.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

#: statuses a step reports (``StepResult.status``)
STATUS_OK = 0
STATUS_OVERFLOW = 1
STATUS_NAN = 2
STATUS_OVERLAP = 3
STATUS_WALL_OVERFLOW = 4
#: an implicit integrator could not take the next step (its ``failure`` says why)
STATUS_INTEGRATOR = 5


@dataclass
class StepResult:
    """What :meth:`Backend.advance` reports: steps done, status (0 ok, 2 NaN, 3 overlap
    beyond ``max_overlap``), rebuilds done, the largest overlap / radius seen and the
    element where it was (-1: none)."""

    steps: int
    status: int = STATUS_OK
    rebuilds: int = 0
    worst_overlap: float = 0.0
    worst_element: int = -1


@runtime_checkable
class Backend(Protocol):
    """The operations the run loop drives (see the module docstring for the order)."""

    #: registered name (``Simulation(device=name)``)
    name: str

    def attach(self, sim: Any) -> None:
        """Take the prepared scene (``sim.plan``, the state containers) and allocate
        what the steps need; called when the scene was (re)planned."""

    def population_changed(self) -> None:
        """Bodies were inserted or removed between calls: resize, rebuild, forces."""

    def prime(self) -> None:
        """Forces of the current state without advancing contact history (dt = 0)."""

    # one step, in order
    def pre_force(self, dt: float) -> None: ...
    def needs_rebuild(self) -> int: ...  # 1 yes, 0 no, -1 a position is NaN
    def rebuild(self) -> None: ...
    def forces(self, dt: float) -> None: ...
    def post_force(self, dt: float) -> None: ...

    def advance(self, n: int, dt: float, frames: np.ndarray) -> StepResult:
        """``n`` steps; ``frames[s]`` the boundary frames at the end of step s (empty: no
        boundary moves)."""

    # reductions
    def max_speed(self) -> tuple[int, float]: ...
    def max_overlap(self) -> tuple[float, int]: ...
    def nan_count(self) -> int: ...
    def boundary_loads(self) -> np.ndarray: ...
    def contact_count(self) -> int: ...

    # state transfer
    def to_host(self) -> None: ...
    def from_host(self) -> None: ...
    def sync_host(self) -> None: ...

    # what else the run loop and dpm ask (defaults: :class:`BackendBase`)
    threads: int | None
    rank: int
    ranks: int
    root: bool
    call_aim: float
    host_stale: bool

    def thread_count(self, n_elements: int) -> int: ...
    def sync_form(self) -> None: ...
    def agree_chunk(self, n: int) -> int: ...
    def agree_any(self, flag: bool) -> bool: ...
    def sorts(self) -> bool: ...
    def sort_due(self) -> None: ...
    def energies(self, gravity: np.ndarray) -> tuple[float, float]: ...
    def guard_hits(self, nonfinite: bool, box: np.ndarray | None) -> bool: ...
    def force_rows_current(self) -> bool: ...
    def force_velocities(self) -> tuple[np.ndarray, np.ndarray] | None: ...


class BackendBase:
    """The defaults of :class:`Backend`'s members for a backend on one process whose host
    arrays are its state (see the module docstring); a backend overrides what differs."""

    name = ""
    #: threads of the step kernels (None: the backend's default)
    threads: int | None = None
    #: this process's rank, the number of ranks, and whether this rank writes the files
    rank = 0
    ranks = 1
    root = True
    #: seconds of work the run loop aims each kernel call at
    call_aim = 0.1
    #: whether ``sim.bodies`` lags the backend's state (see :meth:`sync_host`)
    host_stale = False

    def thread_count(self, n_elements: int) -> int:
        """Threads for a run of a scene of ``n_elements`` elements."""
        return 1

    def sync_form(self) -> None:
        """Follow a changed thread count (a step module with another form)."""

    def agree_chunk(self, n: int) -> int:
        """The steps of the next call, the same on every rank."""
        return n

    def agree_any(self, flag: bool) -> bool:
        """Whether ``flag`` holds on any rank."""
        return flag

    def sync_host(self) -> None:
        """Bring the host state up to the backend's (nothing: the host is the state)."""

    def sorts(self) -> bool:
        """Whether the run renumbers its bodies in cell order (:meth:`sort_due`)."""
        return False

    def sort_due(self) -> None:
        """At a renumbering check (when :meth:`sorts`): renumber if it is time."""

    def force_rows_current(self) -> bool:
        """Whether the pairs' force rows hold the forces of the last evaluation (the
        contact output reads them instead of evaluating the pairs again)."""
        return False

    def force_velocities(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The (linear, angular) velocities the last force evaluation saw (an
        integrator's prediction), None where they are the state's."""
        return None

    def to_host(self) -> None:
        """The host arrays are the state: nothing to copy."""

    def from_host(self) -> None:
        """The host arrays are the state: nothing to copy."""


def step_by_parts(backend: Backend, dt: float) -> int:
    """One step through the protocol's parts, in the order of the module docstring;
    returns the status (what a backend without a fused many-step form runs per step)."""
    backend.pre_force(dt)
    need = backend.needs_rebuild()
    if need < 0:
        return STATUS_NAN
    if need:
        backend.rebuild()
    backend.forces(dt)
    backend.post_force(dt)
    return STATUS_OK
