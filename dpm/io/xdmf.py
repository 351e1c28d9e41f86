"""XDMF sidecar so ParaView (Xdmf3 reader) opens a dpm HDF5 run as particles over time."""

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
}


def _slab(h5name: str, field: str, start: int, count: int, width: int, rows: int,
          ntype: str, prec: int, group: str = "particles") -> str:
    if width:
        dims, sel, full = f"{count} {width}", f"{start} 0 1 1 {count} {width}", f"{rows} {width}"
        ndim = 2
    else:
        dims, sel, full = f"{count}", f"{start} 1 {count}", f"{rows}"
        ndim = 1
    return (f'<DataItem ItemType="HyperSlab" Dimensions="{dims}" Type="HyperSlab">'
            f'<DataItem Dimensions="3 {ndim}" Format="XML">{sel}</DataItem>'
            f'<DataItem Dimensions="{full}" NumberType="{ntype}" Precision="{prec}" '
            f'Format="HDF">{h5name}:/{group}/{field}</DataItem></DataItem>')


_ELEMENT_ATTRS = {"radius": (0, "Float", 8), "body_id": (0, "Int", 8)}


def write_xdmf_from_arrays(h5path: Path, times, starts, counts, rows: int,
                           group: str = "particles") -> Path:
    """Write ``<run>.xdmf`` (particles) or ``<run>.elements.xdmf`` (the sphere elements of
    clustered bodies, ``group="elements"``) beside ``h5path`` for the given frame table."""
    h5path = Path(h5path)
    name = h5path.name
    attrs = _ATTRS if group == "particles" else _ELEMENT_ATTRS
    out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0"><Domain>',
           f'<Grid Name="{group}" GridType="Collection" CollectionType="Temporal">']
    for t, a, n in zip(times, starts, counts, strict=True):
        a, n = int(a), int(n)
        out.append(f'<Grid Name="frame" GridType="Uniform"><Time Value="{float(t):.17g}"/>'
                   f'<Topology TopologyType="Polyvertex" NumberOfElements="{n}"/>'
                   f'<Geometry GeometryType="XYZ">'
                   f'{_slab(name, "position", a, n, 3, rows, "Float", 8, group)}</Geometry>')
        for field, (w, ntype, prec) in attrs.items():
            kind = {0: "Scalar", 3: "Vector", 4: "Matrix"}[w]
            out.append(f'<Attribute Name="{field}" AttributeType="{kind}" Center="Node">'
                       f'{_slab(name, field, a, n, w, rows, ntype, prec, group)}</Attribute>')
        out.append("</Grid>")
    out.append("</Grid></Domain></Xdmf>")
    path = h5path.with_suffix(".xdmf" if group == "particles" else ".elements.xdmf")
    # atomic: a kill never leaves a half-written sidecar (a unique temporary name, so two
    # processes rewriting the same sidecar do not mix their writes)
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
    from .hdf5 import complete_frames

    with h5py.File(h5path, "r", libver="latest", swmr=True) as f:
        n, _, erows = complete_frames(f)
        if erows:
            write_xdmf_from_arrays(Path(h5path), f["frames/time"][:n],
                                   f["frames/element_start"][:n], f["frames/element_count"][:n],
                                   len(f["elements/radius"]), group="elements")
        return write_xdmf_from_arrays(Path(h5path), f["frames/time"][:n], f["frames/start"][:n],
                                      f["frames/count"][:n], len(f["particles/id"]))
