"""Ready-made sphere clusters stored as files (``dpm/shapes/grains/``, installed with dpm).

File format (``<name>.json``, UTF-8 JSON, SI units; format name ``dpm-sphere-cluster``,
version 1) with the source mesh ``<name>.stl`` beside it::

    {
      "format": "dpm-sphere-cluster", "version": 1,
      "name": "rock", "description": "...",
      "shape": {"name": "mesh", "params": {...}},   # how the cluster was made
      "resolution": 0.3,
      "source_mesh": "rock.stl",                    # shape frame, centre of mass at 0
      "source_centre_of_mass": [x, y, z],           # in the mesh's original coordinates
      "volume": V,                                  # m3
      "inertia_tensor_per_density": [[...]] ,       # m5, about the centre of mass, shape frame
      "principal_moments_per_density": [I1, I2, I3],# m5, ascending
      "principal_rotation": [w, x, y, z],           # principal frame -> shape frame
      "elements": {"offset": [[x, y, z], ...],      # m, principal frame, centre of mass at 0
                   "radius": [r, ...]},             # m
      "report": {...}                               # dpm.shapes.metrics.shape_report
    }

Mass and inertia of a body are the per-density values times the material density. The
shape frame is that of the generating shape (documented in ``docs/shapes.md``) or the
mesh's own axes moved to its centre of mass; ``offset_shape = R(q) offset_principal``.

:func:`load` returns a :class:`LibraryShape` for ``sim.add_particles(shape, ...)``;
:func:`save` writes any cluster shape.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter
from .cluster import Cluster, ClusterShape, MassProperties
from .geometry import matrix_from_quaternion

FORMAT = "dpm-sphere-cluster"
VERSION = 1
#: the library folder (package data: installed with dpm)
LIBRARY_DIR = Path(__file__).resolve().parent / "grains"


def names() -> list[str]:
    """Names of the shapes in :data:`LIBRARY_DIR`."""
    if not LIBRARY_DIR.is_dir():
        return []
    return sorted(p.stem for p in LIBRARY_DIR.glob("*.json"))


def find(name_or_path: str | Path) -> Path | None:
    """The ``.json`` file of a library name or path, or None."""
    p = Path(name_or_path)
    if p.suffix.lower() == ".json" and p.is_file():
        return p
    q = LIBRARY_DIR / f"{name_or_path}.json"
    return q if q.is_file() else None


def _json_safe(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.floating | np.integer):
        return v.item()
    if isinstance(v, dict):
        return {k: _json_safe(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_json_safe(x) for x in v]
    return v


def save(shape: ClusterShape, path: str | Path, name: str | None = None,
         description: str = "", report: dict[str, Any] | None = None) -> Path:
    """Write ``shape``'s cluster and mass properties to ``path`` (.json) and its mesh
    beside it (.stl, shape frame). Returns the JSON path."""
    path = Path(path).with_suffix(".json")
    path.parent.mkdir(parents=True, exist_ok=True)
    mp = shape.mass_properties()
    mesh_path = path.with_suffix(".stl")
    shape.mesh(fine=False).export(mesh_path)
    params = {k: v for k, v in shape.params.items() if k not in ("mesh",) and v is not None}
    if "path" in params:
        params["path"] = Path(str(params["path"])).name
    doc = {
        "format": FORMAT, "version": VERSION,
        "name": name or path.stem, "description": description,
        "shape": {"name": getattr(shape, "source_name", shape.name), "params": params},
        "resolution": shape.resolution,
        "source_mesh": mesh_path.name,
        "source_centre_of_mass": mp.centre,
        "volume": mp.volume,
        "inertia_tensor_per_density": mp.tensor,
        "principal_moments_per_density": mp.moments,
        "principal_rotation": mp.quaternion,
        "elements": {"offset": shape.principal_offsets(), "radius": shape.cluster().radii},
        "report": report or {},
    }
    path.write_text(json.dumps(_json_safe(doc), indent=1) + "\n")
    return path


class LibraryShape(ClusterShape):
    """A cluster read from a library file (see the module docstring); use :func:`load`.

    Mass properties and elements are the stored ones (nothing is regenerated); the ideal
    solid (for :mod:`dpm.shapes.metrics`) is the generating built-in shape when the file
    names one, else the source mesh.
    """

    name = "library"
    parameters = {"path": Parameter(kind="str", doc="library .json file or library name")}
    _grain: str | None = None  # (set by the class of one grain: see shape_class)

    def __init__(self, call: str | None = None, **params: Any) -> None:
        super().__init__(call=call, **params)
        path = self._grain or self.params["path"]
        p = find(path)
        if p is None:
            raise ParameterError(f"{self.call}: path={path!r} is no library "
                                 f"file (library shapes: {', '.join(names()) or 'none'})")
        self.file = p
        if self._grain is None:  # (the output's shape name: library:rock, a grain's: rock)
            self.name = f"library:{p.stem}"
        try:
            doc = json.loads(p.read_text())
        except (OSError, ValueError) as exc:
            raise ParameterError(f"{self.call}: {p} cannot be read: {exc}") from exc
        if doc.get("format") != FORMAT or int(doc.get("version", 0)) > VERSION:
            raise ParameterError(f"{self.call}: {p} is not a {FORMAT} file of version "
                                 f"<= {VERSION}")
        self.doc = doc
        self.source_name = doc["shape"]["name"]
        q = np.asarray(doc["principal_rotation"], float)
        rot = matrix_from_quaternion(q)
        off = np.asarray(doc["elements"]["offset"], float).reshape(-1, 3)
        rad = np.asarray(doc["elements"]["radius"], float)
        if len(off) != len(rad) or len(rad) == 0 or np.any(rad <= 0):
            raise ParameterError(f"{self.call}: {p}: elements need as many offsets as "
                                 "positive radii")
        moments = np.asarray(doc["principal_moments_per_density"], float)
        self._cache["mass"] = MassProperties(
            volume=float(doc["volume"]),
            centre=np.asarray(doc.get("source_centre_of_mass", [0, 0, 0]), float),
            tensor=np.asarray(doc["inertia_tensor_per_density"], float),
            moments=moments, rotation=rot, quaternion=q / np.linalg.norm(q))
        rep = doc.get("report", {})
        self._cache["cluster"] = Cluster(
            centres=off @ rot.T, radii=rad,
            inscribed_radius=float(rep.get("inscribed_radius", rad.max())),
            tolerance=float(rep.get("tolerance", 0.0)), min_radius=float(rad.min()),
            samples=0, seconds=0.0)
        self._offsets = off

    @property
    def resolution(self) -> float:
        return float(self.doc.get("resolution", 0.0))

    def principal_offsets(self) -> np.ndarray:
        return self._offsets

    def solid(self) -> ClusterShape:
        """The ideal solid: the generating built-in shape, else the source mesh."""
        if "solid" not in self._cache:
            from . import BUILTIN_SHAPES
            from .mesh import MeshShape

            spec = self.doc["shape"]
            cls = BUILTIN_SHAPES.get(spec["name"])
            if cls is not None and cls is not MeshShape and issubclass(cls, ClusterShape):
                solid = cls(**spec["params"])
            else:
                solid = MeshShape(path=str(self.file.parent / self.doc["source_mesh"]))
            self._cache["solid"] = solid
        return self._cache["solid"]

    # geometry of the ideal solid, in the shape frame
    def bounds(self):
        return self.solid().bounds()

    def inside(self, points):
        return self.solid().inside(points)

    def depth(self, points):
        return self.solid().depth(points)

    def mesh(self, fine: bool = False):
        return self.solid().mesh(fine=fine)

    def volume(self) -> float:
        return self._cache["mass"].volume

    def inertia_tensor(self) -> np.ndarray:
        return self._cache["mass"].tensor

    def describe(self, resolution: bool = True) -> str:
        return f"{self.doc.get('name', self.file.stem)} ({self.file.name})"


def load(path: str | Path) -> LibraryShape:
    """A library shape from a ``.json`` file or a library name (``load("rock")``)."""
    return LibraryShape(call=f"dpm.shapes.library.load({str(path)!r})", path=str(path))


_BY_NAME: dict[str, type] = {}


def shape_class(name: str) -> type | None:
    """A shape class for the library grain ``name`` (``"rock"``): what the registry
    returns for a shape name no plugin registers, so that a scene file, an inlet or
    ``sim.add_particles("rock", ...)`` can name a grain; None if there is no such grain."""
    if not isinstance(name, str) or find(name) is None or Path(name).suffix:
        return None
    if name not in _BY_NAME:
        _BY_NAME[name] = type(f"Library_{name}", (LibraryShape,), {
            "name": name, "parameters": {}, "_grain": name, "__module__": __name__,
            "__doc__": f"Library grain {name!r} ({LIBRARY_DIR.name}/{name}.json)."})
    return _BY_NAME[name]


def __getattr__(attr: str) -> type:
    """``Library_rock``: the class of a grain, so that a pickled one (an inlet's shape in a
    checkpoint) loads in a new process."""
    cls = shape_class(attr[len("Library_"):]) if attr.startswith("Library_") else None
    if cls is None:
        raise AttributeError(f"module {__name__!r} has no attribute {attr!r}")
    return cls
