"""dpm: the Discrete Particle Method (DEM) for granular matter, in Python with numba kernels.

>>> import dpm
>>> sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81))
"""

__version__ = "0.1.0"

import os as _os

import numba as _numba

if "NUMBA_THREADING_LAYER" not in _os.environ:
    # OpenMP first: on a 2-core machine it scales the step 1.8x on two threads, where TBB
    # gave no gain and the workqueue a loss. NUMBA_THREADING_LAYER
    # set by the user wins.
    _numba.config.THREADING_LAYER_PRIORITY = ["omp", "tbb", "workqueue"]

from ._memory import tune_malloc as _tune_malloc
from .boundaries import Boundary
from .checkpoint import restart
from .distributions import LogNormal, Normal, Sieve
from .errors import (
    DpmError,
    OutputError,
    ParameterError,
    SceneError,
    UnknownNameError,
    UnstableRunError,
)
from .flow import Inlet, Outlet
from .hookspecs import hookimpl
from .impact import ImpactModel
from .integrators import Integrator
from .io import load
from .material import Material
from .motion import (
    Compose,
    Motion,
    Oscillation,
    Rotation,
    Translation,
    TriangularOscillation,
    Tumbling,
)
from .operations import Callback, Operation, Periodic, Trigger
from .parallel import is_root, notice
from .plugins import register, registry
from .reciprocating import Reciprocating
from .regions import BoxRegion, CylinderRegion, DiscFace, Face, MeshFace, RectangleFace, Region
from .scene_tools import lattice
from .shapes import Shape
from .simulation import Simulation

_tune_malloc()  # large arrays mapped on their own, freed back at once (dpm/_memory.py)

__all__ = [
    "Boundary", "BoxRegion", "Compose", "CylinderRegion", "DpmError", "hookimpl",
    "ImpactModel", "Inlet", "Integrator", "lattice", "load", "Material", "Motion",
    "Oscillation", "Outlet", "ParameterError", "Region", "register", "registry", "restart",
    "Rotation", "SceneError", "Shape", "Simulation", "Translation", "TriangularOscillation",
    "Tumbling", "UnknownNameError", "UnstableRunError", "__version__", "Reciprocating",
    "OutputError", "Callback", "Operation", "Periodic", "Trigger",
    "Face", "RectangleFace", "DiscFace", "MeshFace", "advise", "is_root", "notice",
    "Normal", "LogNormal", "Sieve",
]


def __getattr__(name: str):
    """``dpm.advise`` (:func:`dpm.advice.advise`) is imported on first use, as h5py, scipy
    and trimesh are (``dpm/_lazy.py``): ``import dpm`` does not load the advisor."""
    if name == "advise":
        from .advice import advise

        return advise
    raise AttributeError(f"module 'dpm' has no attribute {name!r}")
