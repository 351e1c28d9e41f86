"""Impact (contact force) models."""

from .base import ImpactModel, PairContext
from .cohesion import LinearCohesion, LinearCohesionAdhesion
from .hertz_brilliantov import BrilliantovNormal, HertzBrilliantov, MindlinTangential
from .hertz_mindlin import HertzMindlin, HertzTsujiNormal, MindlinTsujiTangential
from .hooke import Hooke, HookeNormal
from .jkr import JKR, JKRNormal, JKRTangential
from .linear import LinearNormal, LinearSpringDashpot, LinearTangential
from .maw import MawLinearSpring, MawNormal, MawTangential
from .parts import (
                    EPSD,
                    ROLLING_PARTS,
                    AdhesionPart,
                    ConstantTorque,
                    NormalPart,
                    Part,
                    RollingPart,
                    TangentialPart,
)
from .walton_braun import WaltonBraun, WaltonBraunNormal

__all__ = ["EPSD", "ROLLING_PARTS", "AdhesionPart", "BrilliantovNormal", "ConstantTorque",
           "HertzBrilliantov", "HertzMindlin", "HertzTsujiNormal", "Hooke", "HookeNormal",
           "ImpactModel", "JKR", "JKRNormal", "JKRTangential", "LinearCohesion",
           "LinearCohesionAdhesion", "LinearNormal",
           "LinearSpringDashpot", "LinearTangential", "MawLinearSpring", "MawNormal",
           "MawTangential", "MindlinTangential", "MindlinTsujiTangential", "NormalPart", "Part",
           "PairContext", "RollingPart", "TangentialPart", "WaltonBraun", "WaltonBraunNormal"]
