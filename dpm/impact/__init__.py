"""Impact (contact force) models."""

from .base import ImpactModel
from .hertz_mindlin import HertzMindlin
from .linear import LinearSpringDashpot

__all__ = ["HertzMindlin", "ImpactModel", "LinearSpringDashpot"]
