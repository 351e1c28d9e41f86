"""Integrators: each names the kernel module holding its per-body step functions."""

from __future__ import annotations

from typing import Any, ClassVar


class Integrator:
    """A time integrator.

    Subclass it and set ``kernel_module`` to a module defining two numba functions
    ``pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt,
    vf, wf, aux)`` and ``post_force_body(i, ..., dt, aux)`` that advance body ``i``; the step calls
    them inside its parallel loops over bodies, before and after the force evaluation.
    ``pre_force_body`` also writes ``vf[i]``, ``wf[i]``: the velocity and angular velocity
    that velocity-dependent forces of this step see.
    ``aux[i]`` is a row of ``aux_columns`` floats per body that the integrator keeps
    between steps (e.g. the higher derivatives of a Gear predictor-corrector); it starts at
    zero and :meth:`start` may fill it once the forces of the initial state are known.
    ``order`` is the global order of accuracy for smooth forces.

    An implicit integrator sets ``implicit = True`` and overrides :meth:`advance`, which
    then replaces the explicit kernel loop: it advances the simulation's state arrays
    ``n`` steps itself. It reads the scene's tables from ``sim.plan`` and keeps its
    per-body state in ``sim.backend.aux``; when it cannot go on it returns the steps it
    did with ``sim.backend.diag[0]`` set to ``STATUS_INTEGRATOR`` (5) and the reason in
    :attr:`failure`, and the run loop stops with that diagnosis.
    """

    name: ClassVar[str] = ""
    kernel_module: ClassVar[str] = ""
    order: ClassVar[int] = 1
    aux_columns: ClassVar[int] = 0
    #: fewest steps per shortest contact the time-step check accepts (explicit schemes go
    #: unstable near 2/omega; an unconditionally stable implicit scheme may lower it)
    min_steps_per_contact: ClassVar[float] = 5.0
    implicit: ClassVar[bool] = False
    #: why the last :meth:`advance` stopped early (implicit integrators)
    failure: str = ""

    def start(self, sim: Any) -> None:
        """Called once before the first step, after the initial forces are computed
        (``sim.bodies.force``/``torque`` hold them) and ``sim.backend.aux`` is allocated."""

    def start_bodies(self, sim: Any, rows: Any) -> None:
        """Bodies were added after the start (``rows`` of ``sim.bodies``; their forces
        are in ``sim.bodies.force``): give them their integrator state. The default
        restarts the whole integrator when it keeps state (``aux_columns`` or implicit)
        and does nothing otherwise; an integrator with per-body state overrides it to
        start the new rows alone, so that the others go on undisturbed."""
        if self.aux_columns or self.implicit:
            self.start(sim)

    def dt_changed(self, sim: Any, old_dt: float) -> None:
        """``sim.dt`` was changed between runs (from ``old_dt``; ``sim.dt`` is the new
        step): rescale the integrator's state. The default restarts it when it keeps
        state (the forces of the current state are in ``sim.bodies.force``)."""
        if self.aux_columns or self.implicit:
            self.start(sim)

    def advance(self, sim: Any, n: int) -> int:
        """Implicit integrators only: advance ``n`` steps of ``sim``; return the number
        of steps done (fewer only when the run must stop, with ``sim.backend.diag[0]`` set)."""
        raise NotImplementedError(f"{type(self).__name__} is explicit: the step kernels "
                                  "advance it")


class SymplecticEuler(Integrator):
    """Symplectic Euler: v += dt F/m, x += dt v (first order).

    See :mod:`dpm.kernels.integrate_symplectic_euler` for the equations.
    """

    name = "symplectic_euler"
    kernel_module = "dpm.kernels.integrate_symplectic_euler"
    order = 1


class VelocityVerlet(Integrator):
    """Velocity Verlet (second order, symplectic, time-reversible).

    See :mod:`dpm.kernels.integrate_velocity_verlet` for the equations.
    """

    name = "velocity_verlet"
    kernel_module = "dpm.kernels.integrate_velocity_verlet"
    order = 2
