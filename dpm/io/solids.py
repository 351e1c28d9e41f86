"""The solid shapes of clustered bodies in the output (``sim.output(..., solids=True)``,
docs/output-format.md): the triangle surface of each shape's ideal solid, stored once in
the body (principal) frame, and per frame the surfaces of every clustered body placed at
its pose, which ``run.solids.xdmf`` shows beside the element spheres of
``run.elements.xdmf``.

A body's solid is found from its elements: a clustered shape remembers itself under the
digest of its elements when it builds bodies (:func:`dpm.shapes.cluster.remember`), the
file keeps that digest with each mesh (so a resumed file finds the meshes it already has),
and each body id is looked up once. Bodies with no known solid are skipped: spheres (the
particles' own view shows them), shapes that are not :class:`~dpm.shapes.ClusterShape`
(a plugin's own ``build``) or that give no mesh, and clustered bodies built in another
process before a restart whose meshes the file does not hold yet.

The faces of a frame (and the body id and shape of each face) are written again only
when the bodies in it or their shapes change; frames with the same bodies share the
rows (``/frames/solid_face_start``, ``solid_face_count``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .contacts import rotation_columns

#: the meshes of ``/solid_shapes``, one row each (``key`` extended last):
#: name -> (shape of a row, dtype)
MESH_FIELDS = {"shape": ((), "i4"), "name": ((), "S64"), "description": ((), "S256"),
               "volume": ((), "f8"), "mesh_volume": ((), "f8"),
               "vertex_start": ((), "i8"), "vertex_count": ((), "i8"),
               "face_start": ((), "i8"), "face_count": ((), "i8"), "key": ((), "S32")}
#: the rows of the meshes' vertices and faces in ``/solid_shapes``
MESH_ROWS = {"vertices": ((3,), "f8"), "faces": ((3,), "i8")}
#: the placed surfaces of ``/solids``: name -> (shape of a row, dtype)
SOLID_FIELDS = {"vertices": ((3,), "f8"), "faces": ((3,), "i8"), "body_id": ((), "i8"),
                "shape": ((), "i4")}
#: the frame table's columns of a file with solids
SOLID_FRAME_FIELDS = {"solid_vertex_start": "i8", "solid_vertex_count": "i8",
                      "solid_face_start": "i8", "solid_face_count": "i8"}


def solids_layout(f: Any, rows: int) -> None:
    """The empty ``/solid_shapes`` and ``/solids`` groups of a new file (``rows``: the
    chunk length of the per-frame datasets)."""
    for gname, fields, chunk in (("solid_shapes", MESH_FIELDS, 64),
                                 ("solid_shapes", MESH_ROWS, 4096),
                                 ("solids", SOLID_FIELDS, rows)):
        g = f.require_group(gname)
        for name, (shape, dtype) in fields.items():
            g.create_dataset(name, shape=(0, *shape), maxshape=(None, *shape), dtype=dtype,
                             chunks=(chunk, *shape))
    f["solid_shapes/vertices"].attrs["unit"] = "m"
    f["solid_shapes/volume"].attrs["unit"] = "m3"
    f["solid_shapes/mesh_volume"].attrs["unit"] = "m3"
    f["solids/vertices"].attrs["unit"] = "m"


def body_frame_mesh(shape: Any) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(vertices (V, 3) in the body's principal frame [m], faces (T, 3), the volume the
    mesh encloses (NaN when it is not closed)) of a clustered shape's ideal solid; None
    when the shape gives no mesh."""
    try:
        m = shape.mesh()
        rot = np.asarray(shape.mass_properties().rotation, float)
    except (AttributeError, NotImplementedError, TypeError, ValueError):
        return None
    vertices = np.asarray(getattr(m, "vertices", ()), float).reshape(-1, 3)
    faces = np.asarray(getattr(m, "faces", ()), np.int64).reshape(-1, 3)
    if len(faces) == 0:
        return None
    # one closed surface (a multisphere's is its spheres', overlapping: not one body)
    closed = bool(getattr(m, "is_watertight", False)) and getattr(m, "body_count", 1) == 1
    volume = float(abs(m.volume)) if closed else float("nan")
    # rows: R^T v, as the elements' offsets (ClusterShape.principal_offsets)
    return vertices @ rot, faces, volume


