"""The built-in plugin: registers dpm's own classes through the ``dpm`` entry points."""

from __future__ import annotations

from .boundaries import Box, Plane
from .hookspecs import Register, hookimpl
from .impact import HertzMindlin, LinearSpringDashpot
from .integrators import SymplecticEuler, VelocityVerlet
from .shapes import Sphere


@hookimpl
def dpm_register_shapes(register: Register) -> None:
    register("sphere", Sphere)


@hookimpl
def dpm_register_boundaries(register: Register) -> None:
    register("plane", Plane)
    register("box", Box)


@hookimpl
def dpm_register_impact_models(register: Register) -> None:
    register("linear_spring_dashpot", LinearSpringDashpot)
    register("hertz_mindlin", HertzMindlin)


@hookimpl
def dpm_register_integrators(register: Register) -> None:
    register("symplectic_euler", SymplecticEuler)
    register("velocity_verlet", VelocityVerlet)
