"""Gear predictor-corrector with 4 values: the per-body functions of :mod:`.integrate_gear`
under the names the step imports."""

from .integrate_gear import gear4_post_force_body as post_force_body
from .integrate_gear import gear4_pre_force_body as pre_force_body

__all__ = ["post_force_body", "pre_force_body"]
