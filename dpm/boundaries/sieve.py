"""Sieve screen: a plate with a square pattern of square or round holes."""

from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from ..kernels.boundary_geometry import SIEVE
from ..parameters import Parameter
from .base import Primitives
from .wall import Wall

SHAPES = {"square": 0, "round": 1}
MODELS = {"exact": 0, "radius": 1, "fixed": 2}


class Sieve(Wall):
    """A screen plate (a :class:`~dpm.boundaries.wall.Wall`: ``center``, ``normal``,
    ``u``, ``half_extents``, ``thickness``) with holes of width ``hole`` (side of a square
    hole, diameter of a round one) separated by bars of width ``bar``; hole centres sit on
    the square grid of pitch hole + bar through ``center``.

    ``clearance_model``:

    - ``"exact"``: the perforated plate as a triangle mesh (16 rim points per hole,
      :mod:`dpm.boundaries.mesh` contact rules, plate of ``thickness`` with rounded rims);
      a sphere passes a hole only if it fits, and one resting in a hole touches its rim
      all round. The plate covers whole pitch cells around ``center`` (2K + 1 per axis,
      K = floor(a / pitch - 1/2)).
    - ``"radius"``: Alkhaldi (2007) model 1 (eq. 4.20): the plate is the plane of zero
      thickness; a sphere of radius r smaller than half the hole passes if its centre lies
      within the reduced hole of half width w - b, w = hole / 2, b = zeta (w - r).
    - ``"fixed"``: model 2 (eq. 4.21): the same with b = zeta w.

    Elsewhere the sphere meets the plane. Screening efficiency follows from counting the
    particles that end below the plate (see :meth:`below`).
    """

    name = "sieve"
    parameters = {
        **Wall.parameters,
        "hole": Parameter(low=0.0, low_open=True, unit="m", doc="hole width"),
        "bar": Parameter(low=0.0, low_open=True, unit="m", doc="bar width"),
        "shape": Parameter(default="square", kind="str", doc="square or round"),
        "clearance_model": Parameter(default="exact", kind="str",
                                     doc="exact, radius (model 1) or fixed (model 2)"),
        "zeta": Parameter(default=0.0, low=0.0, high=1.0,
                          doc="hole clearance factor of the clearance models"),
    }

    def __init__(self, material, call=None, **params):
        super().__init__(material, call, **params)
        call = call or "Sieve()"
        p = self.params
        if p["shape"] not in SHAPES:
            raise ParameterError(f"{call}: shape={p['shape']!r}; allowed: "
                                 f"{', '.join(SHAPES)}")
        if p["clearance_model"] not in MODELS:
            raise ParameterError(f"{call}: clearance_model={p['clearance_model']!r}; "
                                 f"allowed: {', '.join(MODELS)}")
        self.hole = float(p["hole"])
        self.bar = float(p["bar"])
        self.pitch = self.hole + self.bar
        self.shape = p["shape"]
        self.model = p["clearance_model"]
        self.zeta = float(p["zeta"])

    def open_area_fraction(self) -> float:
        """Fraction of the plate area that is holes: hole^2 / pitch^2 (square) or
        pi hole^2 / (4 pitch^2) (round)."""
        f = self.hole**2 / self.pitch**2
        return f * math.pi / 4.0 if self.shape == "round" else f

    def volume(self) -> float:
        """Volume of the plate [m3]: 4 a b thickness (1 - open area fraction)."""
        return 4.0 * self.a * self.b * 2.0 * self.h * (1.0 - self.open_area_fraction())

    def below(self, position: np.ndarray) -> np.ndarray:
        """Mask of points on the far side of the plate (opposite its normal)."""
        return (np.asarray(position, float) - self.center) @ self.normal < 0.0

    def mesh(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices, faces) of the exact model's plate: per pitch cell, quads between 16
        points of the hole rim and 16 points of the cell square at the same angles (the
        square's corners are among them), welded across cells."""
        import trimesh

        p, w = self.pitch, 0.5 * self.hole
        ku = int(np.floor(self.a / p - 0.5))
        kv = int(np.floor(self.b / p - 0.5))
        if ku < 0 or kv < 0:
            raise ParameterError(f"Sieve(): half_extents=({self.a:g}, {self.b:g}) hold no "
                                 f"whole pitch cell of {p:g} m (hole + bar)")
        ang = np.arange(16) * (2 * np.pi / 16)
        c, s = np.cos(ang), np.sin(ang)
        outer = 0.5 * p / np.maximum(np.abs(c), np.abs(s))
        inner = np.full(16, w) if self.shape == "round" else w / np.maximum(np.abs(c), np.abs(s))
        verts, faces = [], []
        for i in range(-ku, ku + 1):
            for j in range(-kv, kv + 1):
                base = len(verts)
                for rad in (inner, outer):
                    for k in range(16):
                        verts.append((i * p + rad[k] * c[k], j * p + rad[k] * s[k]))
                for k in range(16):
                    a, b = base + k, base + (k + 1) % 16
                    faces += [(a, 16 + a, 16 + b), (a, 16 + b, b)]
        uv = np.asarray(verts)
        xyz = self.center + uv[:, :1] * self.u + uv[:, 1:] * self.v
        tm = trimesh.Trimesh(np.round(xyz, 12), np.asarray(faces), process=False)
        tm.merge_vertices()
        return np.asarray(tm.vertices), np.asarray(tm.faces)

    def primitives(self) -> Primitives:
        if self.model == "exact":
            import trimesh

            from .mesh import feature_flags, triangle_primitives

            v, f = self.mesh()
            tm = trimesh.Trimesh(v, f, process=False)
            return triangle_primitives(v, f, self.h, feature_flags(tm, f, len(v)))
        row = [*self.center, *self.u, *self.v, self.a, self.b, self.h, self.hole,
               self.pitch, SHAPES[self.shape], MODELS[self.model], self.zeta]
        lo = self.corners().min(axis=0)
        hi = self.corners().max(axis=0)
        return Primitives.build([(SIEVE, row, (lo, hi))])
