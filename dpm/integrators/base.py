"""Integrators: each names the kernel module holding its per-body step functions."""

from __future__ import annotations

from typing import ClassVar


class Integrator:
    """A time integrator.

    Subclass it and set ``kernel_module`` to a module defining two numba functions
    ``pre_force_body(i, pos, vel, quat, angvel, force, torque, invmass, invinertia, dt,
    vf, wf)`` and ``post_force_body(i, ..., dt)`` that advance body ``i``; the step calls
    them inside its parallel loops over bodies, before and after the force evaluation.
    ``pre_force_body`` also writes ``vf[i]``, ``wf[i]``: the velocity and angular velocity
    that velocity-dependent forces of this step see.
    ``order`` is the global order of accuracy for smooth forces.
    """

    name: ClassVar[str] = ""
    kernel_module: ClassVar[str] = ""
    order: ClassVar[int] = 1


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
