"""VTK building blocks of the viewport: line cells, in-place point views, glyph spheres, per-point colours."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkInteractionWidgets import vtkSphereWidget
from vtkmodules.vtkRenderingCore import vtkActor, vtkGlyph3DMapper
from vtkmodules.util.numpy_support import vtk_to_numpy


def rgb8(colors) -> np.ndarray:
    """Colours in 0-1 (..., 3) as 8-bit RGB."""
    return np.clip(np.round(np.asarray(colors, dtype=float) * 255), 0, 255).astype(np.uint8)


def line_cells(pairs) -> np.ndarray:
    """VTK cell array for 2-point lines."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    return np.hstack([np.full((len(pairs), 1), 2, dtype=np.int64), pairs]).ravel()


def points_view(pd: pv.PolyData) -> np.ndarray:
    """A writable NumPy view of a PolyData's point coordinates (write, then :func:`touch`)."""
    return vtk_to_numpy(pd.GetPoints().GetData())


def touch(pd: pv.PolyData) -> None:
    pd.GetPoints().Modified()


def glyph_actor(points: pv.PolyData, radius: float, colors: np.ndarray | None, color=None):
    """A vtkGlyph3DMapper actor drawing one sphere per point (per-point RGB colours if given)."""
    sphere = pv.Sphere(radius=radius, theta_resolution=14, phi_resolution=10)
    mapper = vtkGlyph3DMapper()
    mapper.SetInputData(points)
    mapper.SetSourceData(sphere)
    mapper.ScalingOff()
    mapper.OrientOff()
    if colors is not None:
        points.point_data.set_array(colors, "colors")
        mapper.SetScalarModeToUsePointFieldData()
        mapper.SelectColorArray("colors")
        mapper.SetColorModeToDirectScalars()
        mapper.ScalarVisibilityOn()
    else:
        mapper.ScalarVisibilityOff()
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    if color is not None:
        prop.SetColor(color)
    prop.SetSpecular(0.3)
    prop.SetSpecularPower(20)
    return actor


def sphere_widget(plotter, radius: float, color, selected_color, resolution: tuple[int, int] = (20, 14),
                  opacity: float = 1.0) -> vtkSphereWidget:
    """A draggable sphere widget (surface, no scaling, picked before the camera moves), off until ``On()``."""
    w = vtkSphereWidget()
    w.SetInteractor(plotter.iren.interactor)
    w.SetCurrentRenderer(plotter.renderer)
    w.SetRepresentationToSurface()
    w.SetRadius(radius)
    w.SetThetaResolution(resolution[0])
    w.SetPhiResolution(resolution[1])
    w.ScaleOff()
    w.SetPriority(1.0)
    w.GetSphereProperty().SetColor(color)
    w.GetSphereProperty().SetSpecular(0.4)
    w.GetSphereProperty().SetOpacity(opacity)
    w.GetSelectedSphereProperty().SetColor(selected_color)
    return w


def set_colors(pd: pv.PolyData, colors: np.ndarray) -> None:
    """Overwrite a PolyData's per-point "colors" array in place."""
    arr = pd.GetPointData().GetArray("colors")
    vtk_to_numpy(arr)[:] = colors
    arr.Modified()
