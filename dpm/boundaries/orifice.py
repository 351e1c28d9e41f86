"""Orifice plate: a floor (or any plate) with one round or rectangular opening."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..kernels.boundary_geometry import AXI
from ..parameters import Parameter, shown
from .base import Boundary, Primitives
from .frames import in_plane_axes, unit

SHAPES = ("round", "rectangle")


class OrificePlate(Boundary):
    """A plate centred at ``center`` with unit ``normal`` and one opening at its centre:
    the floor of a silo or hopper with its outlet.

    - ``shape="round"``: a disc of radius ``radius`` with a round orifice of diameter
      ``hole``. Contact (kernel kind AXI): the annulus from hole / 2 to ``radius`` as a
      surface of revolution about the normal, of ``thickness``, its rims rounded. A sphere
      larger than the orifice resting in it touches the whole rim and gets one contact
      integrated round the ring (it sits centred, not pushed aside); a smaller one falls
      through.
    - ``shape="rectangle"``: a rectangle of ``half_extents`` (a, b) along ``u`` and
      v = normal x u with a rectangular opening ``hole`` = (width along u, length along v)
      (a number: a square), as a triangle mesh of 8 triangles (the mesh contact rules:
      flat seams count once, the opening's edges and corners are rounded rims); a slot
      orifice of a wedge hopper.

    A silo's floor need not fit the silo's outline: a disc larger than the silo's
    cross-section under its walls does. Both sides of the plate touch (particles that have
    fallen through stay below it). :meth:`below` tells which positions lie past it;
    ``hole_area`` is the opening's area.
    """

    name = "orifice_plate"
    parameters = {
        "center": Parameter(default=(0.0, 0.0, 0.0), kind="vector", unit="m"),
        "normal": Parameter(default=(0.0, 0.0, 1.0), kind="vector"),
        "hole": Parameter(kind="any", unit="m",
                          doc="orifice diameter (round), or (width, length) / side"),
        "shape": Parameter(default="round", kind="str", doc="round or rectangle"),
        "radius": Parameter(default=None, low=0.0, low_open=True, unit="m",
                            doc="outline radius (round)"),
        "half_extents": Parameter(default=None, kind="any", unit="m",
                                  doc="outline (a, b) (rectangle)"),
        "u": Parameter(default=None, kind="any", doc="in-plane axis of a (rectangle)"),
        "thickness": Parameter(default=0.0, low=0.0, unit="m"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "OrificePlate()"
        p = self.params
        if p["shape"] not in SHAPES:
            raise ParameterError(f"{call}: shape={p['shape']!r}; allowed: {', '.join(SHAPES)}")
        self.shape = p["shape"]
        self.center = np.asarray(p["center"], float)
        self.normal = unit(call, "normal", p["normal"])
        self.u, self.v = in_plane_axes(call, self.normal, p["u"])
        self.h = 0.5 * float(p["thickness"])
        hole = np.asarray(p["hole"], float).reshape(-1) if not isinstance(p["hole"], str) \
            else np.array([np.nan])
        if self.shape == "round":
            if hole.shape != (1,) or not (np.isfinite(hole[0]) and hole[0] > 0):
                raise ParameterError(f"{call}: hole={shown(p['hole'])} must be the orifice "
                                     "diameter, a positive length in m")
            if p["radius"] is None:
                raise ParameterError(f"{call}: a round plate needs radius= (its outline, "
                                     f"larger than hole / 2 = {hole[0] / 2:g} m)")
            if p["half_extents"] is not None:
                raise ParameterError(f"{call}: half_extents is for shape='rectangle'; a "
                                     "round plate takes radius=")
            self.hole = float(hole[0])
            self.radius = float(p["radius"])
            if not self.radius > 0.5 * self.hole:
                raise ParameterError(f"{call}: radius={shown(self.radius)} must exceed hole / 2 = "
                                     f"{self.hole / 2:g} m")
            self.hole_area = math.pi * self.hole**2 / 4.0
        else:
            if hole.shape == (1,):
                hole = np.repeat(hole, 2)
            if hole.shape != (2,) or not np.all(np.isfinite(hole) & (hole > 0)):
                raise ParameterError(f"{call}: hole={shown(p['hole'])} must be (width, length) "
                                     "of the opening, or its side, positive lengths in m")
            he = None if p["half_extents"] is None else \
                np.asarray(p["half_extents"], float).reshape(-1)
            if he is None or he.shape != (2,) or not np.all(he > 0):
                raise ParameterError(f"{call}: half_extents={shown(p['half_extents'])} must be "
                                     "two positive lengths (a, b) of the outline")
            if p["radius"] is not None:
                raise ParameterError(f"{call}: radius is for shape='round'; a rectangular "
                                     "plate takes half_extents=")
            if not np.all(he > 0.5 * hole):
                raise ParameterError(f"{call}: half_extents={shown(he)} must exceed half the "
                                     f"opening {shown(hole / 2)} on both axes")
            self.hole = (float(hole[0]), float(hole[1]))
            self.a, self.b = float(he[0]), float(he[1])
            self.hole_area = self.hole[0] * self.hole[1]

    def below(self, position: np.ndarray) -> np.ndarray:
        """Mask of points on the far side of the plate (opposite its normal)."""
        return (np.asarray(position, float) - self.center) @ self.normal < 0.0

    def volume(self) -> float:
        """Volume of the plate [m3]: (outline area - hole area) x thickness."""
        area = math.pi * self.radius**2 if self.shape == "round" else 4.0 * self.a * self.b
        return (area - self.hole_area) * 2.0 * self.h

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, faces) of the rectangular plate: the opening's 4 corners and the
        outline's 4, and the 4 trapezoids between them, two triangles each."""
        w, ll = 0.5 * self.hole[0], 0.5 * self.hole[1]
        sig = [(1, 1), (-1, 1), (-1, -1), (1, -1)]
        uv = [(s * w, t * ll) for s, t in sig] + [(s * self.a, t * self.b) for s, t in sig]
        faces = []
        for k in range(4):
            i0, i1, o0, o1 = k, (k + 1) % 4, 4 + k, 4 + (k + 1) % 4
            faces += [(i0, o0, o1), (i0, o1, i1)]
        uv = np.asarray(uv, float)
        xyz = self.center + uv[:, :1] * self.u + uv[:, 1:] * self.v
        return xyz, np.asarray(faces, np.int64)

    def primitives(self) -> Primitives:
        if self.shape == "rectangle":
            import trimesh

            from .mesh import feature_flags, triangle_primitives

            v, f = self.mesh()
            tm = trimesh.Trimesh(v, f, process=False)
            return triangle_primitives(v, f, self.h, feature_flags(tm, f, len(v)))
        o, a, h = self.center, self.normal, self.h
        reach = self.radius + h
        lo, hi = o - reach, o + reach
        prims = Primitives.build([(AXI, [*o, *a, 0.5 * self.hole, 0.0, self.radius, 0.0, h, 0],
                                   (lo, hi))])
        prims.extent = float(np.linalg.norm(o)) + reach
        return prims
