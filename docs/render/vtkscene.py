"""Offscreen VTK rendering shared by the picture scripts of ``docs/render``.

Spheres are glyphed at their radius; boundary surfaces are drawn as lit, partly
transparent triangle meshes. No window opens (``SetOffScreenRendering``), so the
scripts run on a machine without a display.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import vtkmodules.vtkRenderingFreeType  # noqa: F401  (text)
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the rendering backend)
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkFiltersCore import vtkGlyph3D, vtkPolyDataNormals
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import (
    vtkActor,
    vtkPolyDataMapper,
    vtkRenderer,
    vtkRenderWindow,
    vtkWindowToImageFilter,
)


def polydata(vertices: np.ndarray, faces: np.ndarray) -> vtkPolyData:
    """A triangle mesh as vtkPolyData."""
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(vertices, float), deep=True))
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    conn = np.hstack([np.full((len(faces), 1), 3, np.int64), faces]).ravel()
    cells = vtkCellArray()
    cells.SetCells(len(faces), numpy_to_vtkIdTypeArray(conn, deep=True))
    pd = vtkPolyData()
    pd.SetPoints(pts)
    pd.SetPolys(cells)
    return pd


def surface_actor(pd: vtkPolyData, color=(0.62, 0.66, 0.72), opacity: float = 1.0,
                  edges: bool = False) -> vtkActor:
    """A lit surface (normals recomputed, sharp edges kept)."""
    normals = vtkPolyDataNormals()
    normals.SetInputData(pd)
    normals.SetFeatureAngle(40.0)
    normals.ConsistencyOff()
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(normals.GetOutputPort())
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetColor(*color)
    prop.SetOpacity(opacity)
    prop.SetSpecular(0.3)
    prop.SetSpecularPower(20)
    prop.BackfaceCullingOff()
    if edges:
        prop.EdgeVisibilityOn()
        prop.SetEdgeColor(0.35, 0.37, 0.42)
        prop.SetLineWidth(0.5)
    return actor


def spheres_actor(position: np.ndarray, radius: np.ndarray, scalar: np.ndarray,
                  lut_range: tuple[float, float], resolution: int = 12) -> vtkActor:
    """Spheres at ``position`` of ``radius``, coloured by ``scalar``."""
    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(position, float), deep=True))
    pd = vtkPolyData()
    pd.SetPoints(pts)
    scale = numpy_to_vtk(np.ascontiguousarray(2.0 * radius, float), deep=True)
    scale.SetName("diameter")
    color = numpy_to_vtk(np.ascontiguousarray(scalar, float), deep=True)
    color.SetName("color")
    pd.GetPointData().AddArray(scale)
    pd.GetPointData().AddArray(color)
    pd.GetPointData().SetActiveScalars("diameter")
    src = vtkSphereSource()
    src.SetRadius(0.5)
    src.SetThetaResolution(resolution)
    src.SetPhiResolution(resolution)
    glyph = vtkGlyph3D()
    glyph.SetInputData(pd)
    glyph.SetSourceConnection(src.GetOutputPort())
    glyph.SetScaleModeToScaleByScalar()
    glyph.SetScaleFactor(1.0)
    glyph.SetColorModeToColorByScalar()
    glyph.SetInputArrayToProcess(0, 0, 0, 0, "diameter")  # scale
    glyph.SetInputArrayToProcess(3, 0, 0, 0, "color")  # colour
    glyph.OrientOff()
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(glyph.GetOutputPort())
    mapper.SetScalarRange(*lut_range)
    mapper.SelectColorArray("color")
    mapper.SetScalarModeToUsePointFieldData()
    lut = mapper.GetLookupTable()
    lut.SetHueRange(0.62, 0.0)  # blue (slow) to red (fast)
    lut.Build()
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetSpecular(0.25)
    return actor


def render(actors: list[vtkActor], path: str | Path, size=(800, 600), camera=None,
           background=(1.0, 1.0, 1.0), overlays=(), bounds=None) -> None:
    """Render ``actors`` offscreen into the PNG ``path``; ``camera(cam)`` places the
    camera (default: VTK's reset view) after it was fitted to ``bounds`` (xmin, xmax,
    ymin, ymax, zmin, zmax; default: everything)."""
    ren = vtkRenderer()
    ren.SetBackground(*background)
    ren.SetUseDepthPeeling(True)
    ren.SetMaximumNumberOfPeels(8)
    for a in actors:
        ren.AddActor(a)
    for o in overlays:
        ren.AddViewProp(o)
    win = vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetAlphaBitPlanes(1)
    win.SetMultiSamples(0)
    win.AddRenderer(ren)
    win.SetSize(*size)
    if bounds is None:
        ren.ResetCamera()
    else:
        ren.ResetCamera(*bounds)
    if camera is not None:
        camera(ren.GetActiveCamera())
        ren.ResetCameraClippingRange()
    win.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.ReadFrontBufferOff()
    grab.Update()
    writer = vtkPNGWriter()
    writer.SetFileName(str(path))
    writer.SetInputConnection(grab.GetOutputPort())
    writer.SetCompressionLevel(9)
    writer.Write()
    win.Finalize()


def caption(text: str, size: int = 16):
    """A text overlay in the top left corner."""
    from vtkmodules.vtkRenderingCore import vtkTextActor

    t = vtkTextActor()
    t.SetInput(text)
    t.GetTextProperty().SetFontSize(size)
    t.GetTextProperty().SetColor(0.1, 0.1, 0.1)
    t.SetPosition(8, 6)
    return t
