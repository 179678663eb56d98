"""glTF's axes and transforms: quaternions ``(x, y, z, w)``, TRS <-> 4x4, y-up file world <-> gsik's z-up world.

glTF is y up, metres, the character facing +z; gsik is z up. A point ``p_file`` is ``GSIK_FROM_GLTF @ p_file`` in
gsik's world (file y -> gsik z, file z -> gsik -y), the turn Blender's glTF importer makes too, so gsik's world
coordinates of a glTF character are Blender's.
"""

from __future__ import annotations

import numpy as np

from gsik.errors import GltfError
from gsik.rotations import matrix_from_quaternion, quaternion_from_rows

#: (3, 3) file (y up) -> gsik world (z up): +90 degrees about x.
GSIK_FROM_GLTF = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
GSIK_FROM_GLTF.flags.writeable = False
#: (4, 4) the same turn as a homogeneous transform.
GSIK_FROM_GLTF4 = np.eye(4)
GSIK_FROM_GLTF4[:3, :3] = GSIK_FROM_GLTF
GSIK_FROM_GLTF4.flags.writeable = False
_C4 = GSIK_FROM_GLTF4


def matrix_from_xyzw(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) in glTF's order ``(x, y, z, w)``."""
    q = np.asarray(q, dtype=float)
    return matrix_from_quaternion(np.concatenate([q[..., 3:], q[..., :3]], axis=-1))


def xyzw_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (4,) ``(x, y, z, w)``, ``w >= 0``, of a rotation matrix (3, 3)."""
    w, x, y, z = quaternion_from_rows(np.asarray(R, dtype=float).tolist())
    return np.array([x, y, z, w])


def matrix_from_trs(t, r, s) -> np.ndarray:
    """(4, 4) ``T @ R @ S`` of a translation (3,), a quaternion (4,) ``(x, y, z, w)`` and a scale (3,)."""
    M = np.eye(4)
    M[:3, :3] = matrix_from_xyzw(r) * np.asarray(s, dtype=float)[None, :]
    M[:3, 3] = t
    return M


def trs_from_matrix(M: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(translation (3,), rotation (4,) (x, y, z, w), scale (3,))`` of an affine (4, 4) without shear.

    Raises:
        GltfError: a matrix that is not translation, rotation and positive scale (``what`` names it).
    """
    A = np.asarray(M, dtype=float)[:3, :3]
    s = np.linalg.norm(A, axis=0)
    if np.any(s <= 1e-12) or np.linalg.det(A) <= 0:
        raise GltfError(f"{what} is not a rotation with a positive scale")
    R = A / s[None, :]
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-4:
        raise GltfError(f"{what} has shear: gsik reads translation, rotation and scale")
    return np.array(M[:3, 3], dtype=float), xyzw_from_matrix(R), s


def gsik_from_gltf(M: np.ndarray) -> np.ndarray:
    """Transforms (..., 4, 4) of the file's world expressed in gsik's world (the same frames, z up)."""
    return _C4 @ np.asarray(M, dtype=float) @ _C4.T


def gltf_from_gsik(M: np.ndarray) -> np.ndarray:
    """The inverse of :func:`gsik_from_gltf`."""
    return _C4.T @ np.asarray(M, dtype=float) @ _C4


def node_world(nodes) -> np.ndarray:
    """(n_nodes, 4, 4) world transform of every node at its file TRS (parents need not come first)."""
    local = [matrix_from_trs(n.translation, n.rotation, n.scale) for n in nodes]
    world: list[np.ndarray | None] = [None] * len(nodes)

    def at(i: int) -> np.ndarray:
        chain = []
        while i != -1 and world[i] is None:
            chain.append(i)
            i = nodes[i].parent
        above = np.eye(4) if i == -1 else world[i]
        for j in reversed(chain):
            above = world[j] = above @ local[j]
        return above

    for i in range(len(nodes)):
        at(i)
    return np.array(world).reshape(len(nodes), 4, 4)


def rigid(M: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """``(rotation (3, 3), position (3,), uniform scale)`` of a (4, 4) with a uniform positive scale.

    Raises:
        GltfError: a non-uniform scale or shear.
    """
    A = np.asarray(M, dtype=float)[:3, :3]
    s = np.linalg.norm(A, axis=0)
    if np.any(s <= 1e-12) or np.ptp(s) > 1e-4 * s.max():
        raise GltfError(f"a joint's world scale {np.round(s, 6).tolist()} is not uniform; gsik's joints are rigid")
    R = A / s[None, :]
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt, np.array(M[:3, 3], dtype=float), float(s.mean())
