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
an MPI backend reduces them over ranks, a GPU backend on the device. Optional (the run
loop asks with ``getattr``, so a backend without them keeps working): ``sync_host()``
brings ``sim.bodies`` up to date where calls leave the host behind (an MPI backend
gathers the ranks' rows only when the run loop needs them: output, flow events, hooks, a
run's end), with ``host_stale`` saying whether they did; ``guard_hits(nonfinite,
box)`` and ``energies(gravity)`` answer the run-time guards and the energy book from the
backend's own state. :meth:`to_host` and
:meth:`from_host` move the state to and from ``sim.bodies`` (and the other containers) for
output, hooks, flow events and checkpoints; for the CPU backend they are no-ops (the host
arrays are the state).
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
