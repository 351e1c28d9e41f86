"""Boundaries: walls, tubes, bends, meshes and sieves that exert forces on particles."""

from .base import Boundary, Primitives
from .bend import Bend
from .box import Box
from .mesh import Mesh
from .orifice import OrificePlate
from .plane import Plane
from .sieve import Sieve
from .tube import Tube
from .wall import Wall

__all__ = ["Bend", "Boundary", "Box", "Mesh", "OrificePlate", "Plane", "Primitives", "Sieve",
           "Tube", "Wall"]
