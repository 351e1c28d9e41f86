"""dpm: the Discrete Particle Method (DEM) for granular matter, in Python with numba kernels.

>>> import dpm
>>> sim = dpm.Simulation(dt=1e-5, gravity=(0, 0, -9.81))
"""

__version__ = "0.1.0"

from .boundaries import Boundary
from .errors import DpmError, ParameterError, SceneError, UnknownNameError, UnstableRunError
from .hookspecs import hookimpl
from .impact import ImpactModel
from .integrators import Integrator
from .io import load
from .material import Material
from .plugins import register, registry
from .scene_tools import lattice
from .shapes import Shape
from .simulation import Simulation

__all__ = [
    "Boundary", "DpmError", "ImpactModel", "Integrator", "Material", "ParameterError",
    "SceneError", "Shape", "Simulation", "UnknownNameError", "UnstableRunError", "hookimpl",
    "lattice", "load", "register", "registry", "__version__",
]
