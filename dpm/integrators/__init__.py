"""Time integrators."""

from .base import Integrator, SymplecticEuler, VelocityVerlet
from .explicit import Gear4, Gear5, PositionVerlet, Taylor
from .implicit import BackwardEuler, NewmarkBeta, Numerov

__all__ = ["BackwardEuler", "Gear4", "Gear5", "Integrator", "NewmarkBeta", "Numerov",
           "PositionVerlet", "SymplecticEuler", "Taylor", "VelocityVerlet"]
