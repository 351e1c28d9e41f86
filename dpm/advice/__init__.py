"""The set-up a scene needs for a tolerance on one quantity (``dpm.advise``, ``dpm advise``).

From the scene's materials, sizes and impact speed and the measured work-precision tables
(``dpm/data/work_precision.json``, written by :mod:`dpm.advice.condense`), :func:`advise`
recommends the impact model, integrator, time step, skin and shape resolution that meet a
tolerance on a quantity of interest at the lowest predicted cost, with the predicted error
and cost per simulated second, the assumptions and the warnings where the advice leaves
the measured range; on request it checks the choice by two pilot runs (Richardson).
The models, their equations and the benchmark: docs/advise.md.
"""

from .core import Advice, Verification, advise, apply_setting
from .model import Prediction, Setting
from .quantities import QUANTITIES, Measurement, Quantity, quantity, run_and_measure

__all__ = ["Advice", "Measurement", "Prediction", "QUANTITIES", "Quantity", "Setting",
           "Verification", "advise", "apply_setting", "quantity", "run_and_measure"]
