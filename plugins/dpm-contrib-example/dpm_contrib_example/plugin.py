"""The module the entry point names: registers the contributed classes and the hook."""

from __future__ import annotations

import dpm

from . import recorder
from .models import KelvinVoigt
from .motions import Orbit
from .shapes import Spherocylinder


@dpm.hookimpl
def dpm_register_impact_models(register):
    register("kelvin_voigt", KelvinVoigt)


@dpm.hookimpl
def dpm_register_shapes(register):
    register("spherocylinder", Spherocylinder)


@dpm.hookimpl
def dpm_register_motions(register):
    register("orbit", Orbit)


@dpm.hookimpl
def dpm_output_layout(sim, file):
    """Lay out the orbit datasets in a new output file (:mod:`.recorder`)."""
    recorder.layout(sim, file)


@dpm.hookimpl
def dpm_on_output(sim, frame, path):
    """Record the orbiting boundaries' frames into the output (:mod:`.recorder`)."""
    recorder.on_output(sim, frame)
