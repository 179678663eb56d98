"""A body to look at: capsules and boxes around the bones, built once and moved in place every frame.

Each bone is a rigid solid in the frame that carries it (:func:`segment_shapes`):
its vertices and normals are stored once in that frame, and a frame's update
is one ``einsum`` writing world coordinates into the PolyData's own arrays
(no mesh is rebuilt, see /work/shared/VIEWPORT.md). Capsules and boxes are two
PolyData with one template each, so each updates with one vectorised product.

The bundled skeletons' segments get hand-set sizes (:data:`SEGMENT_SIZES`); bones
of any other skeleton are capsules whose radius follows their length.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper
from vtkmodules.util.numpy_support import vtk_to_numpy

import gsik
from gsik.mannequin import (BODY_COLOR, LEFT_COLOR, SEGMENT_SIZES, Shape, box_faces, capsule_template,  # noqa: F401
                            capsule_local, box_local, segment_shapes)
from gsik_studio.scene import rgb8, touch


class BodyMesh:
    """One PolyData of same-template solids: local vertices and normals per solid, moved by its carrier."""

    def __init__(self, carriers: list[int], local: list[tuple[np.ndarray, np.ndarray]], faces_per_solid: np.ndarray,
                 colors: np.ndarray):
        self.carriers = np.array(carriers, dtype=np.int64)
        self.local_points = np.stack([v for v, _ in local]) if local else np.zeros((0, 0, 3))
        self.local_normals = np.stack([n for _, n in local]) if local else np.zeros((0, 0, 3))
        s, k = self.local_points.shape[:2]
        faces = (faces_per_solid[None] + (np.arange(s) * k)[:, None, None]).reshape(-1, faces_per_solid.shape[1])
        cells = np.hstack([np.full((len(faces), 1), faces.shape[1]), faces]).ravel() if len(faces) else []
        self.polydata = pv.PolyData(self.local_points.reshape(-1, 3).copy(), faces=np.asarray(cells, dtype=np.int64))
        if not s:  # a skeleton with no solid of this kind: an empty mesh, nothing to move
            return
        self.polydata.point_data.set_array(self.local_normals.reshape(-1, 3).copy(), "Normals")
        self.polydata.point_data.active_normals_name = "Normals"
        self.polydata.point_data.set_array(np.repeat(colors, k, axis=0), "colors")
        self._xyz = vtk_to_numpy(self.polydata.GetPoints().GetData())
        self._normals = vtk_to_numpy(self.polydata.GetPointData().GetArray("Normals"))

    def update(self, P: np.ndarray, R: np.ndarray) -> None:
        """Move every solid with its carrier: world positions P (n_frames, 3) [m], rotations R (n_frames, 3, 3)."""
        if not len(self.carriers):
            return
        Rc = R[self.carriers]
        self._xyz[:] = (np.einsum("sij,skj->ski", Rc, self.local_points) + P[self.carriers][:, None, :]).reshape(-1, 3)
        self._normals[:] = np.einsum("sij,skj->ski", Rc, self.local_normals).reshape(-1, 3)
        touch(self.polydata)
        self.polydata.GetPointData().GetArray("Normals").Modified()


def _solid_actor(pd: pv.PolyData) -> vtkActor:
    """A plain mapper and actor (no pyvista pipeline in between): per-point RGB, the PolyData's own normals."""
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(pd)
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("colors")
    mapper.SetColorModeToDirectScalars()
    mapper.ScalarVisibilityOn()
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetSpecular(0.25)
    prop.SetSpecularPower(18)
    return actor


class SolidBody:
    """Meshes (each with a ``polydata`` and an ``update(P, R)``) drawn by one actor each, added to a plotter once.

    The mannequin and a character's skinned body (:mod:`gsik_studio.skinned_body`) are both one, so the body view
    draws either the same way.
    """

    def __init__(self, plotter: pv.Plotter, meshes: tuple) -> None:
        self.meshes = meshes
        self.actors = [_solid_actor(m.polydata) for m in self.meshes]
        for a in self.actors:
            plotter.add_actor(a, reset_camera=False, pickable=False)

    def update(self, P: np.ndarray, R: np.ndarray) -> None:
        """Move the body to world positions P (n_frames, 3) [m] and rotations R (n_frames, 3, 3)."""
        for m in self.meshes:
            m.update(P, R)

    def set_visible(self, visible: bool) -> None:
        for a in self.actors:
            a.SetVisibility(bool(visible))

    @property
    def visible(self) -> bool:
        return bool(self.actors[0].GetVisibility())


class Mannequin(SolidBody):
    """The body: capsules and boxes added to a plotter once; :meth:`update` moves them in place.

    Args:
        plotter: The pyvista plotter to draw into.
        skeleton: The skeleton whose bones get solids.
    """

    def __init__(self, plotter: pv.Plotter, skeleton: gsik.Skeleton):
        shapes = segment_shapes(skeleton)
        template = capsule_template()
        caps = [s for s in shapes if s.kind == "capsule"]
        boxes = [s for s in shapes if s.kind == "box"]

        def colors(group):
            return rgb8([LEFT_COLOR if s.left else BODY_COLOR for s in group]).reshape(-1, 3)

        super().__init__(plotter, (
            BodyMesh([s.carrier for s in caps], [capsule_local(s, template) for s in caps], template[2],
                     colors(caps)),
            BodyMesh([s.carrier for s in boxes], [box_local(s) for s in boxes], box_faces(1), colors(boxes)),
        ))

    @property
    def n_solids(self) -> int:
        return sum(len(m.carriers) for m in self.meshes)
