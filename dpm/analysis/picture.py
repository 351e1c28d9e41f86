"""A picture of the particles of one frame, coloured by a field, with the boundaries'
surfaces (matplotlib, optional)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DpmError, ParameterError
from ._common import AXES, as_frame, frame_index, is_run, radius_of

COLORS = {"speed": "speed [m/s]", "x": "x [m]", "y": "y [m]", "z": "z [m]",
          "material": "material", "id": "id", "radius": "radius [m]"}


def _pyplot() -> Any:
    try:
        import matplotlib
    except ImportError:
        raise DpmError("dpm.analysis.picture needs matplotlib: pip install 'dpm-granular[plot]' "
                       "(or pip install matplotlib)") from None
    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg", "ps", "cairo"):
        try:
            matplotlib.use("Agg")
        except Exception:  # a GUI backend already running: keep it
            pass
    import matplotlib.pyplot as plt

    return plt


#: the angle between two triangles' planes above which their common edge is drawn
FEATURE_ANGLE = 30.0
#: faces and edges of the boundaries (RGBA)
FACE_RGBA = (0.55, 0.55, 0.6, 0.10)
EDGE_RGBA = (0.25, 0.25, 0.3, 0.7)


def boundary_triangles(source: Any, frame: int = -1) -> dict[str, np.ndarray] | None:
    """The boundaries' surfaces at ``frame`` of a run (``/boundaries/surface`` on the
    triangles ``/surfaces/faces``, what ``run.boundaries.xdmf`` shows) or at a
    Simulation's current time: ``triangles`` (T, 3, 3) [m], ``boundary`` (T,) the index
    of each triangle's boundary, ``plane`` (T,) bool (a triangle of an infinite plane,
    drawn as a square over the particles). None for a frame dict, a file without
    surfaces or a scene without boundaries."""
    from ._common import is_sim

    if is_run(source):
        from ..io.hdf5 import _open

        if len(source.times) == 0:
            return None
        k = frame_index(source, frame)
        with _open(source.path) as f:
            if "surfaces" not in f or not len(f["surfaces/faces"]):
                return None
            faces = f["surfaces/faces"][:]
            owner = f["surfaces/boundary"][:]
            xyz = f["boundaries/surface"][k]
        scene = source.scene or {}
        kinds = [b.get("kind") for b in scene.get("boundaries", [])]
    elif is_sim(source):
        if not len(source.boundaries):
            return None
        from ..io.hdf5 import boundary_surfaces
        from ..io.surfaces import world
        from ..motion import frames as motion_frames

        local, faces, owner, vowner = boundary_surfaces(source)
        if not len(faces):
            return None
        xyz = np.zeros_like(local)
        for b, bd in enumerate(source.boundaries):
            pose = motion_frames(getattr(bd, "motion", None), np.array([source.time]))[0, :12]
            sel = vowner == b
            xyz[sel] = world(local[sel], pose)
        kinds = [bd.name for bd in source.boundaries]
    else:
        return None
    owner = np.asarray(owner, np.int64)
    plane = np.array([0 <= b < len(kinds) and kinds[b] == "plane" for b in owner], bool)
    return {"triangles": np.asarray(xyz, float)[np.asarray(faces, np.int64)],
            "boundary": owner, "plane": plane}


def feature_edges(triangles: np.ndarray, angle: float = FEATURE_ANGLE) -> np.ndarray:
    """(E, 2, 3) the edges of a triangle surface worth drawing: those of one triangle
    only (an open rim) and those between two triangles whose planes meet at more than
    ``angle`` degrees (a box's edges, not the diagonals of its faces nor the facets of
    a tube)."""
    t = np.asarray(triangles, float).reshape(-1, 3, 3)
    # (a degenerate triangle, as the fan of a disc's centre has, is no face)
    t = t[np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1) > 0]
    if not len(t):
        return np.zeros((0, 2, 3))
    # vertices by value (a triangle soup: each boundary's own vertices)
    pts, inv = np.unique(t.reshape(-1, 3), axis=0, return_inverse=True)
    tri = inv.reshape(-1, 3)
    normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    length = np.linalg.norm(normal, axis=1)
    normal = np.divide(normal, length[:, None], out=np.zeros_like(normal),
                       where=length[:, None] > 0)
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    owner = np.tile(np.arange(len(tri)), 3)
    edges.sort(axis=1)
    key, first, inverse, count = np.unique(edges, axis=0, return_index=True,
                                           return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    keep = count == 1
    # two triangles on an edge: compare their normals (orientation ignored)
    pair = np.flatnonzero(count == 2)
    if len(pair):
        faces_of = np.full((len(key), 2), -1)
        order = np.argsort(inverse, kind="stable")
        starts = np.concatenate([[0], np.cumsum(count)[:-1]])
        faces_of[pair, 0] = owner[order[starts[pair]]]
        faces_of[pair, 1] = owner[order[starts[pair] + 1]]
        dot = np.abs(np.einsum("ij,ij->i", normal[faces_of[pair, 0]],
                               normal[faces_of[pair, 1]]))
        keep[pair] = dot < np.cos(np.radians(angle))
    keep |= count > 2
    return pts[key[keep]]


def _draw_boundaries(ax: Any, b: dict[str, np.ndarray], view: str) -> Any:
    """Add the boundaries' faces (a translucent collection labelled ``"boundaries"``)
    and feature edges (``"boundary edges"``) to ``ax``; returns the faces' collection."""
    tris, edges = b["triangles"], feature_edges(b["triangles"])
    if view == "3d":
        from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

        # (drawn under the particles: ax.computed_zorder is off)
        faces = Poly3DCollection(tris, facecolors=[FACE_RGBA], edgecolors="none",
                                 linewidths=0.0, label="boundaries", zorder=0.5)
        ax.add_collection3d(faces)
        lines = Line3DCollection(edges, colors=[EDGE_RGBA], linewidths=0.6,
                                 label="boundary edges", zorder=0.6)
        ax.add_collection3d(lines)
        return faces
    from matplotlib.collections import LineCollection, PathCollection
    from matplotlib.path import Path as MplPath

    i, j = AXES[view[0]], AXES[view[1]]
    # an infinite plane is drawn where it is seen edge on (a floor in a side view), not
    # as the square that stands for it in a view across it
    normal = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    length = np.maximum(np.linalg.norm(normal, axis=1), 1e-300)
    across = b["plane"] & (np.abs(normal[:, 3 - i - j]) / length > 0.1)
    if across.any():
        tris = tris[~across]
        edges = feature_edges(tris)
    # the projected triangles as one path, all turned counter-clockwise: filled once by
    # the non-zero rule (no seams along shared edges, no darker overlaps)
    t2 = tris[:, :, [i, j]]
    area = ((t2[:, 1, 0] - t2[:, 0, 0]) * (t2[:, 2, 1] - t2[:, 0, 1])
            - (t2[:, 2, 0] - t2[:, 0, 0]) * (t2[:, 1, 1] - t2[:, 0, 1]))
    t2 = np.where((area < 0)[:, None, None], t2[:, ::-1], t2)
    verts = np.concatenate([t2, t2[:, :1]], axis=1).reshape(-1, 2)
    codes = np.tile([MplPath.MOVETO, MplPath.LINETO, MplPath.LINETO, MplPath.CLOSEPOLY],
                    len(t2))
    faces = PathCollection([MplPath(verts, codes)], facecolors=[FACE_RGBA],
                           edgecolors="none", linewidths=0.0, label="boundaries",
                           zorder=0.5, transform=ax.transData)
    faces.set_offset_transform(None)
    ax.add_collection(faces, autolim=False)
    ax.add_collection(LineCollection(edges[:, :, [i, j]], colors=[EDGE_RGBA],
                                     linewidths=0.6, label="boundary edges", zorder=0.6),
                      autolim=False)
    return faces


