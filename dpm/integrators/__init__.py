"""Time integrators."""

from .base import Integrator, SymplecticEuler, VelocityVerlet

__all__ = ["Integrator", "SymplecticEuler", "VelocityVerlet"]
