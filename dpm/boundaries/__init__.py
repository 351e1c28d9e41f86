"""Boundaries: walls that exert forces on particles."""

from .base import Boundary
from .box import Box
from .plane import Plane

__all__ = ["Boundary", "Box", "Plane"]
