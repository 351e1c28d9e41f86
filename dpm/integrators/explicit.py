"""Explicit integrators beyond the two of :mod:`.base`: Taylor, position Verlet, Gear.

Each names its kernel module (the equations and sources are in the module docstrings and
in docs/integrators.md); the step calls the module's per-body functions in its loops.
"""

from __future__ import annotations

from typing import Any

from .base import Integrator


class Taylor(Integrator):
    """Taylor (constant acceleration over the step), first order (DPM thesis §2.7.2).

    See :mod:`dpm.kernels.integrate_taylor`.
    """

    name = "taylor"
    kernel_module = "dpm.kernels.integrate_taylor"
    order = 1


class PositionVerlet(Integrator):
    """Position (Stormer) Verlet with a backward-difference velocity, second order.

    See :mod:`dpm.kernels.integrate_position_verlet`.
    """

    name = "position_verlet"
    kernel_module = "dpm.kernels.integrate_position_verlet"
    order = 2
    aux_columns = 6

    def start(self, sim: Any) -> None:
        """d_0 = x_0 - x_{-1} = dt v_0 - dt^2/2 F_0/m (Taylor backwards)."""
        b = sim.bodies
        a = b.force * b.invmass[:, None]
        sim.backend.aux[:, 0:3] = sim.dt * b.velocity - 0.5 * sim.dt**2 * a
        sim.backend.aux[:, 3:6] = b.velocity

    def start_bodies(self, sim: Any, rows: Any) -> None:
        """d_0 of the added bodies alone."""
        b = sim.bodies
        a = b.force[rows] * b.invmass[rows, None]
        sim.backend.aux[rows, 0:3] = sim.dt * b.velocity[rows] - 0.5 * sim.dt**2 * a
        sim.backend.aux[rows, 3:6] = b.velocity[rows]


class Gear4(Integrator):
    """Gear predictor-corrector, 4 values (x, v, a, third derivative).

    See :mod:`dpm.kernels.integrate_gear` for the coefficients.
    """

    name = "gear4"
    kernel_module = "dpm.kernels.integrate_gear4"
    #: measured in position on smooth forces (a linear and a cubic oscillator): 4
    order = 4
    aux_columns = 6

    def start(self, sim: Any) -> None:
        """Higher derivatives start at zero; a^p at the current acceleration."""
        sim.backend.aux[:] = 0.0
        sim.backend.aux[:, 0:3] = sim.bodies.force * sim.bodies.invmass[:, None]

    def start_bodies(self, sim: Any, rows: Any) -> None:
        """The added bodies alone: derivatives zero, a^p their acceleration."""
        sim.backend.aux[rows] = 0.0
        sim.backend.aux[rows, 0:3] = sim.bodies.force[rows] * sim.bodies.invmass[rows, None]

    def dt_changed(self, sim: Any, old_dt: float) -> None:
        """Nothing: a^p and the higher derivatives are kept in physical units."""


class Gear5(Gear4):
    """Gear predictor-corrector, 5 values (x, v, a, third and fourth derivatives).

    See :mod:`dpm.kernels.integrate_gear` for the coefficients.
    """

    name = "gear5"
    kernel_module = "dpm.kernels.integrate_gear5"
    #: measured in position on smooth forces: 5
    order = 5
    aux_columns = 9


__all__ = ["Gear4", "Gear5", "PositionVerlet", "Taylor"]