def body_rotations(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) arrays ``a`` with ``v @ a[k] = R(q_k) v`` (the transposed rotations)."""
    return rotation_columns(q).reshape(-1, 3, 3)


class Solids:
    """What a :class:`~dpm.io.hdf5.Writer` keeps to write the solids of an open file: the
    mesh of each body id seen, the file's meshes (read back from a resumed file) and the
    face rows of the last frame, which the next frame shares when its bodies are the same.
    """

    def __init__(self, file: Any) -> None:
        self.file = file
        g = file["solid_shapes"]
        n = min(len(g[k]) for k in MESH_FIELDS)
        self.index: dict[str, int] = {k.decode(): i for i, k in enumerate(g["key"][:n])}
        self.meshes: list[tuple[np.ndarray, np.ndarray] | None] = [None] * n
        self.shape_of: list[int] = [int(s) for s in g["shape"][:n]]
        self.body_mesh: dict[int, int] = {}
        self.last: tuple[np.ndarray, np.ndarray, int, int] | None = None
        self.vertex_rows = self.face_rows = 0

    def resume(self, vertex_rows: int, face_rows: int) -> None:
        """Go on after the rows ``vertex_rows`` and ``face_rows`` of a file cut back to a
        checkpoint (the next frame writes its faces afresh)."""
        self.vertex_rows, self.face_rows = vertex_rows, face_rows
        self.last = None

    def _mesh(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        if self.meshes[k] is None:
            g = self.file["solid_shapes"]
            a, n = int(g["vertex_start"][k]), int(g["vertex_count"][k])
            b, m = int(g["face_start"][k]), int(g["face_count"][k])
            self.meshes[k] = (g["vertices"][a:a + n], g["faces"][b:b + m])
        return self.meshes[k]

    def _add_mesh(self, key: str, shape: Any, sim: Any) -> int:
        """Store the mesh of ``shape`` in ``/solid_shapes`` (``key`` extended last); its
        index, or -1 when the shape gives no mesh."""
        mesh = body_frame_mesh(shape)
        if mesh is None:
            self.index[key] = -1
            return -1
        vertices, faces, mesh_volume = mesh
        g = self.file["solid_shapes"]
        k = len(self.meshes)
        vstart, fstart = len(g["vertices"]), len(g["faces"])
        for name, value in (("vertices", vertices), ("faces", faces)):
            ds = g[name]
            ds.resize(len(ds) + len(value), axis=0)
            ds[len(ds) - len(value):] = value
        name = getattr(shape, "name", "") or type(shape).__name__
        names = list(getattr(sim, "shape_names", []))
        try:
            volume = float(shape.volume())
        except (AttributeError, NotImplementedError):
            volume = float("nan")
        try:
            description = str(shape.describe())
        except (AttributeError, NotImplementedError, TypeError):
            description = name
        row = {"shape": names.index(name) if name in names else -1,
               "name": name.encode()[:64], "description": description.encode()[:256],
               "volume": volume,
               "mesh_volume": mesh_volume, "vertex_start": vstart,
               "vertex_count": len(vertices), "face_start": fstart,
               "face_count": len(faces), "key": key.encode()}
        for field in MESH_FIELDS:
            if field == "key":
                self.file.flush()
            ds = g[field]
            ds.resize(k + 1, axis=0)
            ds[k] = row[field]
        self.index[key] = k
        self.meshes.append((vertices, faces))
        self.shape_of.append(row["shape"])
        return k

    def mesh_of_bodies(self, sim: Any) -> np.ndarray:
        """The mesh index of each body (rows of ``sim.bodies``; -1: no solid)."""
        from ..shapes.cluster import built_shape, element_key

        b, e = sim.bodies, sim.elements
        out = np.empty(len(b), np.int64)
        starts = b.element_start
        for row, body in enumerate(b.id.tolist()):
            k = self.body_mesh.get(body)
            if k is None:
                a, z = int(starts[row]), int(starts[row + 1])
                key = element_key(e.offset[a:z], e.radius[a:z])
                k = self.index.get(key)
                if k is None:
                    shape = built_shape(key)
                    k = -1 if shape is None else self._add_mesh(key, shape, sim)
                self.body_mesh[body] = k
            out[row] = k
        return out

    def write(self, sim: Any) -> tuple[int, int, int, int]:
        """Append this frame's placed surfaces; return (vertex start, vertex count, face
        start, face count) for the frame table."""
        b = sim.bodies
        mesh = self.mesh_of_bodies(sim)
        rows = np.flatnonzero(mesh >= 0)
        ids, mesh = b.id[rows], mesh[rows]
        counts = np.array([len(self._mesh(k)[0]) for k in range(len(self.meshes))]
                          + [0], np.int64)
        nverts = counts[mesh]
        vstart = np.concatenate([[0], np.cumsum(nverts)])
        total = int(vstart[-1])
        xyz = np.empty((total, 3))
        rot = body_rotations(b.orientation[rows]) if len(rows) else np.zeros((0, 3, 3))
        pos = b.position[rows]
        for k in np.unique(mesh):
            sel = np.flatnonzero(mesh == k)
            local = self._mesh(int(k))[0]
            block = pos[sel, None, :] + local @ rot[sel]
            idx = vstart[sel][:, None] + np.arange(len(local))[None, :]
            xyz[idx] = block
        g = self.file["solids"]
        if total:
            ds = g["vertices"]
            ds.resize(self.vertex_rows + total, axis=0)
            ds[self.vertex_rows:] = xyz
        vrow = self.vertex_rows
        self.vertex_rows += total
        if (self.last is not None and np.array_equal(self.last[0], ids)
                and np.array_equal(self.last[1], mesh)):
            return vrow, total, self.last[2], self.last[3]
        faces = [self._mesh(int(k))[1] + int(s) for k, s in zip(mesh, vstart[:-1],
                                                                 strict=True)]
        nfaces = np.array([len(x) for x in faces], np.int64)
        values = {"faces": np.concatenate(faces) if faces else np.zeros((0, 3), np.int64),
                  "body_id": np.repeat(ids, nfaces),
                  "shape": np.repeat(np.asarray(self.shape_of, np.int32)[mesh]
                                     if len(mesh) else np.zeros(0, np.int32), nfaces)}
        nf = int(nfaces.sum())
        for name, value in values.items() if nf else ():
            ds = g[name]
            ds.resize(self.face_rows + nf, axis=0)
            ds[self.face_rows:] = value
        frow = self.face_rows
        self.face_rows += nf
        self.last = (ids.copy(), mesh.copy(), frow, nf)
        return vrow, total, frow, nf


def solid_rows(f: Any) -> tuple[int, int]:
    """Rows of ``/solids`` written in full: (vertices, faces) (0, 0 without solids)."""
    if "solids" not in f:
        return 0, 0
    g = f["solids"]
    return len(g["vertices"]), min(len(g[k]) for k in ("faces", "body_id", "shape"))
