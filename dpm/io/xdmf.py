"""XDMF sidecars so ParaView opens a dpm HDF5 run over time: ``run.xdmf`` (particles),
``run.elements.xdmf`` (the sphere elements of clustered bodies),
``run.boundaries.xdmf`` (every boundary's surface as triangles, moving with it) and
``run.contacts.xdmf`` (the touching pairs as lines between the body centres, with their
forces as cell attributes; written with ``sim.output(..., contacts=True)``) and
``run.solids.xdmf`` (the solid shapes of clustered bodies as triangles, with the body id
and shape of each as cell attributes; written with ``sim.output(..., solids=True)``).

Read by VTK's ``vtkXdmfReader`` (ParaView's "XDMF Reader"; the tests read every value back
with it and check that it prints no error). Each frame's rows of a growing dataset are a
HyperSlab DataItem, which the Xdmf3 library behind ParaView's "Xdmf3 Reader S/T" does not
read (it asks a HyperSlab array for its number type before reading it and gets none:
``Skipping unrecognized array type [None]``, no points; ParaView 5.11).

Two things keep ``vtkXdmfReader`` quiet: a frame with no rows is written as a grid of one
point at the origin and no cell, without attributes (a hyperslab of count 0 makes the XDMF
library print ``Alloc :: ...`` and fail); and no topology is a plain HDF DataItem (the boundaries'
triangles are a hyperslab of all their rows): the reader's cache of unchanged grids keys
on the text of the topology's and the geometry's first DataItem, and with a plain
topology it prints ``Cannot find DataItem element in geometry xml, no caching possible``
for every frame whose geometry is a hyperslab (its first child is an element, not text).
"""

from __future__ import annotations

import os
from pathlib import Path

from .._lazy import lazy_module

h5py = lazy_module("h5py")


#: attribute name -> (width, HDF5 number type, precision)
_ATTRS = {
    "id": (0, "Int", 8),
    "velocity": (3, "Float", 8),
    "angular_velocity": (3, "Float", 8),
    "orientation": (4, "Float", 8),
    "radius": (0, "Float", 8),
    "mass": (0, "Float", 8),
    "material": (0, "Int", 4),
    "shape": (0, "Int", 4),
    # optional fields (sim.output(fields=...)): written where the file has them
    "force": (3, "Float", 8),
    "torque": (3, "Float", 8),
    "contact_count": (0, "Int", 4),
    "rotation": (9, "Float", 8),
}
#: cell attributes of the contact lines: name -> (width, number type, precision)
_CONTACT_ATTRS = {"force": (3, "Float", 8), "normal_force": (0, "Float", 8),
                  "overlap": (0, "Float", 8), "point": (3, "Float", 8)}


def _slab(h5name: str, field: str, start: int, count: int, width: int | tuple[int, ...],
          rows: int, ntype: str, prec: int, group: str = "particles",
          dims: str | None = None) -> str:
    """Rows ``start : start + count`` of the dataset ``group/field`` of ``rows`` rows of
    ``width`` values (0: one scalar; a tuple: a row's shape), as a hyperslab DataItem of
    ``dims`` (default: count x width)."""
    shape = (width,) if isinstance(width, int) and width else tuple(width or ())
    tail = "".join(f" {w}" for w in shape)
    sel = (f"{start}{' 0' * len(shape)} 1{' 1' * len(shape)} {count}{tail}")
    return (f'<DataItem ItemType="HyperSlab" Dimensions="{dims or f"{count}{tail}"}" '
            f'Type="HyperSlab">'
            f'<DataItem Dimensions="3 {1 + len(shape)}" Format="XML">{sel}</DataItem>'
            f'<DataItem Dimensions="{rows}{tail}" NumberType="{ntype}" Precision="{prec}" '
            f'Format="HDF">{h5name}:/{group}/{field}</DataItem></DataItem>')


def _empty_grid(t: float) -> str:
    """A frame with no rows: one point at the origin, no cell (nothing is drawn), no
    attributes. (An empty hyperslab or XML DataItem makes the XDMF library print
    ``Alloc :: ...`` and fail; a Geometry without a DataItem reads an uninitialised point
    count.)"""
    return (f'<Grid Name="frame" GridType="Uniform"><Time Value="{float(t):.17g}"/>'
            f'<Topology TopologyType="Polyvertex" NumberOfElements="0"/>'
            f'<Geometry GeometryType="XYZ"><DataItem Dimensions="1 3" NumberType="Float" '
            f'Precision="8" Format="XML">0 0 0</DataItem></Geometry></Grid>')


def _attribute(name: str, width: int, center: str, slab: str) -> str:
    """An Attribute element: a scalar (width 0), a 3x3 tensor (9) or a vector."""
    # (a quaternion is a "Vector" of 4: "Matrix" reads as one tuple of 4 n values)
    kind = "Scalar" if width == 0 else "Tensor" if width == 9 else "Vector"
    return f'<Attribute Name="{name}" AttributeType="{kind}" Center="{center}">{slab}</Attribute>'


