"""How close a sphere cluster is to its ideal solid: counts, volume and surface errors.

:func:`shape_report` measures one shape; :func:`report_table` prints the table that
``dpm shapes`` shows, for registered shape names (with parameters), library files and mesh
files at several resolutions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._lazy import lazy_module
from ..errors import ParameterError
from .base import Shape
from .cluster import ClusterShape
from .sphere import Sphere

trimesh = lazy_module("trimesh")

#: resolutions of the table when none are given
DEFAULT_RESOLUTIONS = (0.1, 0.3, 0.6, 1.0)
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf")


def union_distance(points: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Signed distance of points to the union of spheres: ``min_i(|p - c_i| - r_i)``."""
    p = np.asarray(points, float)
    out = np.empty(len(p))
    step = max(1, 2_000_000 // max(len(radii), 1))
    for i in range(0, len(p), step):
        d = np.linalg.norm(p[i:i + step, None, :] - centres[None], axis=2) - radii[None]
        out[i:i + step] = d.min(axis=1)
    return out


def _in_union(points: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    p = np.asarray(points, float)
    out = np.empty(len(p), dtype=bool)
    cc = np.einsum("ij,ij->i", centres, centres) - radii**2
    step = max(1, 4_000_000 // max(len(radii), 1))
    for i in range(0, len(p), step):
        q = p[i:i + step]
        d2 = np.einsum("ij,ij->i", q, q)[:, None] - 2.0 * q @ centres.T + cc[None]
        out[i:i + step] = (d2 <= 0).any(axis=1)
    return out


def cluster_surface_samples(centres: np.ndarray, radii: np.ndarray, count: int,
                            seed: int = 0) -> np.ndarray:
    """About ``count`` area-uniform points on the boundary of the union of spheres."""
    rng = np.random.default_rng(seed)
    area = radii**2
    n_try = 4 * count
    per = rng.multinomial(n_try, area / area.sum())
    owner = np.repeat(np.arange(len(radii)), per)
    v = rng.normal(size=(len(owner), 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    q = centres[owner] + radii[owner, None] * v
    # exposed: not strictly inside any other sphere
    cc = np.einsum("ij,ij->i", centres, centres)
    keep = np.ones(len(q), dtype=bool)
    step = max(1, 4_000_000 // max(len(radii), 1))
    for i in range(0, len(q), step):
        x = q[i:i + step]
        d2 = np.einsum("ij,ij->i", x, x)[:, None] - 2.0 * x @ centres.T + cc[None]
        inner = d2 < (radii**2)[None] * (1.0 - 1e-9)
        inner[np.arange(len(x)), owner[i:i + step]] = False
        keep[i:i + step] = ~inner.any(axis=1)
    q = q[keep]
    if len(q) > count:
        q = q[rng.choice(len(q), count, replace=False)]
    return q


def shape_report(shape: Shape, samples: int = 4000, volume_samples: int = 100_000,
                 seed: int = 1) -> dict[str, Any]:
    """Sphere count and shape errors of ``shape``'s cluster against its ideal solid.

    Keys: ``shape`` (description), ``resolution``, ``count`` (spheres), ``volume`` (ideal,
    m3), ``volume_union`` (Monte Carlo over the solid's bounding box, ``volume_samples``
    points), ``volume_ratio`` = union / ideal and ``volume_ratio_err`` (one standard
    error), ``r_eq`` (radius of the sphere of equal volume), surface deviations in metres
    -- ``dev_ideal_max``/``dev_ideal_rms`` from ``samples`` points on the ideal surface to
    the cluster surface (``|min_i |p - c_i| - r_i|``), ``dev_cluster_max``/``dev_cluster_rms``
    from ``samples`` points on the cluster surface to the ideal surface, ``dev_max`` and
    ``dev_rms`` over both sets --, ``r_min``/``r_max`` (element radii, m), ``tolerance``
    (the generator's surface tolerance, m), ``inscribed_radius`` (m) and ``seconds``
    (generation time). A plain sphere reports one element and no error.
    """
    if isinstance(shape, Sphere):
        r = float(np.max(shape.params["radius"]))
        v = 4.0 / 3.0 * math.pi * r**3
        return {"shape": f"sphere(radius={r:g})", "resolution": None, "count": 1,
                "volume": v, "volume_union": v, "volume_ratio": 1.0, "volume_ratio_err": 0.0,
                "r_eq": r, "dev_ideal_max": 0.0, "dev_ideal_rms": 0.0, "dev_cluster_max": 0.0,
                "dev_cluster_rms": 0.0, "dev_max": 0.0, "dev_rms": 0.0, "r_min": r,
                "r_max": r, "tolerance": 0.0, "inscribed_radius": r, "seconds": 0.0}
    if not isinstance(shape, ClusterShape):
        raise ParameterError(f"shape_report: {type(shape).__name__} is not a cluster shape")
    cl = shape.cluster()
    mp = shape.mass_properties()
    c, r = cl.centres, cl.radii
    vol = mp.volume
    r_eq = (3.0 * vol / (4.0 * math.pi)) ** (1.0 / 3.0)
    rng = np.random.default_rng(seed)
    lo, hi = (np.asarray(x, float) for x in shape.bounds())
    box = float(np.prod(hi - lo))
    pts = rng.uniform(lo, hi, size=(volume_samples, 3))
    frac = float(_in_union(pts, c, r).mean())
    ratio = frac * box / vol
    ratio_err = box / vol * math.sqrt(max(frac * (1.0 - frac), 1e-300) / volume_samples)
    ideal_pts, _ = trimesh.sample.sample_surface(shape.mesh(fine=True), samples, seed=seed)
    d_ideal = np.abs(union_distance(np.asarray(ideal_pts), c, r))
    cl_pts = cluster_surface_samples(c, r, samples, seed=seed)
    d_cluster = np.abs(shape.depth(cl_pts))
    both = np.concatenate([d_ideal, d_cluster])
    return {
        "shape": shape.describe(), "resolution": shape.resolution, "count": int(len(r)),
        "volume": vol, "volume_union": ratio * vol, "volume_ratio": ratio,
        "volume_ratio_err": ratio_err, "r_eq": r_eq,
        "dev_ideal_max": float(d_ideal.max()), "dev_ideal_rms": _rms(d_ideal),
        "dev_cluster_max": float(d_cluster.max()), "dev_cluster_rms": _rms(d_cluster),
        "dev_max": float(both.max()), "dev_rms": _rms(both),
        "r_min": float(r.min()), "r_max": float(r.max()), "tolerance": cl.tolerance,
        "inscribed_radius": cl.inscribed_radius, "seconds": cl.seconds,
    }


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x**2)))


# ------------------------------------------------------------------ the table
def _value(text: str) -> Any:
    if text.lower() == "none":
        return None
    try:
        return float(text)
    except ValueError:
        return text


def parse_spec(spec: str) -> tuple[str, dict[str, Any]]:
    """``"cylinder:r=1e-3,l=4e-3"`` -> ("cylinder", {"r": 0.001, "l": 0.004})."""
    name, _, rest = spec.partition(":")
    params: dict[str, Any] = {}
    for item in filter(None, (x.strip() for x in rest.split(","))):
        key, eq, val = item.partition("=")
        if not eq:
            raise ParameterError(f"dpm shapes: {item!r} in {spec!r} is not key=value")
        params[key.strip()] = _value(val.strip())
    return name.strip(), params


def resolve_shape(spec: str | Shape, resolution: float | None = None) -> Shape:
    """A shape from a table entry: a Shape, a registered name with optional parameters
    (``"torus:r1=1e-3,r2=4e-3"``), a library name (``"rock"``) or ``.json`` file, or a
    mesh file (``"grain.stl:scale=1e-3"``). ``resolution`` applies where it can."""
    if isinstance(spec, Shape):
        return spec
    from . import library
    from .mesh import MeshShape

    name, params = parse_spec(spec)
    if resolution is not None:
        params.setdefault("resolution", resolution)
    import dpm

    reg = dpm.registry()
    if name in reg.names("shape"):
        cls = reg.lookup("shape", name, "dpm shapes")
        if "resolution" not in getattr(cls, "parameters", {}):
            params.pop("resolution", None)
        return cls(call=f"dpm shapes {spec}", **params)
    path = Path(name)
    if path.suffix.lower() in MESH_SUFFIXES:
        return MeshShape(call=f"dpm shapes {spec}", path=str(path), **params)
    if path.suffix.lower() == ".json" or library.find(name) is not None:
        return library.load(name)
    raise ParameterError(
        f"dpm shapes: {spec!r} is neither a registered shape ({', '.join(reg.names('shape'))})"
        f", a library shape ({', '.join(library.names()) or 'none'}) nor a mesh or .json file")


def report_table(names_or_paths: Sequence[str | Shape],
                 resolutions: Sequence[float] | None = None, samples: int = 4000) -> str:
    """The table printed by ``dpm shapes``: one row per shape and resolution.

    ``names_or_paths``: registered shape names, optionally with parameters
    (``"block:a=4e-3,b=2e-3,c=1e-3"``; defaults otherwise), library names or ``.json``
    files (their stored resolution only), mesh files (``"grain.stl:scale=1e-3"``) or Shape
    instances. ``resolutions`` default to :data:`DEFAULT_RESOLUTIONS`. Columns: spheres,
    union volume / ideal volume (+- one standard error), surface deviation max and RMS as
    % of the equal-volume radius r_eq, smallest element radius (m and % of r_eq) and the
    generation time.
    """
    res_list = list(DEFAULT_RESOLUTIONS if resolutions is None else resolutions)
    header = ["shape", "res", "spheres", "V_union/V %", "dev max %", "dev RMS %",
              "r_min [m]", "r_min %", "gen s"]
    rows: list[list[str]] = []
    for spec in names_or_paths:
        seen: set[float | None] = set()
        for res in res_list:
            shape = resolve_shape(spec, res)
            fixed = not isinstance(shape, ClusterShape) or _fixed_resolution(shape)
            key = None if fixed else res
            if key in seen:
                continue
            seen.add(key)
            rep = shape_report(shape, samples=samples)
            req = rep["r_eq"]
            label = shape.describe(resolution=False) if isinstance(shape, ClusterShape) \
                else rep["shape"]
            rows.append([
                label, "-" if rep["resolution"] is None else f"{rep['resolution']:g}",
                str(rep["count"]),
                f"{100 * rep['volume_ratio']:.1f} ± {100 * rep['volume_ratio_err']:.1f}",
                f"{100 * rep['dev_max'] / req:.1f}", f"{100 * rep['dev_rms'] / req:.2f}",
                f"{rep['r_min']:.3g}", f"{100 * rep['r_min'] / req:.1f}",
                f"{rep['seconds']:.2f}",
            ])
    widths = [max(len(h), *(len(r[k]) for r in rows)) if rows else len(h)
              for k, h in enumerate(header)]

    def line(cells: list[str]) -> str:
        return "| " + " | ".join(c.ljust(w) if k == 0 else c.rjust(w)
                                 for k, (c, w) in enumerate(zip(cells, widths, strict=True))) + " |"

    sep = "|" + "|".join("-" * (w + 1) + (":" if k else "-")
                         for k, w in enumerate(widths)) + "|"
    out = [line(header), sep] + [line(r) for r in rows]
    note = ("dev: surface deviation between the cluster and the ideal surface (both ways), "
            "in % of r_eq, the radius of the sphere of equal volume")
    return "\n".join(out) + "\n\n" + note


def _fixed_resolution(shape: ClusterShape) -> bool:
    from .library import LibraryShape

    return isinstance(shape, LibraryShape)
