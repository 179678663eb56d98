"""A glTF character's body: its meshes skinned by :mod:`gsik.skinning` every frame, into one PolyData in place.

Built once (one PolyData, one mapper, one actor); a frame writes the skinned points and normals into the
PolyData's own arrays (no VTK object is made per frame, see /work/shared/VIEWPORT.md). The same interface as the
mannequin (:class:`gsik_studio.mannequin.Mannequin`), so the body view draws either.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.util.numpy_support import vtk_to_numpy

from gsik.skinning import SkinBinding, skin_into
from gsik_studio.mannequin import SolidBody
from gsik_studio.scene import rgb8, touch


class SkinnedMesh:
    """One PolyData holding every vertex of a binding; :meth:`update` skins it in place."""

    def __init__(self, binding: SkinBinding) -> None:
        self.binding = binding
        tris = binding.triangles
        cells = np.hstack([np.full((len(tris), 1), 3, dtype=np.int64), tris]).ravel() if len(tris) else []
        self.polydata = pv.PolyData(np.asarray(binding.positions, dtype=float).copy(),
                                    faces=np.asarray(cells, dtype=np.int64))
        self.polydata.point_data.set_array(np.asarray(binding.normals, dtype=float).copy(), "Normals")
        self.polydata.point_data.active_normals_name = "Normals"
        self.polydata.point_data.set_array(rgb8(binding.colors), "colors")
        self._xyz = vtk_to_numpy(self.polydata.GetPoints().GetData())
        self._normals = vtk_to_numpy(self.polydata.GetPointData().GetArray("Normals"))
        self._world = None  # (n_frames, 4, 4), made on the first update and reused

    def update(self, P: np.ndarray, R: np.ndarray) -> None:
        """Skin to world positions P (n_frames, 3) [m] and rotations R (n_frames, 3, 3) of the skeleton's frames."""
        if self._world is None or len(self._world) != len(P):
            self._world = np.zeros((len(P), 4, 4))
            self._world[:, 3, 3] = 1.0
        self._world[:, :3, :3] = R
        self._world[:, :3, 3] = P
        skin_into(self.binding, self._world, self._xyz, self._normals)
        touch(self.polydata)
        self.polydata.GetPointData().GetArray("Normals").Modified()


class SkinnedBody(SolidBody):
    """A character's body drawn in ``plotter``: its skinned mesh and actor, moved by :meth:`update`."""

    def __init__(self, plotter: pv.Plotter, binding: SkinBinding) -> None:
        super().__init__(plotter, (SkinnedMesh(binding),))

    @property
    def n_vertices(self) -> int:
        return sum(m.binding.n_vertices for m in self.meshes)
