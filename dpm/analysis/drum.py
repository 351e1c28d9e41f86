"""Free surface and dynamic angle of repose of the bed in a rotating drum."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import shown
from ._common import as_frame, radius_of, unit
from .fields import ball_points


@dataclass
class DrumSurface:
    """The bed surface in the drum's cross-section: ``across`` (bin centres, horizontal
    coordinate from the axis [m]), ``height`` (surface height above the axis [m], NaN in
    empty bins), the fitted line ``height = slope * across + intercept``, ``angle`` [deg]
    = atan(slope) against the horizontal (signed: positive when the surface rises towards
    +across, the direction ``up x axis``), and the basis (``horizontal``, ``up``)."""

    across: np.ndarray
    height: np.ndarray
    slope: float
    intercept: float
    angle: float
    horizontal: np.ndarray
    up: np.ndarray
    residual: float

    def __str__(self) -> str:
        return (f"dynamic angle of repose {abs(self.angle):.2f} deg (signed {self.angle:.2f}; "
                f"surface {self.intercept:+.4g} m at the axis, rms residual "
                f"{self.residual:.3g} m, {np.count_nonzero(np.isfinite(self.height))} bins)")


def drum_surface(source: Any, axis_point: Any, axis: Any, radius: float,
                 frame: int = -1, bins: int = 20, span: float = 0.7,
                 method: str = "highest", gravity: Any = (0.0, 0.0, -9.81),
                 threshold: float = 0.5) -> DrumSurface:
    """Free surface of the bed in a drum of ``radius`` turning about the line through
    ``axis_point`` along ``axis``, and its dynamic angle of repose.

    The bodies are projected onto the cross-section (coordinates ``across`` = (x - a).h,
    ``height`` = (x - a).u, with u the upward direction -g made normal to the axis and
    h = u x axis). The middle ``span`` of the diameter is cut into ``bins`` columns; in each
    the surface is

    - ``"highest"``: the top of the highest body (its centre height + radius);
    - ``"fraction"``: the highest point where the column's area fraction (the bodies'
      volume, sub-sampled as in :func:`dpm.analysis.voxel_fields`, in cells of the column
      width) is still at least ``threshold`` times the column's largest fraction.

    A straight line is fitted through the column surfaces by least squares; its angle
    against the horizontal is the dynamic angle of repose of a bed in the rolling regime,
    whose flat surface is the standard measure (Henein, H., Brimacombe, J. K., Watkinson,
    A. P. 1983, "Experimental study of transverse bed motion in rotary kilns", Metall.
    Trans. B 14, 191-205; Mellmann, J. 2001, "The transverse motion of solids in rotating
    cylinders - forms of motion and transition behavior", Powder Technol. 118, 251-270).
    In the cascading and cataracting regimes the surface is S-shaped or broken and a line
    is a rough summary: check ``residual`` and the column heights.
    """
    if method not in ("highest", "fraction"):
        raise ParameterError(f"method={method!r}; allowed: 'highest', 'fraction'")
    if not radius > 0 or not 0 < span <= 1 or bins < 2:
        raise ParameterError(f"radius={shown(radius)} must be > 0, span={shown(span)} in (0, 1], "
                             f"bins={shown(bins)} >= 2")
    f = as_frame(source, frame)
    a = np.asarray(axis_point, float).reshape(3)
    ax = unit(axis, "axis")
    g = unit(gravity, "gravity")
    up = -g - (-g @ ax) * ax
    if np.linalg.norm(up) < 1e-9:
        raise ParameterError("the drum axis is parallel to gravity: no horizontal surface")
    up /= np.linalg.norm(up)
    h = np.cross(up, ax)
    x = np.asarray(f["position"], float) - a
    r = radius_of(f, len(x))
    s, z = x @ h, x @ up
    edges = np.linspace(-span * radius, span * radius, bins + 1)
    col = np.searchsorted(edges, s, side="right") - 1
    ok = (col >= 0) & (col < bins)
    height = np.full(bins, np.nan)
    if method == "highest":
        top = z + r
        for k in range(bins):
            sel = ok & (col == k)
            if np.any(sel):
                height[k] = top[sel].max()
    else:
        dz = edges[1] - edges[0]
        zedges = np.arange(-radius, radius + dz, dz)
        ref = ball_points(3)
        pts = x[:, None, :] + r[:, None, None] * ref[None]
        ps, pz = (pts @ h).ravel(), (pts @ up).ravel()
        wv = np.repeat(r**3, len(ref))
        area, _, _ = np.histogram2d(ps, pz, bins=(edges, zedges), weights=wv)
        for k in range(bins):
            c = area[k]
            if c.max() <= 0:
                continue
            full = np.nonzero(c >= threshold * c.max())[0]
            j = full.max()
            # the height where the fraction crosses the threshold, within the cell
            nxt = c[j + 1] if j + 1 < len(c) else 0.0
            frac = (c[j] - threshold * c.max()) / max(c[j] - nxt, 1e-300)
            height[k] = zedges[j] + 0.5 * dz + min(max(frac, 0.0), 1.0) * dz
    centres = 0.5 * (edges[1:] + edges[:-1])
    good = np.isfinite(height)
    if np.count_nonzero(good) < 2:
        raise ParameterError("fewer than 2 columns of the cross-section hold bodies")
    slope, intercept = np.polyfit(centres[good], height[good], 1)
    res = height[good] - (slope * centres[good] + intercept)
    return DrumSurface(centres, height, float(slope), float(intercept),
                       float(np.degrees(np.arctan(slope))), h, up,
                       float(np.sqrt(np.mean(res**2))))


def angle_of_repose(source: Any, axis_point: Any, axis: Any, radius: float, **kw: Any
                    ) -> float:
    """The dynamic angle of repose [deg] (absolute) of :func:`drum_surface`."""
    return abs(drum_surface(source, axis_point, axis, radius, **kw).angle)
