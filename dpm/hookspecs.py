"""pluggy hook specifications of dpm (entry-point group ``dpm``).

A plugin package declares in its ``pyproject.toml``::

    [project.entry-points.dpm]
    my_plugin = "my_package.dpm_plugin"

and implements any of these hooks in that module with ``@dpm.hookimpl``. The built-ins
of dpm register through exactly this mechanism (``dpm.builtin``).

Registration hooks are called once, when the registry loads. Run-time hooks are called
per step (only if some plugin implements them: then the step loop returns to Python every
step) or per event; never per contact.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import pluggy

if TYPE_CHECKING:
    from .simulation import Simulation

hookspec = pluggy.HookspecMarker("dpm")
hookimpl = pluggy.HookimplMarker("dpm")

Register = Callable[[str, type], None]


@hookspec
def dpm_register_shapes(register: Register) -> None:
    """Call ``register(name, cls)`` for each :class:`dpm.Shape` subclass provided."""


@hookspec
def dpm_register_boundaries(register: Register) -> None:
    """Call ``register(name, cls)`` for each :class:`dpm.Boundary` subclass provided."""


@hookspec
def dpm_register_impact_models(register: Register) -> None:
    """Call ``register(name, cls)`` for each :class:`dpm.ImpactModel` subclass provided."""


@hookspec
def dpm_register_integrators(register: Register) -> None:
    """Call ``register(name, cls)`` for each :class:`dpm.Integrator` subclass provided."""


@hookspec
def dpm_register_backends(register: Register) -> None:
    """Call ``register(name, cls)`` for each backend class provided (the protocol of
    :class:`dpm.backends.base.Backend`; ``Simulation(device=name)`` selects it)."""


@hookspec
def dpm_register_motions(register: Register) -> None:
    """Register prescribed boundary motions (subclasses of :class:`dpm.motion.Motion`;
    a scene file names them as ``motion = { type = "name", ... }``)."""


@hookspec
def dpm_register_regions(register: Register) -> None:
    """Register regions for inlets and outlets (subclasses of :class:`dpm.regions.Region`;
    a scene file names them as ``region = { name = {...} }``)."""


@hookspec
def dpm_register_rolling_models(register: Register) -> None:
    """Register rolling-resistance parts (subclasses of :class:`dpm.impact.parts.RollingPart`;
    a composed impact model selects one by ``rolling_model = "name"``)."""


@hookspec
def dpm_before_step(sim: Simulation, rank: int) -> None:
    """Called before every step (makes the run return to Python each step); on every MPI
    rank, ``rank`` its number (0 on one process)."""


@hookspec
def dpm_after_step(sim: Simulation, rank: int) -> None:
    """Called after every step (makes the run return to Python each step); on every MPI
    rank, ``rank`` its number (0 on one process)."""


@hookspec
def dpm_output_layout(sim: Simulation, file: Any) -> None:
    """A new output file is being laid out: create the plugin's own groups and (empty,
    extendable) datasets in ``file`` (the open ``h5py.File``) here, then fill them in
    :func:`dpm_on_output`. Called once per file, before the file goes to HDF5's
    single-writer/multiple-reader mode, after which HDF5 before 2.0 refuses new
    datasets."""


@hookspec
def dpm_on_output(sim: Simulation, frame: int, path: Any, rank: int) -> None:
    """Called after each output frame is written and flushed."""


@hookspec
def dpm_on_particles_inserted(sim: Simulation, inlet: Any, ids: Any, rank: int) -> None:
    """An inlet has just inserted the bodies ``ids`` (numpy int64 array)."""


@hookspec
def dpm_on_particles_removed(sim: Simulation, outlet: Any, records: Any,
                             rank: int) -> None:
    """An outlet has just removed bodies; ``records`` is a dict of arrays: id, time, mass,
    residence_time, position (n, 3), velocity (n, 3)."""


@hookspec
def dpm_on_checkpoint(sim: Simulation, state: dict, rank: int) -> None:
    """A checkpoint is being written: put what the plugin must have back after a restart
    into ``state`` under a key of its own (picklable values: numpy arrays, numbers,
    strings, lists, dicts). State kept on the scene's own objects (a boundary, a motion,
    an impact model) is in the checkpoint already."""


@hookspec
def dpm_on_restart(sim: Simulation, state: dict, rank: int) -> None:
    """A simulation was restored from a checkpoint (:func:`dpm.restart`); ``state`` is the
    dict that :func:`dpm_on_checkpoint` filled when it was written."""
