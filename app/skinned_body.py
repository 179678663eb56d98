"""The body in the viewport: a skinned mesh (a glTF character's, or the biped's mannequin) skinned in place each frame.

Every body goes through one path: the document's :func:`~gsik_studio.model.characters.body_character` (the
character read from a file, else the skeleton with its mannequin as a skinned mesh, as Export glTF writes it), its
meshes bound to the skeleton by :func:`gsik.io.gltf.binding.skin_binding`, skinned by :mod:`gsik.skinning`.

Built once (one PolyData, one mapper, one actor); a frame whose pose moved the skin writes the skinned points and
normals straight into the PolyData's own float32 arrays (what VTK uploads; no VTK object is made per frame, see
/work/shared/VIEWPORT.md), and a frame that did not move it writes nothing, so VTK uploads nothing either.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

import gsik
from gsik.skinning import SkinBinding, blend_into, slot_matrices
from gsik_studio.scene import rgb8, touch


class SkinnedMesh:
    """One PolyData holding every vertex of a binding; :meth:`update` skins it in place.

    Attributes:
        binding: What skinning the mesh needs (:class:`gsik.skinning.SkinBinding`).
        polydata: The mesh as drawn: float32 points and "Normals", uint8 RGB "colors".
    """

    def __init__(self, binding: SkinBinding) -> None:
        self.binding = binding
        tris = binding.triangles
        cells = np.hstack([np.full((len(tris), 1), 3, dtype=np.int64), tris]).ravel() if len(tris) else []
        self.polydata = pv.PolyData(np.asarray(binding.positions, dtype=np.float32),
                                    faces=np.asarray(cells, dtype=np.int64))
        self.polydata.point_data.set_array(np.asarray(binding.normals, dtype=np.float32), "Normals")
        self.polydata.point_data.active_normals_name = "Normals"
        self.polydata.point_data.set_array(rgb8(binding.colors).reshape(-1, 3), "colors")
        self._xyz = vtk_to_numpy(self.polydata.GetPoints().GetData())
        self._normals = vtk_to_numpy(self.polydata.GetPointData().GetArray("Normals"))
        self._world = np.zeros((0, 4, 4))  # (n_frames, 4, 4), made on the first update and reused
        self._skinned_at: np.ndarray | None = None  # the slot matrices the arrays hold the skin at

    @property
    def carriers(self) -> np.ndarray:
        """Indices of the skeleton frames that move at least one vertex (sorted)."""
        b = self.binding
        return np.unique(b.slot_frames[b.slots[b.weights > 0]])

    def update(self, P: np.ndarray, R: np.ndarray) -> bool:
        """Skin to world positions P (n_frames, 3) [m] and rotations R (n_frames, 3, 3) of the skeleton's frames.

        Returns False, writing nothing, when no vertex's transform changed since the last update.
        """
        if len(self._world) != len(P):
            self._world = np.zeros((len(P), 4, 4))
            self._world[:, 3, 3] = 1.0
        self._world[:, :3, :3] = R
        self._world[:, :3, 3] = P
        M = np.ascontiguousarray(slot_matrices(self.binding, self._world))  # (n_slots, 3, 4)
        if self._skinned_at is not None and np.array_equal(M, self._skinned_at):
            return False
        blend_into(self.binding, M, self._xyz, self._normals)
        self._skinned_at = M
        touch(self.polydata)
        self.polydata.GetPointData().GetArray("Normals").Modified()
        return True


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


class SkinnedBody:
    """A body drawn in ``plotter``: its skinned meshes, one actor each, added once and moved by :meth:`update`.

    Args:
        plotter: The pyvista plotter to draw into.
        binding: The body's meshes bound to the skeleton (one :class:`SkinnedMesh`).
    """

    def __init__(self, plotter: pv.Plotter, binding: SkinBinding) -> None:
        self.meshes = (SkinnedMesh(binding),)
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

    @property
    def n_vertices(self) -> int:
        return sum(m.binding.n_vertices for m in self.meshes)


def body_of(plotter: pv.Plotter, skeleton: gsik.Skeleton) -> SkinnedBody:
    """The body of a document on ``skeleton``: its character's meshes, else its mannequin (see the module)."""
    from gsik.io.gltf.binding import skin_binding
    from gsik_studio.model.characters import body_character

    return SkinnedBody(plotter, skin_binding(body_character(skeleton)))
