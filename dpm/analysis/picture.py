"""A picture of the particles of one frame, coloured by a field (matplotlib, optional)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import DpmError, ParameterError
from ._common import AXES, as_frame, is_run, radius_of

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


def picture(source: Any, frame: int = -1, color: str = "speed", view: str = "xz",
            path: str | Path | None = "frame.png", cmap: str = "viridis",
            size: tuple[float, float] = (7.0, 5.5), dpi: int = 150,
            limits: Any = None, title: str | None = None) -> Any:
    """Draw the particles of ``frame`` of a run (or a Simulation's current state, or a
    frame dict) coloured by ``color`` (``speed``, ``x``, ``y``, ``z``, ``material``,
    ``id``, ``radius``) and save it to ``path`` (PNG, or any format matplotlib writes by
    the suffix; ``None``: do not save). Returns the matplotlib figure.

    ``view``: two axis letters (``"xz"``, ``"xy"``, ``"yz"``, ...) for a projection
    along the third axis, drawn back to front, each particle a disc of its true radius
    (marker sizes from the axes' scale); or ``"3d"`` for a 3-D scatter (marker sizes
    proportional to the radius, approximate). The colour bar carries the field's unit.
    ``limits``: ((lo1, hi1), (lo2, hi2)) of the projected view (default: the particles'
    extent). Needs matplotlib (the ``plot`` extra).
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
        s = 20.0 * (r / max(float(r.max()), 1e-300)) ** 2 if n else 1.0
        sc = ax.scatter(x[:, 0], x[:, 1], x[:, 2], c=cvals, s=s, cmap=cm, norm=norm,
                        depthshade=True, linewidths=0)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
        if n:
            lo, hi = x.min(axis=0) - r.max(), x.max(axis=0) + r.max()
            ax.set_box_aspect(tuple(np.maximum(hi - lo, 1e-12)))
    else:
        if len(view) != 2 or any(a not in AXES for a in view) or view[0] == view[1]:
            raise ParameterError(f"view={view!r}; allowed: two of x, y, z ('xz') or '3d'")
        i, j = AXES[view[0]], AXES[view[1]]
        k = 3 - i - j
        ax = fig.add_subplot()
        if limits is None and n:
            pad = float(r.max())
            limits = ((x[:, i].min() - pad, x[:, i].max() + pad),
                      (x[:, j].min() - pad, x[:, j].max() + pad))
        elif limits is None:
            limits = ((0, 1), (0, 1))
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
    if discrete and n:
        cb.set_ticks(range(len(levels)))
        cb.set_ticklabels([names[int(v)] if names and 0 <= int(v) < len(names) else
                           str(int(v)) for v in levels])
    if path is not None:
        fig.savefig(path, dpi=dpi, bbox_inches="tight")
    return fig
