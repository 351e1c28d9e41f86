"""Picture of a run's last frame read back from its XDMF output with VTK's XDMF reader:
the particles glyphed as spheres of their radius, coloured by speed, and the boundaries
of ``<run>.boundaries.xdmf`` at the same time, rendered offscreen.

    python examples/rotating_drum.py --quick --output /tmp/drum.h5
    python docs/render/scene_snapshot.py /tmp/drum.xdmf docs/images/rotating_drum.png \
        --view -y --cut y
    python examples/tumbling_screen.py --quick --output /tmp/screen.h5
    python docs/render/scene_snapshot.py /tmp/screen.xdmf docs/images/tumbling_screen.png \
        --view iso

``--view`` looks along an axis (``-y``: from y < 0 towards +y) or from an oblique corner
(``iso``); the camera frames the boundaries (a particle thrown far out may leave the picture);
``--cut AXIS`` leaves out the boundary faces whose normal lies along AXIS (the
drum's end caps) so that the bed inside shows. ``--solids`` draws the clustered bodies
as their solid shapes from ``<run>.solids.xdmf`` (written with
``sim.output(..., solids=True)``) instead of their bounding spheres:

    python docs/render/solids_run.py /tmp/solids.h5
    python docs/render/scene_snapshot.py /tmp/solids.xdmf docs/images/solids_drum.png \
        --view=-y --cut y --solids
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline as Pipeline
from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

sys.path.insert(0, str(Path(__file__).parent))
from vtkscene import caption, polydata, render, spheres_actor, surface_actor  # noqa: E402


def read_last(path: Path):
    """(time, dataset) of the last frame of an XDMF file."""
    r = vtkXdmfReader()
    r.SetFileName(str(path))
    r.UpdateInformation()
    times = list(r.GetOutputInformation(0).Get(Pipeline.TIME_STEPS()) or [0.0])
    r.UpdateTimeStep(times[-1])
    return times[-1], r.GetOutputDataObject(0)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("xdmf", type=Path, help="the run's particle XDMF file")
    ap.add_argument("png", type=Path)
    ap.add_argument("--view", default="iso", help="-x, +x, -y, +y, -z, +z or iso")
    ap.add_argument("--cut", default="", help="axis whose facing boundary faces are hidden")
    ap.add_argument("--size", type=int, nargs=2, default=(800, 600))
    ap.add_argument("--title", default="")
    ap.add_argument("--solids", action="store_true", help="clustered bodies as their solid "
                    "shapes (<run>.solids.xdmf)")
    args = ap.parse_args(argv)

    t, grid = read_last(args.xdmf)
    pos = vtk_to_numpy(grid.GetPoints().GetData())
    pd = grid.GetPointData()
    radius = vtk_to_numpy(pd.GetArray("radius"))
    speed = np.linalg.norm(vtk_to_numpy(pd.GetArray("velocity")), axis=1)
    hi = float(np.percentile(speed, 98)) or 1.0
    actors = [spheres_actor(pos, radius, speed, (0.0, hi))]
    if args.solids:
        _, solid = read_last(args.xdmf.with_name(args.xdmf.stem + ".solids.xdmf"))
        geo = vtkGeometryFilter()
        geo.SetInputData(solid)
        geo.Update()
        mesh = geo.GetOutput()
        actors = [surface_actor(polydata(
            vtk_to_numpy(mesh.GetPoints().GetData()),
            vtk_to_numpy(mesh.GetPolys().GetConnectivityArray()).reshape(-1, 3)),
            color=(0.85, 0.55, 0.3))]

    bounds = None
    side = args.xdmf.with_name(args.xdmf.stem + ".boundaries.xdmf")
    if side.exists():
        tb, surf = read_last(side)
        geo = vtkGeometryFilter()
        geo.SetInputData(surf)
        geo.Update()
        mesh = geo.GetOutput()
        verts = vtk_to_numpy(mesh.GetPoints().GetData())
        faces = vtk_to_numpy(mesh.GetPolys().GetConnectivityArray()).reshape(-1, 3)
        if args.cut:
            axis = "xyz".index(args.cut)
            tri = verts[faces]
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
            faces = faces[np.abs(n[:, axis]) < 0.9]
        lo, hi = verts.min(axis=0), verts.max(axis=0)
        bounds = [v for pair in zip(lo, hi, strict=True) for v in pair]
        actors.insert(0, surface_actor(polydata(verts, faces), opacity=0.35, edges=True))
        print(f"{args.xdmf.name}: {len(pos)} particles at t = {t:.3f} s; boundaries at "
              f"t = {tb:.3f} s, {len(faces)} triangles")

    def camera(cam):
        fx, fy, fz = cam.GetFocalPoint()
        d = cam.GetDistance()
        if args.view == "iso":
            direction = np.array([1.0, -1.4, 0.9])
            up = (0.0, 0.0, 1.0)
        else:
            direction = np.zeros(3)
            direction["xyz".index(args.view[1])] = 1.0 if args.view[0] == "+" else -1.0
            up = (0.0, 1.0, 0.0) if args.view[1] == "z" else (0.0, 0.0, 1.0)
        direction /= np.linalg.norm(direction)
        cam.SetPosition(*(np.array([fx, fy, fz]) + d * direction))
        cam.SetViewUp(*up)
        cam.Zoom(1.25)

    title = args.title or f"{args.xdmf.stem}, t = {t:.2f} s (colour: speed, 0 to {hi:.2g} m/s)"
    render(actors, args.png, size=tuple(args.size), camera=camera, overlays=[caption(title)],
           bounds=bounds)
    print(f"wrote {args.png} ({args.png.stat().st_size // 1024} kB)")


if __name__ == "__main__":
    main()
