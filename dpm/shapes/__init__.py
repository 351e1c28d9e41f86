"""Particle shapes: a body is one or more sphere elements."""

from .base import BodyBatch, Shape
from .sphere import Sphere

#: the shapes dpm registers under these names (dpm.builtin)
BUILTIN_SHAPES: dict[str, type[Shape]] = {"sphere": Sphere}

__all__ = ["BUILTIN_SHAPES", "BodyBatch", "Shape", "Sphere"]
