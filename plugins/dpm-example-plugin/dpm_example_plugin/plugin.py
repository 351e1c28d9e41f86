"""The plugin module named by the entry point: registers a shape and an impact model."""

from __future__ import annotations

import math

import numpy as np

import dpm
from dpm.impact.base import COMMON
from dpm.impact.linear import cutoff_contact_time, damping_ratio_for_restitution
from dpm.parameters import Parameter
from dpm.shapes import BodyBatch


class Dimer(dpm.Shape):
    """Two equal spheres of radius ``radius`` [m], centres ``separation`` [m] apart along x.

    Volume and inertia of the union of the two solid spheres (the lens they share counted
    once), principal axes = the shape axes.
    """

    name = "dimer"
    parameters = {
        "radius": Parameter(low=0.0, low_open=True, unit="m"),
        "separation": Parameter(low=0.0, unit="m", doc="centre distance, < 2 radius"),
    }

    def build(self, count: int, density: float) -> BodyBatch:
        r, s = float(self.params["radius"]), float(self.params["separation"])
        if s >= 2 * r:
            raise dpm.ParameterError(f"dimer: separation={s:g} must be below 2 radius={2 * r:g}")
        # inertia of the union by numerical integration over slices along x
        x = np.linspace(-s / 2 - r, s / 2 + r, 4001)
        rho2 = np.maximum(r**2 - (np.abs(x) - s / 2) ** 2, 0.0)  # slice radius^2 (outer)
        rho2 = np.maximum(rho2, np.where(np.abs(x) < s / 2, r**2 - (s / 2) ** 2, 0.0))
        area = np.pi * rho2
        vol = np.trapezoid(area, x)
        ixx = np.trapezoid(0.5 * area * rho2, x) * density
        iyy = np.trapezoid(area * (rho2 / 4 + x**2), x) * density
        m = vol * density
        offsets = np.tile([[-s / 2, 0.0, 0.0], [s / 2, 0.0, 0.0]], (count, 1))
        return BodyBatch(np.full(count, m), np.tile([ixx, iyy, iyy], (count, 1)),
                         np.full(count, 2, np.int64), offsets, np.full(2 * count, r),
                         np.full(count, s / 2 + r))


class LinearViscous(dpm.ImpactModel):
    """Linear spring-dashpot normal force, purely viscous Coulomb-limited tangential force.

    Parameters: stiffness k_n [N/m], restitution (with the cut-off, as dpm's linear law),
    friction, tangential_damping_ratio zeta_t (default 0.5), rolling friction.
    """

    name = "linear_viscous"
    kernel = ("dpm_example_plugin.kernels", "linear_viscous")
    parameters = {
        **COMMON,
        "stiffness": Parameter(low=0.0, low_open=True, unit="N/m"),
        "tangential_damping_ratio": Parameter(default=0.5, low=0.0),
    }

    def pair_row(self, a, b, context):
        zeta = damping_ratio_for_restitution(float(self.params["restitution"]))
        return self._row(self.params["stiffness"], zeta, self.params["friction"],
                         self.params["tangential_damping_ratio"])

    def contact_time(self, a, b, meff, reff, speed):
        zeta = damping_ratio_for_restitution(float(self.params["restitution"]))
        return cutoff_contact_time(zeta, math.sqrt(self.params["stiffness"] / meff))


@dpm.hookimpl
def dpm_register_shapes(register):
    register("dimer", Dimer)


@dpm.hookimpl
def dpm_register_impact_models(register):
    register("linear_viscous", LinearViscous)
