"""Time integrators."""

from .base import Integrator, SymplecticEuler, VelocityVerlet
from .explicit import Gear4, Gear5, PositionVerlet, Taylor

__all__ = ["Gear4", "Gear5", "Integrator", "PositionVerlet", "SymplecticEuler", "Taylor",
           "VelocityVerlet"]
