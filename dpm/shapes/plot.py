"""Pictures of sphere clusters in their shape frame (matplotlib, optional dependency)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .cluster import ClusterShape


def plot_cluster(shape: ClusterShape, path: str | Path, title: str | None = None,
                 max_spheres: int = 1500) -> Path:
    """Draw the cluster's spheres in the shape frame with the frame's x (red), y (green)
    and z (blue) axes from the centre of mass, and save a PNG to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    cl = shape.cluster()
    c, r = cl.centres, cl.radii
    order = np.argsort(-r, kind="stable")[:max_spheres]
    fig = plt.figure(figsize=(4.2, 4.2), dpi=110)
    ax = fig.add_subplot(projection="3d")
    nu, nv = 14, 9
    u = np.linspace(0, 2 * np.pi, nu + 1)
    v = np.linspace(0, np.pi, nv + 1)
    sx = np.outer(np.cos(u), np.sin(v))
    sy = np.outer(np.sin(u), np.sin(v))
    sz = np.outer(np.ones_like(u), np.cos(v))
    unit = np.stack([sx, sy, sz], axis=-1)
    quads = []
    for k in order:
        pts = c[k] + r[k] * unit
        a, b = pts[:-1, :-1], pts[1:, :-1]
        cc, d = pts[1:, 1:], pts[:-1, 1:]
        quads.append(np.stack([a, b, cc, d], axis=2).reshape(-1, 4, 3))
    polys = np.concatenate(quads)
    normals = polys.mean(axis=1) - np.repeat(c[order], nu * nv, axis=0)
    normals /= np.maximum(np.linalg.norm(normals, axis=1), 1e-300)[:, None]
    light = np.array([-0.4, -0.5, 0.77])
    shade = 0.35 + 0.65 * np.clip(normals @ (light / np.linalg.norm(light)), 0, 1)
    base = np.array([0.80, 0.62, 0.38])
    colors = np.clip(shade[:, None] * base[None, :], 0, 1)
    coll = Poly3DCollection(polys, facecolors=colors, edgecolors="none", linewidths=0)
    ax.add_collection3d(coll)
    ext = float(np.max(np.abs(np.concatenate([c + r[:, None], c - r[:, None]]))))
    arrow = 1.35 * ext
    for k, col in enumerate(("tab:red", "tab:green", "tab:blue")):
        e = np.zeros(3)
        e[k] = arrow
        ax.plot([0, e[0]], [0, e[1]], [0, e[2]], color=col, lw=2.0, zorder=10)
        ax.text(*(1.08 * e), "xyz"[k], color=col, fontsize=11, fontweight="bold")
    lim = 1.25 * ext
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_zlim(-lim, lim)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=22, azim=-58)
    ax.set_axis_off()
    ax.set_title(title or f"{shape.describe()}\n{len(r)} spheres", fontsize=8)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight", pad_inches=0.05)
    plt.close(fig)
    return path
