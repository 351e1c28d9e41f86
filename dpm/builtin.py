"""The built-in plugin: registers dpm's own classes through the ``dpm`` entry points."""

from __future__ import annotations

from .backends.cpu import CpuBackend
from .boundaries import Bend, Box, Mesh, OrificePlate, Plane, Sieve, Tube, Wall
from .hookspecs import Register, hookimpl
from .impact import (
    JKR,
    HertzBrilliantov,
    HertzMindlin,
    Hooke,
    LinearCohesion,
    LinearSpringDashpot,
    MawLinearSpring,
    WaltonBraun,
)
from .integrators import (
    BackwardEuler,
    Gear4,
    Gear5,
    NewmarkBeta,
    Numerov,
    PositionVerlet,
    SymplecticEuler,
    Taylor,
    VelocityVerlet,
)
from .reciprocating import Reciprocating
from .shapes import BUILTIN_SHAPES


@hookimpl
def dpm_register_shapes(register: Register) -> None:
    from .shapes.library import LibraryShape
    from .shapes.multisphere import Multisphere

    for name, cls in BUILTIN_SHAPES.items():
        register(name, cls)
    register("library", LibraryShape)  # path = a grain's name or a .json file
    register("multisphere", Multisphere)  # centres = [[x, y, z], ...], radii = [...]


@hookimpl
def dpm_register_boundaries(register: Register) -> None:
    register("plane", Plane)
    register("box", Box)
    register("wall", Wall)
    register("tube", Tube)
    register("bend", Bend)
    register("mesh", Mesh)
    register("sieve", Sieve)
    register("orifice_plate", OrificePlate)


@hookimpl
def dpm_register_impact_models(register: Register) -> None:
    register("linear_spring_dashpot", LinearSpringDashpot)
    register("maw_linear_spring", MawLinearSpring)
    register("hooke", Hooke)
    register("hertz_brilliantov", HertzBrilliantov)
    register("hertz_mindlin", HertzMindlin)
    register("walton_braun", WaltonBraun)
    register("linear_cohesion", LinearCohesion)
    register("jkr", JKR)


@hookimpl
def dpm_register_integrators(register: Register) -> None:
    register("symplectic_euler", SymplecticEuler)
    register("velocity_verlet", VelocityVerlet)
    register("taylor", Taylor)
    register("position_verlet", PositionVerlet)
    register("gear4", Gear4)
    register("gear5", Gear5)
    register("backward_euler", BackwardEuler)
    register("newmark_beta", NewmarkBeta)
    register("numerov", Numerov)


@hookimpl
def dpm_register_motions(register: Register) -> None:
    from . import motion

    register("translation", motion.Translation)
    register("rotation", motion.Rotation)
    register("oscillation", motion.Oscillation)
    register("triangular_oscillation", motion.TriangularOscillation)
    register("tumbling", motion.Tumbling)
    register("reciprocating", Reciprocating)


@hookimpl
def dpm_register_regions(register: Register) -> None:
    from .regions import BoxRegion, CylinderRegion, DiscFace, MeshFace, RectangleFace

    register("box", BoxRegion)
    register("cylinder", CylinderRegion)
    register("rectangle_face", RectangleFace)
    register("disc_face", DiscFace)
    register("mesh_face", MeshFace)


@hookimpl
def dpm_register_rolling_models(register: Register) -> None:
    from .impact.parts import EPSD, ConstantTorque

    register("constant_torque", ConstantTorque)
    register("epsd", EPSD)


@hookimpl
def dpm_register_backends(register: Register) -> None:
    register("cpu", CpuBackend)
    from .parallel.backend import MpiBackend

    register("mpi", MpiBackend)
    from .backends.cuda import CudaBackend  # (numba.cuda is imported only when it is used)

    register("cuda", CudaBackend)
