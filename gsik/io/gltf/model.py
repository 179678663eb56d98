"""The plain data of a glTF file between the reader and the writer (Blender's glTF I/O keeps the same split).

A reader returns a :class:`GltfFile`; the character builder and the writer take one. Arrays are read-only NumPy
arrays in the file's own axes (y up) and units (metres); nothing here knows gsik's skeletons.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class GltfNode:
    """One node of the file.

    Attributes:
        name: The node's name (``"node<i>"`` when the file gives none).
        parent: Index of the parent node, -1 for a scene root.
        translation: (3,) [m] in the parent's frame.
        rotation: (4,) unit quaternion ``(x, y, z, w)`` (glTF's order) in the parent's frame.
        scale: (3,) per-axis scale.
        mesh: Index of the mesh it shows, -1 for none.
        skin: Index of the skin that deforms that mesh, -1 for none.
    """

    name: str
    parent: int
    translation: np.ndarray
    rotation: np.ndarray
    scale: np.ndarray
    mesh: int = -1
    skin: int = -1


@dataclass(frozen=True, eq=False)
class GltfSkin:
    """A skin: the joints that deform its meshes.

    Attributes:
        name: The skin's name.
        joints: (n_joints,) node index of each joint, in the skin's order (what ``JOINTS_0`` indexes).
        inverse_bind: (n_joints, 4, 4) inverse bind matrices (identity when the file gives none).
    """

    name: str
    joints: tuple[int, ...]
    inverse_bind: np.ndarray


@dataclass(frozen=True, eq=False)
class GltfPrimitive:
    """One triangle list of a mesh, with what skinning needs.

    Attributes:
        positions: (n_vertices, 3) [m] bind-pose vertices in the mesh node's frame.
        normals: (n_vertices, 3) unit normals, or ``None``.
        triangles: (n_triangles, 3) vertex indices.
        joints: (n_vertices, 4 * k) skin joint indices (``JOINTS_0``, ``JOINTS_1`` ...), or ``None``.
        weights: (n_vertices, 4 * k) their weights, summing to 1 per vertex, or ``None``.
        base_color: (4,) RGBA of the material's base colour factor (white without a material).
        material: Index of the material, -1 for none.
        colors: (n_vertices, 3) RGB vertex colours (``COLOR_0``), or ``None``.
    """

    positions: np.ndarray
    normals: np.ndarray | None
    triangles: np.ndarray
    joints: np.ndarray | None
    weights: np.ndarray | None
    base_color: np.ndarray
    material: int = -1
    colors: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class GltfMesh:
    """A mesh: its primitives."""

    name: str
    primitives: tuple[GltfPrimitive, ...]


@dataclass(frozen=True, eq=False)
class GltfFile:
    """What a glTF file holds, read and checked.

    Attributes:
        path: Where it was read from (``"<memory>"`` when made in memory).
        nodes: Every node, in the file's order.
        skins: Every skin.
        meshes: Every mesh, with its primitives' arrays.
        document: The file's parsed JSON (a ``pygltflib.GLTF2``), kept so the writer can keep everything else.
        buffers: The bytes of every buffer, in the file's order (external and data-URI buffers resolved).
    """

    path: str
    nodes: tuple[GltfNode, ...]
    skins: tuple[GltfSkin, ...]
    meshes: tuple[GltfMesh, ...]
    document: object
    buffers: tuple[bytes, ...]

    @property
    def n_vertices(self) -> int:
        """Vertices of every primitive of every mesh."""
        return sum(len(p.positions) for m in self.meshes for p in m.primitives)


def frozen_array(values, dtype=float) -> np.ndarray:
    """``values`` as a new read-only array of ``dtype``."""
    a = np.array(values, dtype=dtype)
    a.flags.writeable = False
    return a
