"""Particle shapes: a body is one sphere or a rigid cluster of overlapping sphere elements.

``sphere`` is one element; the other built-in shapes are ideal solids approximated by a
cluster of spheres (:mod:`dpm.shapes.cluster`), with mass properties of the ideal solid.
``docs/shapes.md`` documents each shape's parameters and default orientation;
:mod:`dpm.shapes.metrics` reports sphere counts and shape errors;
:mod:`dpm.shapes.library` reads and writes the ready-made shapes of ``shapes/``.
"""

from .base import BodyBatch, Shape
from .cluster import Cluster, ClusterShape, MassProperties
from .mesh import MeshShape
from .multisphere import Multisphere
from .solids import (
    Barrel,
    Block,
    Cone,
    Cube,
    Cylinder,
    Disc,
    DoubleCone,
    Ellipsoid,
    Hyperboloid,
    Parallelepiped,
    Tetrahedron,
    Torus,
)
from .sphere import Sphere

#: the shapes dpm registers under these names (dpm.builtin)
BUILTIN_SHAPES: dict[str, type[Shape]] = {
    cls.name: cls
    for cls in (Sphere, Ellipsoid, Cylinder, Cube, Block, Parallelepiped, Tetrahedron, Cone,
                DoubleCone, Hyperboloid, Barrel, Disc, Torus, MeshShape)
}

from . import library, metrics  # noqa: E402  (they use BUILTIN_SHAPES)

__all__ = [
    "BUILTIN_SHAPES", "Barrel", "Block", "BodyBatch", "Cluster", "ClusterShape", "Cone", "Cube",
    "Cylinder", "Disc", "DoubleCone", "Ellipsoid", "Hyperboloid", "MassProperties", "MeshShape",
    "Multisphere",
    "Parallelepiped", "Shape", "Sphere", "Tetrahedron", "Torus", "library", "metrics",
]
