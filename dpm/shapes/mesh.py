"""Any closed triangle mesh (STL/OBJ/PLY/... read by trimesh) as a sphere cluster."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._lazy import lazy_module
from ..errors import ParameterError
from ..parameters import Parameter
from .cluster import RESOLUTION, ClusterShape, MassProperties
from .geometry import mesh_inside_grid, triangle_distance

trimesh = lazy_module("trimesh")


class MeshShape(ClusterShape):
    """A closed (watertight) triangle mesh turned into a sphere cluster.

    Give ``path`` (any format trimesh reads: STL, OBJ, PLY, OFF, GLB) or ``mesh`` (a
    ``trimesh.Trimesh``), and ``scale`` (a factor applied to the mesh's coordinates, e.g.
    1e-3 for a mesh drawn in millimetres). Volume, centre of mass and inertia tensor are
    trimesh's mass properties of the mesh. The shape frame is the mesh's own axes moved
    to the centre of mass: a body's position is its centre of mass and an identity
    orientation keeps the mesh's axes. Inside test: ray parity along z on the voxel grid;
    depth: exact point-triangle distance.
    """

    name = "mesh"
    grid_jitter = True
    parameters = {
        "path": Parameter(default=None, kind="str", doc="mesh file (STL, OBJ, PLY, ...)"),
        "mesh": Parameter(default=None, kind="any", doc="a trimesh.Trimesh instead of path"),
        "scale": Parameter(default=1.0, low=0.0, low_open=True,
                           doc="factor applied to the mesh coordinates (to metres)"),
        "resolution": RESOLUTION,
    }

    def __init__(self, call: str | None = None, **params: Any) -> None:
        super().__init__(call=call, **params)
        self._source = self._load()
        props = self._source.mass_properties
        self.centre = np.asarray(props["center_mass"], float)
        self._mesh = self._source.copy()
        self._mesh.apply_translation(-self.centre)
        self._volume = float(props["volume"])
        self._tensor = np.asarray(props["inertia"], float)

    def check(self) -> list[str]:
        p = self.params
        if (p["path"] is None) == (p["mesh"] is None):
            return ["give exactly one of path (a mesh file) or mesh (a trimesh.Trimesh)"]
        if p["mesh"] is not None and not isinstance(p["mesh"], trimesh.Trimesh):
            return [f"mesh={type(p['mesh']).__name__} is not a trimesh.Trimesh"]
        return []

    def _load(self) -> trimesh.Trimesh:
        p = self.params
        if p["path"] is not None:
            from ..boundaries.mesh import check_stl

            check_stl(self.call, "path", p["path"])
            try:
                m = trimesh.load(str(p["path"]), force="mesh")
            except (OSError, ValueError) as exc:
                raise ParameterError(f"{self.call}: path={p['path']!r} cannot be read as a "
                                     f"mesh: {exc}") from exc
        else:
            m = p["mesh"].copy()
        if not isinstance(m, trimesh.Trimesh) or len(m.faces) == 0:
            raise ParameterError(f"{self.call}: {self._what()} holds no triangle mesh")
        m.apply_scale(float(p["scale"]))
        if not m.is_watertight:
            raise ParameterError(f"{self.call}: {self._what()} is not a closed (watertight) "
                                 "mesh; a solid needs one")
        if m.volume < 0:
            m.invert()
        if not m.is_volume:
            trimesh.repair.fix_normals(m)
        if not m.is_volume or m.volume <= 0:
            raise ParameterError(f"{self.call}: {self._what()} does not bound a volume "
                                 "(inconsistent winding or self-intersection)")
        return m

    def _what(self) -> str:
        p = self.params
        return f"path={p['path']!r}" if p["path"] is not None else "mesh"

    # the mass properties keep the mesh's centre of mass (in its own coordinates)
    def mass_properties(self) -> MassProperties:
        if "mass" not in self._cache:
            self._cache["mass"] = MassProperties.from_tensor(self._volume, self._tensor,
                                                             self.centre)
        return self._cache["mass"]

    def volume(self) -> float:
        return self._volume

    def inertia_tensor(self) -> np.ndarray:
        return self._tensor

    def bounds(self):
        return self._mesh.bounds[0], self._mesh.bounds[1]

    def inside_grid(self, xs, ys, zs):
        return mesh_inside_grid(self._mesh.triangles, xs, ys, zs)

    def inside(self, points):
        """Generalised winding number (exact for closed meshes, O(points x faces))."""
        p = np.asarray(points, float)
        tri = self._mesh.triangles
        out = np.empty(len(p), dtype=bool)
        step = max(1, 1_000_000 // len(tri))
        for i in range(0, len(p), step):
            a = tri[None, :, 0] - p[i:i + step, None]
            b = tri[None, :, 1] - p[i:i + step, None]
            c = tri[None, :, 2] - p[i:i + step, None]
            la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
            det = np.einsum("pfk,pfk->pf", a, np.cross(b, c))
            den = (la * lb * lc + np.einsum("pfk,pfk->pf", a, b) * lc
                   + np.einsum("pfk,pfk->pf", b, c) * la + np.einsum("pfk,pfk->pf", c, a) * lb)
            wn = np.sum(np.arctan2(det, den), axis=1) / (2 * np.pi)
            out[i:i + step] = wn > 0.5
        return out

    def depth(self, points):
        return triangle_distance(points, self._mesh.triangles)

    def mesh(self, fine: bool = False):
        """The mesh in the shape frame (centre of mass at the origin)."""
        return self._mesh.copy()

    def describe(self, resolution: bool = True) -> str:
        src = self.params["path"] if self.params["path"] is not None else "<trimesh>"
        res = f", resolution={self.resolution:g}" if resolution else ""
        return f"mesh({src}, scale={float(self.params['scale']):g}{res})"
