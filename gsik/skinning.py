"""Linear blend skinning in NumPy, in place (three.js's SkinnedMesh: bind matrices, bone matrices, weights).

A :class:`SkinBinding` ties each vertex to a few *slots*; a slot is a skeleton frame and a constant bind matrix.
Each frame, a slot's matrix is ``world_from_frame @ bind`` and a vertex's position is the weighted sum of its slots'
matrices applied to its bind position::

    p = sum_k w[v, k] * (T[frame[slot[v, k]]] @ bind[slot[v, k]]) @ (bind_position[v], 1)

:func:`skin_into` writes the result into arrays the caller owns (a viewer's vertex buffer), so nothing is allocated
for the mesh's size per frame beyond NumPy's temporaries.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class SkinBinding:
    """What skinning a mesh needs, fixed once.

    Attributes:
        positions: (n_vertices, 3) bind positions, in the frame ``bind`` matrices take them from.
        normals: (n_vertices, 3) bind normals.
        slots: (n_vertices, k) slot index of each influence.
        weights: (n_vertices, k) influence weights, summing to 1 per vertex.
        slot_frames: (n_slots,) skeleton frame index each slot moves with.
        bind: (n_slots, 4, 4) constant matrix per slot: world_from_vertex = world_from_frame @ bind.
        triangles: (n_triangles, 3) vertex indices.
        colors: (n_vertices, 3) RGB in [0, 1].
    """

    positions: np.ndarray
    normals: np.ndarray
    slots: np.ndarray
    weights: np.ndarray
    slot_frames: np.ndarray
    bind: np.ndarray
    triangles: np.ndarray
    colors: np.ndarray

    def __post_init__(self) -> None:
        kinds = {"slots": np.int64, "slot_frames": np.int64, "triangles": np.int64}
        for name in self.__dataclass_fields__:
            value = np.ascontiguousarray(getattr(self, name), dtype=kinds.get(name, np.float64))
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    @property
    def n_vertices(self) -> int:
        return len(self.positions)


def slot_matrices(binding: SkinBinding, world_from_frames: np.ndarray) -> np.ndarray:
    """(n_slots, 3, 4) the upper rows of each slot's matrix, given every frame's world transform (n_frames, 4, 4)."""
    return (world_from_frames[binding.slot_frames] @ binding.bind)[:, :3, :]


def skin_into(binding: SkinBinding, world_from_frames: np.ndarray, points: np.ndarray,
              normals: np.ndarray | None = None) -> None:
    """Skin the mesh at a pose: world positions into ``points`` (n_vertices, 3), unit normals into ``normals``.

    Args:
        binding: The mesh's binding.
        world_from_frames: (n_frames, 4, 4) the skeleton's world transforms [m] at the pose.
        points: (n_vertices, 3) float64 or float32 (a viewer's vertex buffer), written in place [m].
        normals: (n_vertices, 3) of the same type, written in place, or ``None`` to skip them.
    """
    blend_into(binding, np.ascontiguousarray(slot_matrices(binding, world_from_frames)), points, normals)


def blend_into(binding: SkinBinding, M: np.ndarray, points: np.ndarray, normals: np.ndarray | None = None) -> None:
    """:func:`skin_into` given the slot matrices ``M`` (n_slots, 3, 4) (:func:`slot_matrices`, C-contiguous)."""
    from gsik.kernels.skinning import blend_skin

    out_normals = normals if normals is not None else np.empty_like(points)
    blend_skin(M, binding.slots, binding.weights, binding.positions, binding.normals, points, out_normals)


def skinned(binding: SkinBinding, world_from_frames: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(points, normals)`` (n_vertices, 3) of the mesh at a pose, in new arrays (see :func:`skin_into`)."""
    points = np.empty((binding.n_vertices, 3))
    normals = np.empty((binding.n_vertices, 3))
    skin_into(binding, world_from_frames, points, normals)
    return points, normals
