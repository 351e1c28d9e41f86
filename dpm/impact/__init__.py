"""Impact (contact force) models."""

from .base import ImpactModel, PairContext
from .cohesion import LinearCohesion
from .hertz_brilliantov import HertzBrilliantov
from .hertz_mindlin import HertzMindlin
from .hooke import Hooke
from .linear import LinearSpringDashpot
from .maw import MawLinearSpring
from .walton_braun import WaltonBraun

__all__ = ["HertzBrilliantov", "HertzMindlin", "Hooke", "ImpactModel", "LinearCohesion",
           "LinearSpringDashpot", "MawLinearSpring", "PairContext", "WaltonBraun"]
