"""A gsik motion on a character as the glTF nodes' local transforms per frame.

Only the skin's joints move: each gets the rotation (and, for a joint whose parent is not a joint, the
translation) that puts it where gsik's forward kinematics has it; every other node keeps its file transform.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.anim.motion import Motion
from gsik.errors import GltfError, choices
from gsik.io.gltf.axes import gltf_from_gsik, xyzw_from_matrix
from gsik.io.gltf.character import Character
from gsik.kinematics import world_frames


class NodeTracks(NamedTuple):
    """The skin joints' local transforms per frame.

    Attributes:
        nodes: (n,) node index of each moved joint, in the skin's order.
        translation: (n_frames, n, 3) [m] local translation.
        rotation: (n_frames, n, 4) local rotation, quaternions ``(x, y, z, w)``, sign-continuous over frames.
        times: (n_frames,) [s] the time of each frame.
    """

    nodes: tuple[int, ...]
    translation: np.ndarray
    rotation: np.ndarray
    times: np.ndarray


def _q_on(character: Character, motion: Motion) -> np.ndarray:
    """(n_frames, n_dofs) the motion's angles on the character's skeleton, matched by DOF name."""
    sk, msk = character.skeleton, motion.skeleton
    if msk is sk or msk.dof_names == sk.dof_names:
        return np.asarray(motion.q)
    missing = [d for d in sk.dof_names if d not in msk.dof_names]
    if missing:
        raise GltfError(f"the motion's skeleton {msk.name!r} has no DOF {missing[0]!r} of the character "
                        f"{sk.name!r}; its DOFs: {choices(msk.dof_names)}")
    return np.asarray(motion.q)[:, [msk.dof_index(d) for d in sk.dof_names]]


def _posed_joint_worlds(character: Character, motion: Motion) -> np.ndarray:
    """(n_frames, n_joints, 4, 4) each gsik joint's world transform in the file's axes, its rest scale kept."""
    sk = character.skeleton
    q = _q_on(character, motion)
    frames = sk.joint_frame
    scale = np.ones(sk.n_joints)
    for i, node in enumerate(character.joint_nodes):
        if node >= 0:
            scale[i] = np.linalg.norm(character.rest_world[node][:3, 0])
    out = np.empty((motion.n_frames, sk.n_joints, 4, 4))
    for f in range(motion.n_frames):
        R, p = world_frames(sk, q[f], motion.world_from_root[f], motion.roots[f])
        T = np.zeros((sk.n_joints, 4, 4))
        T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = R[frames], p[frames], 1.0
        out[f] = gltf_from_gsik(T)
    out[..., :3, :3] *= scale[None, :, None, None]
    return out


def node_tracks(character: Character, motion: Motion) -> NodeTracks:
    """The local transforms that pose the character's skin joints as ``motion`` does, every frame.

    Raises:
        GltfError: the motion lacks a DOF of the character.
    """
    file = character.file
    joints = file.skins[character.skin].joints
    skin = set(joints)
    gsik_index = {node: i for i, node in enumerate(character.joint_nodes) if node in skin}
    posed = _posed_joint_worlds(character, motion)
    F = motion.n_frames
    translation = np.empty((F, len(joints), 3))
    rotation = np.empty((F, len(joints), 4))
    for k, node in enumerate(joints):
        parent_world = _posed_parent(character, posed, gsik_index, file.nodes[node].parent, F)
        local = np.linalg.solve(parent_world, posed[:, gsik_index[node]])
        translation[:, k] = local[:, :3, 3]
        R = local[:, :3, :3] / np.asarray(file.nodes[node].scale)[None, None, :]
        rotation[:, k] = _continuous([_orthonormal_xyzw(r) for r in R])
    return NodeTracks(tuple(joints), translation, rotation, np.arange(F) * motion.frame_time)


def _posed_parent(character: Character, posed: np.ndarray, gsik_index: dict[int, int], parent: int,
                  F: int) -> np.ndarray:
    """(F, 4, 4) world transform of node ``parent`` in the pose: moved with its nearest skin joint (a key of
    ``gsik_index``), else at rest."""
    if parent < 0:
        return np.broadcast_to(np.eye(4), (F, 4, 4))
    rest = character.rest_world
    a = parent
    while a >= 0 and a not in gsik_index:
        a = character.file.nodes[a].parent
    if a < 0:
        return np.broadcast_to(rest[parent], (F, 4, 4))
    return posed[:, gsik_index[a]] @ (np.linalg.inv(rest[a]) @ rest[parent])


def _orthonormal_xyzw(R: np.ndarray) -> np.ndarray:
    U, _, Vt = np.linalg.svd(R)
    return xyzw_from_matrix(U @ Vt)


def _continuous(quats: list[np.ndarray]) -> np.ndarray:
    """(F, 4) quaternions, each flipped to the sign nearer the one before (interpolation takes the short way)."""
    out = np.array(quats)
    for f in range(1, len(out)):
        if out[f] @ out[f - 1] < 0:
            out[f] = -out[f]
    return out
