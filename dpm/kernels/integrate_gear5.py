"""Gear predictor-corrector with 5 values: the per-body functions of :mod:`.integrate_gear`
under the names the step imports."""

from .integrate_gear import gear5_post_force_body as post_force_body
from .integrate_gear import gear5_pre_force_body as pre_force_body

__all__ = ["post_force_body", "pre_force_body"]
