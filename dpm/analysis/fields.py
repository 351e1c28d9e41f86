"""Time-averaged solids fraction and velocity fields: voxel binning and Gaussian
coarse-graining, with 2-D slices."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import shown
from ._common import axis_index, frames_of, mass_of, radius_of


@dataclass
class Field:
    """Fields on a regular grid of cells: ``edges`` (3 arrays of cell edges [m]),
    ``centres`` (3 arrays), ``phi`` (nx, ny, nz) solids fraction, ``density`` (nx, ny, nz)
    mass density [kg/m3], ``velocity`` (nx, ny, nz, 3) [m/s] (mass-weighted mean, NaN
    where no mass), ``frames`` averaged."""

    edges: tuple[np.ndarray, np.ndarray, np.ndarray]
    phi: np.ndarray
    density: np.ndarray
    velocity: np.ndarray
    frames: int
    method: str

    @property
    def centres(self) -> tuple[np.ndarray, ...]:
        return tuple(0.5 * (e[1:] + e[:-1]) for e in self.edges)

    def slice(self, name: str = "phi", axis: str | int = "y", at: float | None = None
              ) -> tuple[np.ndarray, tuple[float, float, float, float]]:
        """A 2-D slice of ``name`` (``phi``, ``density``, ``speed``, ``vx``, ``vy``,
        ``vz``) normal to ``axis``: the cells containing ``at`` [m], or with ``at=None``
        the mean along the axis. Returns ``(array, extent)``: the array indexed by the two
        remaining axes in order (first, second), and ``(lo1, hi1, lo2, hi2)`` for
        ``matplotlib.pyplot.imshow(array.T, origin="lower", extent=extent)``."""
        data = {"phi": self.phi, "density": self.density,
                "speed": np.linalg.norm(self.velocity, axis=-1),
                "vx": self.velocity[..., 0], "vy": self.velocity[..., 1],
                "vz": self.velocity[..., 2]}
        if name not in data:
            raise ParameterError(f"name={name!r}; allowed: {', '.join(data)}")
        a = axis_index(axis)
        arr = data[name]
        if at is None:
            with np.errstate(invalid="ignore"):
                out = np.nanmean(arr, axis=a) if name not in ("phi", "density") \
                    else arr.mean(axis=a)
        else:
            e = self.edges[a]
            k = int(np.searchsorted(e, at, side="right")) - 1
            if not 0 <= k < len(e) - 1:
                raise ParameterError(f"at={shown(at)} is outside the grid [{e[0]}, {e[-1]}]")
            out = np.take(arr, k, axis=a)
        rest = [i for i in range(3) if i != a]
        e1, e2 = self.edges[rest[0]], self.edges[rest[1]]
        return out, (float(e1[0]), float(e1[-1]), float(e2[0]), float(e2[-1]))


def _grid(lower: Any, upper: Any, cell: Any) -> tuple[np.ndarray, ...]:
    lo, hi = np.asarray(lower, float).reshape(3), np.asarray(upper, float).reshape(3)
    c = np.broadcast_to(np.asarray(cell, float), (3,))
    if not np.all(c > 0) or not np.all(hi > lo):
        raise ParameterError(f"cell={shown(cell)} must be > 0 and upper > lower "
                             f"(lower={shown(lo)}, upper={shown(hi)})")
    n = np.maximum(np.round((hi - lo) / c).astype(int), 1)
    return tuple(lo[i] + c[i] * np.arange(n[i] + 1) for i in range(3))


@lru_cache(maxsize=8)
def ball_points(per_radius: int) -> np.ndarray:
    """The fixed sub-sample of the unit ball: the centres of a cubic lattice of spacing
    1/per_radius (offset by half a spacing, so the set is symmetric about the three
    coordinate planes and has no point on them) that lie inside the ball."""
    h = 1.0 / per_radius
    g = (np.arange(-per_radius, per_radius) + 0.5) * h
    p = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    return p[np.einsum("ij,ij->i", p, p) <= 1.0]


def _deposit(edges, pos, weights_list, shape):
    """Add each weight array at the cells of ``pos`` (points outside are dropped)."""
    idx = []
    inside = np.ones(len(pos), bool)
    for i in range(3):
        k = np.searchsorted(edges[i], pos[:, i], side="right") - 1
        inside &= (k >= 0) & (k < len(edges[i]) - 1)
        idx.append(k)
    flat = np.ravel_multi_index(tuple(k[inside] for k in idx), shape)
    size = int(np.prod(shape))
    return [np.bincount(flat, weights=w[inside], minlength=size).reshape(shape)
            for w in weights_list]


def voxel_fields(source: Any, cell: Any, lower: Any, upper: Any, frames: Any = None,
                 method: str = "points", per_radius: int = 4) -> Field:
    """Time-averaged solids fraction and velocity on a grid of cells (binning).

    phi(cell) = (sum of the sphere volume inside the cell) / (cell volume), averaged over
    the frames; velocity(cell) = sum m_i v_i / sum m_i over the bodies' mass inside the
    cell and all frames (Favre, mass-weighted). ``method``:

    - ``"points"`` (default): each sphere is represented by a fixed set of points, the
      centres of a cubic lattice of spacing r/``per_radius`` that fall inside it
      (``per_radius=4``: 280 points), each carrying V/N of its volume and m/N of its
      mass. The volume a sphere gives a cell is then exact to within the lattice spacing
      near the faces: for cells of size R the error on one cell's share is a few percent,
      for 2R and 4R it averages out (a cell that spans whole periods of a lattice of
      spheres gets exactly their volume, as the point set's volume is exact).
    - ``"centre"``: each sphere is given whole to the cell of its centre: exact only for
      cells much larger than the spheres (error ~ R / cell at the cells' faces; cells of
      size R on a lattice get 0 or 8 pi/6).

    Cell sizes of R, 2R and 4R (R the sphere radius) trade resolution against noise. The
    cells span ``lower`` to ``upper`` (their size rounded to fit). For clustered bodies the
    bounding radius is used (a sphere of the body's bounding radius: an overestimate of
    the volume; use :func:`coarse_grain` with the element data for those).
    Source: the standard binning of DEM fields (e.g. Weinhart et al. 2012, section 2).
    """
    if method not in ("points", "centre"):
        raise ParameterError(f"method={method!r}; allowed: 'points', 'centre'")
    edges = _grid(lower, upper, cell)
    shape = tuple(len(e) - 1 for e in edges)
    vol = np.zeros(shape)
    mass = np.zeros(shape)
    mom = np.zeros(shape + (3,))
    nf = 0
    ref = ball_points(int(per_radius)) if method == "points" else np.zeros((1, 3))
    for f in frames_of(source, frames):
        x = np.asarray(f["position"], float)
        n = len(x)
        r = radius_of(f, n)
        m = mass_of(f, n)
        v = np.asarray(f.get("velocity", np.zeros((n, 3))), float)
        nf += 1
        k = len(ref)
        chunk = max(1, 2_000_000 // k)
        for a in range(0, n, chunk):
            b = slice(a, min(a + chunk, n))
            pts = (x[b, None, :] + r[b, None, None] * ref[None]).reshape(-1, 3)
            vi = np.repeat(4.0 / 3.0 * np.pi * r[b] ** 3 / k, k)
            mi = np.repeat(m[b] / k, k)
            vv = np.repeat(v[b], k, axis=0)
            out = _deposit(edges, pts, [vi, mi, mi * vv[:, 0], mi * vv[:, 1],
                                        mi * vv[:, 2]], shape)
            vol += out[0]
            mass += out[1]
            for c in range(3):
                mom[..., c] += out[2 + c]
    if nf == 0:
        raise ParameterError("no frame to average")
    cv = np.prod([e[1] - e[0] for e in edges])
    with np.errstate(invalid="ignore", divide="ignore"):
        vel = np.where(mass[..., None] > 0, mom / mass[..., None], np.nan)
    return Field(edges, vol / (cv * nf), mass / (cv * nf), vel, nf, method)


def _truncated_mass(c: float) -> float:
    """Mass of the 3-D unit Gaussian inside radius c (sigma units)."""
    return float(math.erf(c / math.sqrt(2)) - np.sqrt(2 / np.pi) * c * np.exp(-c * c / 2))


def coarse_grain(source: Any, width: float, cell: Any, lower: Any, upper: Any,
                 frames: Any = None, cutoff: float = 3.0) -> Field:
    """Time-averaged fields by coarse-graining with a Gaussian kernel of width ``width``.

    phi(r) = sum_i V_i W(r - r_i), rho(r) = sum_i m_i W(r - r_i), momentum density
    p(r) = sum_i m_i v_i W(r - r_i), velocity = p / rho, with
    W(r) = (2 pi w^2)^(-3/2) exp(-``|r|^2`` / (2 w^2)) cut at ``cutoff`` w and renormalised to
    integral 1 (Goldhirsch, I. 2010, "Stress, stress asymmetry and couple stress: from
    discrete particles to continuous fields", Granular Matter 12, 239-252; Weinhart, T.,
    Thornton, A. R., Luding, S., Bokhove, O. 2012, "From discrete particles to continuum
    fields near a boundary", Granular Matter 14, 289-294). Evaluated at the centres of the
    cells of size ``cell`` from ``lower`` to ``upper``, averaged over the frames (velocity:
    time-averaged momentum over time-averaged density). The fields are smooth on the scale
    w; w of about the particle diameter removes the layering of the particles while
    keeping gradients over a few diameters. Fields within ``cutoff`` w of the packing's
    edge are reduced by the kernel reaching outside.
    """
    from scipy.spatial import cKDTree

    if not width > 0:
        raise ParameterError(f"width={shown(width)} must be > 0 [m]")
    edges = _grid(lower, upper, cell)
    shape = tuple(len(e) - 1 for e in edges)
    cen = np.stack(np.meshgrid(*(0.5 * (e[1:] + e[:-1]) for e in edges), indexing="ij"),
                   axis=-1).reshape(-1, 3)
    gtree = cKDTree(cen)
    norm = (2 * np.pi * width**2) ** -1.5 / _truncated_mass(cutoff)
    phi = np.zeros(len(cen))
    rho = np.zeros(len(cen))
    mom = np.zeros((len(cen), 3))
    nf = 0
    for f in frames_of(source, frames):
        x = np.asarray(f["position"], float)
        n = len(x)
        r = radius_of(f, n)
        m = mass_of(f, n)
        v = np.asarray(f.get("velocity", np.zeros((n, 3))), float)
        nf += 1
        if n == 0:
            continue
        d = gtree.sparse_distance_matrix(cKDTree(x), cutoff * width, output_type="ndarray")
        w = norm * np.exp(-0.5 * (d["v"] / width) ** 2)
        g, i = d["i"], d["j"]
        phi += np.bincount(g, weights=w * (4.0 / 3.0 * np.pi * r[i] ** 3), minlength=len(cen))
        rho += np.bincount(g, weights=w * m[i], minlength=len(cen))
        for c in range(3):
            mom[:, c] += np.bincount(g, weights=w * m[i] * v[i, c], minlength=len(cen))
    if nf == 0:
        raise ParameterError("no frame to average")
    with np.errstate(invalid="ignore", divide="ignore"):
        vel = np.where(rho[:, None] > 0, mom / rho[:, None], np.nan)
    return Field(edges, (phi / nf).reshape(shape), (rho / nf).reshape(shape),
                 vel.reshape(shape + (3,)), nf, f"gaussian w={width:g}")