_ELEMENT_ATTRS = {"radius": (0, "Float", 8), "body_id": (0, "Int", 8)}


def write_xdmf_from_arrays(h5path: Path, times, starts, counts, rows: int,
                           group: str = "particles", fields: set[str] | None = None) -> Path:
    """Write ``<run>.xdmf`` (particles) or ``<run>.elements.xdmf`` (the sphere elements of
    clustered bodies, ``group="elements"``) beside ``h5path`` for the given frame table."""
    h5path = Path(h5path)
    name = h5path.name
    attrs = _ATTRS if group == "particles" else _ELEMENT_ATTRS
    if fields is not None:  # (a file written before a field existed lacks it)
        attrs = {k: v for k, v in attrs.items() if k in fields}
    out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0"><Domain>',
           f'<Grid Name="{group}" GridType="Collection" CollectionType="Temporal">']
    for t, a, n in zip(times, starts, counts, strict=True):
        a, n = int(a), int(n)
        if n == 0:
            out.append(_empty_grid(t))
            continue
        out.append(f'<Grid Name="frame" GridType="Uniform"><Time Value="{float(t):.17g}"/>'
                   f'<Topology TopologyType="Polyvertex" NumberOfElements="{n}"/>'
                   f'<Geometry GeometryType="XYZ">'
                   f'{_slab(name, "position", a, n, 3, rows, "Float", 8, group)}</Geometry>')
        for field, (w, ntype, prec) in attrs.items():
            out.append(_attribute(field, w, "Node",
                                  _slab(name, field, a, n, w, rows, ntype, prec, group)))
        out.append("</Grid>")
    out.append("</Grid></Domain></Xdmf>")
    path = h5path.with_suffix(".xdmf" if group == "particles" else ".elements.xdmf")
    return _publish_text(path, out)


def write_boundaries_xdmf(h5path: Path, times, nverts: int, nfaces: int) -> Path:
    """Write ``<run>.boundaries.xdmf``: per frame the triangles of every boundary
    (``/surfaces/faces``) at that frame's world vertices (``/boundaries/surface``), with
    the boundary index of each triangle as a cell attribute."""
    h5path = Path(h5path)
    name = h5path.name
    nf = len(times)
    out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0"><Domain>',
           '<Grid Name="boundaries" GridType="Collection" CollectionType="Temporal">']
    for k, t in enumerate(times):
        out.append(
            f'<Grid Name="frame" GridType="Uniform"><Time Value="{float(t):.17g}"/>'
            f'<Topology TopologyType="Triangle" NumberOfElements="{nfaces}">'
            f'{_slab(name, "faces", 0, nfaces, 3, nfaces, "Int", 8, "surfaces")}</Topology>'
            f'<Geometry GeometryType="XYZ">'
            f'<DataItem ItemType="HyperSlab" Dimensions="{nverts} 3" Type="HyperSlab">'
            f'<DataItem Dimensions="3 3" Format="XML">{k} 0 0 1 1 1 1 {nverts} 3</DataItem>'
            f'<DataItem Dimensions="{nf} {nverts} 3" NumberType="Float" Precision="8" '
            f'Format="HDF">{name}:/boundaries/surface</DataItem></DataItem></Geometry>'
            f'<Attribute Name="boundary" AttributeType="Scalar" Center="Cell">'
            f'<DataItem Dimensions="{nfaces}" NumberType="Int" Precision="4" '
            f'Format="HDF">{name}:/surfaces/boundary</DataItem></Attribute></Grid>')
    out.append("</Grid></Domain></Xdmf>")
    return _publish_text(h5path.with_suffix(".boundaries.xdmf"), out)


def write_contacts_xdmf(h5path: Path, times, starts, counts, rows: int,
                        line_nodes: int) -> Path:
    """Write ``<run>.contacts.xdmf``: per frame the touching pairs of ``/contacts`` as
    lines (a Polyline topology of 2 nodes each) from body i's centre to body j's
    (``/contacts/ends``), with id_i, id_j, force, normal_force, overlap and point as cell
    attributes."""
    h5path = Path(h5path)
    name = h5path.name
    out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0"><Domain>',
           '<Grid Name="contacts" GridType="Collection" CollectionType="Temporal">']
    for t, a, n in zip(times, starts, counts, strict=True):
        a, n = int(a), int(n)
        if n == 0:
            out.append(_empty_grid(t))
            continue
        out.append(
            f'<Grid Name="frame" GridType="Uniform"><Time Value="{float(t):.17g}"/>'
            f'<Topology TopologyType="Polyline" NodesPerElement="2" NumberOfElements="{n}">'
            f'{_slab(name, "line_nodes", 0, n, 2, line_nodes, "Int", 8, "contacts")}'
            f'</Topology><Geometry GeometryType="XYZ">'
            f'{_slab(name, "ends", a, n, (2, 3), rows, "Float", 8, "contacts", f"{2 * n} 3")}'
            f'</Geometry>')
        for field, (w, ntype, prec) in _CONTACT_ATTRS.items():
            out.append(_attribute(field, w, "Cell",
                                  _slab(name, field, a, n, w, rows, ntype, prec, "contacts")))
        # the two body ids as scalars, columns of /contacts/id (a "Vector" of 2 reads as 3)
        for col, label in enumerate(("id_i", "id_j")):
            out.append(_attribute(label, 0, "Cell", (
                f'<DataItem ItemType="HyperSlab" Dimensions="{n}" Type="HyperSlab">'
                f'<DataItem Dimensions="3 2" Format="XML">{a} {col} 1 1 {n} 1</DataItem>'
                f'<DataItem Dimensions="{rows} 2" NumberType="Int" Precision="8" '
                f'Format="HDF">{name}:/contacts/id</DataItem></DataItem>')))
        out.append("</Grid>")
    out.append("</Grid></Domain></Xdmf>")
    return _publish_text(h5path.with_suffix(".contacts.xdmf"), out)


