"""Backends: where and how the state is stepped (see :mod:`dpm.backends.base`).

``Simulation(device="cpu")`` (the default) takes :class:`CpuBackend`; a backend instance
may be passed instead (``device=CpuBackend(force_pass="two_pass")``). Backends register
through the entry-point group ``dpm`` like every other plugin kind (``dpm plugins``).
"""

from .base import Backend, StepResult, step_by_parts
from .cpu import CpuBackend

__all__ = ["Backend", "CpuBackend", "StepResult", "step_by_parts"]
