"""Particle shapes: a body is one or more sphere elements."""

from .base import BodyBatch, Shape
from .sphere import Sphere

__all__ = ["BodyBatch", "Shape", "Sphere"]