def picture(source: Any, frame: int = -1, color: str = "speed", view: str = "xz",
            path: str | Path | None = "frame.png", cmap: str = "viridis",
            size: tuple[float, float] = (7.0, 5.5), dpi: int = 150,
            limits: Any = None, title: str | None = None, boundaries: bool = True) -> Any:
    """Draw the particles of ``frame`` of a run (or a Simulation's current state, or a
    frame dict) coloured by ``color`` (``speed``, ``x``, ``y``, ``z``, ``material``,
    ``id``, ``radius``) and save it to ``path`` (PNG, or any format matplotlib writes by
    the suffix; ``None``: do not save). Returns the matplotlib figure.

    ``view``: two axis letters (``"xz"``, ``"xy"``, ``"yz"``, ...) for a projection
    along the third axis, drawn back to front, each particle a disc of its true radius
    (marker sizes from the axes' scale); or ``"3d"`` for a 3-D scatter in a cube: every
    axis has the same range, so lengths compare in every direction (marker sizes from the
    view's scale at the cube's centre: approximate, the view has perspective). The colour
    bar carries the field's unit.
    ``limits``: ((lo1, hi1), (lo2, hi2)) of the projected view (default: the particles'
    and the boundaries' extent, planes excepted: an infinite plane is drawn as a square
    over the particles, cut at the view's edge).

    ``boundaries`` (default True): draw the boundaries' surfaces of a run's frame (the
    file's ``/boundaries/surface``, the triangles ``run.boundaries.xdmf`` shows) or of a
    Simulation, as translucent faces (the collection labelled ``"boundaries"``) and
    their edges (``"boundary edges"``: rims and creases, not the diagonals of flat
    faces). Needs matplotlib (the ``plot`` extra).
    """
    if color not in COLORS:
        raise ParameterError(f"color={color!r}; allowed: {', '.join(COLORS)}")
    plt = _pyplot()
    f = as_frame(source, frame)
    x = np.asarray(f["position"], float)
    n = len(x)
    r = radius_of(f, n).astype(float)
    if color == "speed":
        c = np.linalg.norm(np.asarray(f["velocity"], float), axis=1)
    elif color in ("x", "y", "z"):
        c = x[:, AXES[color]]
    elif color == "radius":
        c = r
    else:
        c = np.asarray(f[color])
    label = COLORS[color]
    names = None
    if color == "material" and is_run(source):
        names = [m.decode() if isinstance(m, bytes) else str(m)
                 for m in source.attrs.get("materials", [])]
    bnd = boundary_triangles(source, frame) if boundaries else None
    fig = plt.figure(figsize=size, dpi=dpi)
    t = f.get("time")
    title = title if title is not None else (f"t = {t:.4g} s, {n} particles"
                                             if t is not None else f"{n} particles")
    discrete = color in ("material",)
    norm = None
    if discrete and n:
        levels = np.unique(c)
        cm = plt.get_cmap("tab10" if len(levels) <= 10 else cmap, max(len(levels), 1))
        lut = {v: k for k, v in enumerate(levels)}
        cvals = np.array([lut[v] for v in c])
        norm = plt.Normalize(-0.5, len(levels) - 0.5)
    else:
        cm = plt.get_cmap(cmap)
        cvals = c
    if view == "3d":
        ax = fig.add_subplot(projection="3d")
        ax.computed_zorder = False  # (the boundaries under the particles)
        s = 20.0 * (r / max(float(r.max()), 1e-300)) ** 2 if n else 1.0
        sc = ax.scatter(x[:, 0], x[:, 1], x[:, 2], c=cvals, s=s, cmap=cm, norm=norm,
                        depthshade=True, linewidths=0)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
        pts = [x - r.max(), x + r.max()] if n else []
        if bnd is not None:
            _draw_boundaries(ax, bnd, view)
            pts.append(bnd["triangles"].reshape(-1, 3))
        if pts:  # a cube about everything drawn: equal ranges, equal scales
            allp = np.concatenate(pts)
            lo, hi = allp.min(axis=0), allp.max(axis=0)
            half = 0.5 * max(float(np.max(hi - lo)), 1e-12)
            mid = 0.5 * (lo + hi)
            ax.set_xlim3d(mid[0] - half, mid[0] + half)
            ax.set_ylim3d(mid[1] - half, mid[1] + half)
            ax.set_zlim3d(mid[2] - half, mid[2] + half)
            ax.set_box_aspect((1.0, 1.0, 1.0))
    else:
        if len(view) != 2 or any(a not in AXES for a in view) or view[0] == view[1]:
            raise ParameterError(f"view={view!r}; allowed: two of x, y, z ('xz') or '3d'")
        i, j = AXES[view[0]], AXES[view[1]]
        k = 3 - i - j
        ax = fig.add_subplot()
        if limits is None:
            pts = [x[:, [i, j]] - r.max(), x[:, [i, j]] + r.max()] if n else []
            pad = 0.0
            if bnd is not None and (~bnd["plane"]).any():
                pts.append(bnd["triangles"][~bnd["plane"]].reshape(-1, 3)[:, [i, j]])
                pad = 0.02  # (the boundaries' edges inside the frame)
            if pts:
                allp = np.concatenate(pts)
                lo, hi = allp.min(axis=0), allp.max(axis=0)
                pad *= float(np.max(hi - lo))
                limits = ((lo[0] - pad, hi[0] + pad), (lo[1] - pad, hi[1] + pad))
            else:
                limits = ((0, 1), (0, 1))
        if bnd is not None:
            _draw_boundaries(ax, bnd, view)
        ax.set_xlim(*limits[0])
        ax.set_ylim(*limits[1])
        ax.set_aspect("equal")
        ax.set_xlabel(f"{view[0]} [m]")
        ax.set_ylabel(f"{view[1]} [m]")
        # looking along -k for the right-handed pair (i, j), so draw from low k up
        handed = np.cross(np.eye(3)[i], np.eye(3)[j])[k]
        order = np.argsort(x[:, k] * handed)
        sc = ax.scatter(x[order, i], x[order, j], c=np.asarray(cvals)[order], s=1.0,
                        cmap=cm, norm=norm, edgecolors="k", linewidths=0.2)
    ax.set_title(title)
    cb = fig.colorbar(sc, ax=ax, label=label, shrink=0.8, pad=0.12 if view == "3d" else 0.05)
    if view != "3d":
        # marker size (points^2) of a disc of radius r, from the axes' final points per
        # metre (the colour bar has taken its room)
        fig.canvas.draw()
        bbox = ax.get_window_extent()
        per_m = min(bbox.width / (limits[0][1] - limits[0][0]),
                    bbox.height / (limits[1][1] - limits[1][0])) * 72.0 / fig.dpi
        sc.set_sizes((2.0 * r[order] * per_m) ** 2)
    elif n:
        # the view's scale at the cube's centre: an orthonormal triad projects onto the
        # screen with squared lengths summing to 2 scale^2 (perspective: approximate)
        from mpl_toolkits.mplot3d import proj3d

        fig.canvas.draw()
        lims = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
        mid, half = lims.mean(axis=1), 0.5 * float(lims[0, 1] - lims[0, 0])
        ends = np.vstack([mid, mid + half * np.eye(3)])
        px, py, _ = proj3d.proj_transform(ends[:, 0], ends[:, 1], ends[:, 2], ax.get_proj())
        disp = ax.transData.transform(np.column_stack([px, py]))
        per_m = (np.sqrt(np.sum((disp[1:] - disp[0]) ** 2) / 2.0) / half
                 * 72.0 / fig.dpi)
        sc.set_sizes((2.0 * r * per_m) ** 2)
    if discrete and n:
        cb.set_ticks(range(len(levels)))
        cb.set_ticklabels([names[int(v)] if names and 0 <= int(v) < len(names) else
                           str(int(v)) for v in levels])
    if path is not None:
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return fig