def write_solids_xdmf(h5path: Path, times, vstarts, vcounts, fstarts, fcounts,
                      vrows: int, frows: int) -> Path:
    """Write ``<run>.solids.xdmf``: per frame the triangles of ``/solids/faces`` (rows
    ``solid_face_start`` on, shared by frames with the same bodies) on that frame's
    vertices of ``/solids/vertices``, with ``body_id`` and ``shape`` as cell attributes."""
    h5path = Path(h5path)
    name = h5path.name
    out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0"><Domain>',
           '<Grid Name="solids" GridType="Collection" CollectionType="Temporal">']
    for t, a, n, b, m in zip(times, vstarts, vcounts, fstarts, fcounts, strict=True):
        a, n, b, m = int(a), int(n), int(b), int(m)
        if n == 0 or m == 0:  # (no clustered body)
            out.append(_empty_grid(t))
            continue
        out.append(
            f'<Grid Name="frame" GridType="Uniform"><Time Value="{float(t):.17g}"/>'
            f'<Topology TopologyType="Triangle" NumberOfElements="{m}">'
            f'{_slab(name, "faces", b, m, 3, frows, "Int", 8, "solids")}</Topology>'
            f'<Geometry GeometryType="XYZ">'
            f'{_slab(name, "vertices", a, n, 3, vrows, "Float", 8, "solids")}</Geometry>')
        for field, ntype, prec in (("body_id", "Int", 8), ("shape", "Int", 4)):
            out.append(_attribute(field, 0, "Cell",
                                  _slab(name, field, b, m, 0, frows, ntype, prec, "solids")))
        out.append("</Grid>")
    out.append("</Grid></Domain></Xdmf>")
    return _publish_text(h5path.with_suffix(".solids.xdmf"), out)


def _publish_text(path: Path, out: list[str]) -> Path:
    """Write the lines ``out`` to ``path`` atomically: a kill never leaves a half-written
    sidecar (a unique temporary name, so two processes rewriting the same sidecar do not
    mix their writes)."""
    from .hdf5 import _temp_beside

    tmp = _temp_beside(path)
    try:
        tmp.write_text("\n".join(out))
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_xdmf(h5path: str | Path) -> Path:
    """(Re)write the XDMF sidecar(s) of an existing dpm HDF5 run for its complete frames;
    returns the path of ``run.xdmf``."""
    from .hdf5 import complete_frames, contact_rows
    from .solids import SOLID_FRAME_FIELDS, solid_rows

    with h5py.File(h5path, "r", libver="latest", swmr=True) as f:
        n, _, erows = complete_frames(f)
        if erows:
            write_xdmf_from_arrays(Path(h5path), f["frames/time"][:n],
                                   f["frames/element_start"][:n], f["frames/element_count"][:n],
                                   len(f["elements/radius"]), group="elements")
        if "surfaces" in f and len(f["surfaces/faces"]):
            write_boundaries_xdmf(Path(h5path), f["frames/time"][:n],
                                  f["boundaries/surface"].shape[1], len(f["surfaces/faces"]))
        if "contacts" in f:
            fr = f["frames"]
            write_contacts_xdmf(Path(h5path), fr["time"][:n], fr["contact_start"][:n],
                                fr["contact_count"][:n], contact_rows(f),
                                len(f["contacts/line_nodes"]))
        if "solids" in f:
            fr = f["frames"]
            write_solids_xdmf(Path(h5path), fr["time"][:n],
                              *(fr[c][:n] for c in SOLID_FRAME_FIELDS), *solid_rows(f))
        return write_xdmf_from_arrays(Path(h5path), f["frames/time"][:n], f["frames/start"][:n],
                                      f["frames/count"][:n], len(f["particles/id"]),
                                      fields=set(f["particles"]))
