"""A body from a given list of spheres (LIGGGHTS' ``particletemplate/multisphere``).

``Multisphere(centres=[[x, y, z], ...], radii=[r, ...])``: the elements are the spheres
given; the solid is their union, whose mass properties (volume, centre of mass, inertia)
are computed once per shape by the divergence theorem on the union's surface:

    V = 1/3 oint x.n dA,  V c_k = 1/4 oint (x.n) x_k dA,  S_kl = 1/5 oint (x.n) x_k x_l dA

over the parts of each sphere's surface that lie inside no other sphere. On each circle
of latitude of a sphere the covered arcs are exact (another sphere covers one arc,
``A + B cos(phi - phi0) < 0``); the uncovered arcs are integrated by Gauss-Legendre in
phi, the latitudes by Gauss-Legendre in a cosine-mapped variable between the latitudes
where an intersection circle starts or ends (the square-root ends there become smooth).
Non-overlapping spheres and a single sphere come out exact to rounding; overlapping ones
to about 1e-10 relative (``tests/objects/test_multisphere.py`` against 1-D integrals of
collinear unions and a Monte-Carlo estimate). LIGGGHTS samples the union by Monte Carlo
(``ntry``) instead.

The shape frame is the frame of the given coordinates moved to the centre of mass;
``mass_properties().centre`` is the centre of mass in the given coordinates. A sphere
inside another adds nothing to the mass; it still is an element.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..parameters import Parameter, numeric_array
from .cluster import Cluster, ClusterShape, MassProperties
from .metrics import _in_union

#: Gauss-Legendre nodes per uncovered arc (phi) and per latitude band (mapped u)
ARC_NODES = 24
BAND_NODES = 48


class Multisphere(ClusterShape):
    """A rigid body made of the spheres ``centres`` (k, 3) [m] and ``radii`` (k,) [m],
    with the mass properties of their union (see the module docstring)."""

    name = "multisphere"
    parameters = {
        "centres": Parameter(kind="any", unit="m", doc="sphere centres, (k, 3)"),
        "radii": Parameter(kind="any", unit="m", doc="sphere radii, (k,)"),
        "resolution": Parameter(default=1.0, low=0.0, high=1.0, low_open=True,
                                doc="unused: the elements are the spheres given"),
    }

    def check(self) -> list[str]:
        c = numeric_array(self.params["centres"])
        r = numeric_array(self.params["radii"])
        if c is None or c.ndim != 2 or c.shape[1] != 3 or len(c) == 0:
            return [f"centres={self.params['centres']!r} must be a list of 3-vectors "
                    "(numbers) [m]"]
        if r is None or r.ndim > 1:
            return [f"radii={self.params['radii']!r} must be a list of numbers [m]"]
        r = np.broadcast_to(r, (len(c),)) if r.ndim == 0 else r
        if len(r) != len(c):
            return [f"radii has {len(r)} values for {len(c)} centres"]
        if not np.all(np.isfinite(c)) or not np.all(np.isfinite(r)) or np.any(r <= 0):
            return [f"radii={r.tolist()!r} and centres must be finite, radii > 0"]
        self._c, self._r = c.astype(float), r.astype(float)
        return []

    # the solid: the union of the spheres, in the shape frame (centre of mass at 0)
    def _frame(self) -> tuple[np.ndarray, np.ndarray]:
        return self._c - self.mass_properties().centre, self._r

    def volume(self) -> float:
        return self.mass_properties().volume

    def inertia_tensor(self) -> np.ndarray:
        return self.mass_properties().tensor

    def bounds(self):
        c, r = self._frame()
        return (c - r[:, None]).min(axis=0), (c + r[:, None]).max(axis=0)

    def inside(self, points):
        c, r = self._frame()
        return _in_union(np.asarray(points, float), c, r)

    def depth(self, points):
        """``max_i (r_i - |p - c_i|)``: the depth below the deepest sphere (a lower bound of
        the union's depth near the seams)."""
        c, r = self._frame()
        p = np.asarray(points, float)
        return np.max(r[None] - np.linalg.norm(p[:, None] - c[None], axis=2), axis=1)

    def mesh(self, fine: bool = False):
        """The spheres' surfaces, overlapping (for pictures: not a closed union)."""
        import trimesh

        c, r = self._frame()
        parts = [trimesh.creation.icosphere(subdivisions=3 if fine else 2, radius=ri)
                 .apply_translation(ci) for ci, ri in zip(c, r, strict=True)]
        return trimesh.util.concatenate(parts)

    def mass_properties(self) -> MassProperties:
        if "mass" not in self._cache:
            vol, centre, second = union_moments(self._c, self._r)
            s = second - vol * np.outer(centre, centre)  # about the centre of mass
            tensor = np.trace(s) * np.eye(3) - s
            self._cache["mass"] = MassProperties.from_tensor(vol, tensor, centre)
        return self._cache["mass"]

    def cluster(self) -> Cluster:
        if "cluster" not in self._cache:
            c, r = self._frame()
            self._cache["cluster"] = Cluster(
                centres=c, radii=r.copy(), inscribed_radius=float(r.max()), tolerance=0.0,
                min_radius=float(r.min()), samples=0, seconds=0.0)
        return self._cache["cluster"]

    def describe(self, resolution: bool = True) -> str:
        return f"multisphere({len(self._r)} spheres)"


def union_moments(centres: np.ndarray, radii: np.ndarray) -> tuple[float, np.ndarray,
                                                                   np.ndarray]:
    """Volume V, centre of mass and second moment S = int x x^T dV (about the origin of
    the given coordinates) of the union of the spheres (the module docstring)."""
    cr = np.unique(np.column_stack([np.asarray(centres, float).reshape(-1, 3),
                                    np.asarray(radii, float).reshape(-1)]), axis=0)
    c, r = cr[:, :3], cr[:, 3]  # (equal copies count once)
    origin = c.mean(axis=0)  # (moments about a central point: less cancellation)
    c = c - origin
    vol, first, second = 0.0, np.zeros(3), np.zeros((3, 3))
    gx, gw = np.polynomial.legendre.leggauss(ARC_NODES)
    tx, tw = np.polynomial.legendre.leggauss(BAND_NODES)
    for i in range(len(r)):
        d = c[i] - c  # from each other centre to this one
        others = np.flatnonzero(np.arange(len(r)) != i)
        dist = np.linalg.norm(d, axis=1)
        if np.any(dist[others] + r[i] <= r[others]):
            continue  # inside another sphere
        # the latitudes where an intersection circle starts or ends split the bands
        breaks = [-1.0, 1.0]
        for j in others:
            if dist[j] == 0:
                continue
            cos_b = (dist[j] ** 2 + r[i] ** 2 - r[j] ** 2) / (2 * r[i] * dist[j])
            if abs(cos_b) >= 1:
                continue
            theta = math.acos(max(-1.0, min(1.0, -d[j, 2] / dist[j])))
            beta = math.acos(cos_b)
            breaks += [math.cos(theta - beta), math.cos(theta + beta)]
        breaks = np.unique(np.clip(breaks, -1.0, 1.0))
        for u0, u1 in zip(breaks[:-1], breaks[1:], strict=True):
            if u1 - u0 <= 1e-15:
                continue
            # u = u0 + (u1 - u0) (1 - cos t) / 2, t in [0, pi]: smooth at both ends
            t = 0.5 * np.pi * (tx + 1.0)
            us = u0 + (u1 - u0) * 0.5 * (1.0 - np.cos(t))
            ws = tw * 0.5 * np.pi * (u1 - u0) * 0.5 * np.sin(t)
            for u, w in zip(us, ws, strict=True):
                arcs = _uncovered(u, i, c, r, d, others)
                if not arcs:
                    continue
                rho = r[i] * math.sqrt(max(0.0, 1.0 - u * u))
                phis, pw = [], []
                for a0, a1 in arcs:
                    phis.append(a0 + (a1 - a0) * 0.5 * (gx + 1.0))
                    pw.append(gw * 0.5 * (a1 - a0))
                phi, wphi = np.concatenate(phis), np.concatenate(pw) * w * r[i] ** 2
                n = np.column_stack([rho / r[i] * np.cos(phi), rho / r[i] * np.sin(phi),
                                     np.full(len(phi), u)])
                x = c[i] + r[i] * n
                xn = np.einsum("ij,ij->i", x, n) * wphi
                vol += xn.sum() / 3.0
                first += (xn[:, None] * x).sum(axis=0) / 4.0
                second += np.einsum("i,ij,ik->jk", xn, x, x) / 5.0
    centre = first / vol
    # back to the given coordinates
    second = second + np.outer(first, origin) + np.outer(origin, first) \
        + vol * np.outer(origin, origin)
    return float(vol), centre + origin, second


def _uncovered(u: float, i: int, c: np.ndarray, r: np.ndarray, d: np.ndarray,
               others: np.ndarray) -> list[tuple[float, float]]:
    """Arcs [phi0, phi1] of the latitude u of sphere i that lie inside no other sphere."""
    w = math.sqrt(max(0.0, 1.0 - u * u))
    covered = []
    for j in others:
        a = d[j] @ d[j] + r[i] ** 2 - r[j] ** 2 + 2 * r[i] * d[j, 2] * u
        b = 2 * r[i] * w * math.hypot(d[j, 0], d[j, 1])
        if a + b <= 0:  # the whole circle inside sphere j
            return []
        if a - b >= 0:  # none of it
            continue
        half = math.pi - math.acos(max(-1.0, min(1.0, -a / b)))  # covered half-width
        mid = math.atan2(d[j, 1], d[j, 0]) + math.pi
        lo = (mid - half) % (2 * math.pi)
        hi = lo + 2 * half
        if hi > 2 * math.pi:
            covered += [(lo, 2 * math.pi), (0.0, hi - 2 * math.pi)]
        else:
            covered.append((lo, hi))
    covered.sort()
    out, at = [], 0.0
    for lo, hi in covered:
        if lo > at:
            out.append((at, lo))
        at = max(at, hi)
    if at < 2 * math.pi:
        out.append((at, 2 * math.pi))
    return [(a0, a1) for a0, a1 in out if a1 - a0 > 1e-15]


def multisphere(centres: Any, radii: Any) -> Multisphere:
    """``Multisphere(centres=..., radii=...)``."""
    return Multisphere(centres=centres, radii=radii)
