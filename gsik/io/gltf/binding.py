"""A character's meshes as one :class:`~gsik.skinning.SkinBinding` on its gsik skeleton, in gsik's world.

Meshes deformed by the character's skin are skinned as the file says (``joint world @ inverse bind``); every other
mesh (unskinned, or another skin's) moves rigidly with its nearest ancestor joint, or with the top when it has none.
"""

from __future__ import annotations

import numpy as np

from gsik.io.gltf.axes import GSIK_FROM_GLTF4 as _C4
from gsik.io.gltf.character import Character
from gsik.io.gltf.model import GltfPrimitive
from gsik.skinning import SkinBinding


class _Parts:
    """Lists of per-primitive arrays, concatenated at the end."""

    def __init__(self) -> None:
        self.positions, self.normals, self.slots, self.weights, self.triangles, self.colors = [], [], [], [], [], []
        self.slot_frames: list[int] = []
        self.bind: list[np.ndarray] = []
        self.n = 0

    def slot(self, frame: int, bind: np.ndarray) -> int:
        self.slot_frames.append(int(frame))
        self.bind.append(bind)
        return len(self.bind) - 1

    def add(self, prim: GltfPrimitive, slots: np.ndarray, weights: np.ndarray) -> None:
        n = len(prim.positions)
        self.positions.append(prim.positions)
        self.normals.append(prim.normals if prim.normals is not None else np.tile([0.0, 0.0, 1.0], (n, 1)))
        self.slots.append(slots)
        self.weights.append(weights)
        self.triangles.append(prim.triangles + self.n)
        colors = prim.colors if prim.colors is not None else np.ones((n, 3))
        self.colors.append(colors * prim.base_color[:3])
        self.n += n

    def binding(self) -> SkinBinding:
        k = max((s.shape[1] for s in self.slots), default=1)

        def pad(a, fill):
            return np.hstack([a, np.full((len(a), k - a.shape[1]), fill, dtype=a.dtype)])

        if not self.positions:
            z = np.zeros((0, 3))
            return SkinBinding(z, z, np.zeros((0, 1), np.int64), np.zeros((0, 1)), np.zeros(1, np.int64),
                               np.eye(4)[None], np.zeros((0, 3), np.int64), z)
        return SkinBinding(np.concatenate(self.positions).astype(float), np.concatenate(self.normals).astype(float),
                           np.concatenate([pad(s, 0) for s in self.slots]),
                           np.concatenate([pad(w, 0.0) for w in self.weights]), np.array(self.slot_frames),
                           np.array(self.bind), np.concatenate(self.triangles), np.concatenate(self.colors))


def skin_binding(character: Character) -> SkinBinding:
    """Every mesh of ``character`` bound to its skeleton (see the module); positions in the file's units."""
    file, sk = character.file, character.skeleton
    gsik_of = {node: j for j, node in enumerate(character.joint_nodes) if node >= 0}
    rest_T = sk.frame_transforms(character.bind_q)[sk.joint_frame]  # (n_joints, 4, 4) gsik world at the bind
    skin = file.skins[character.skin]
    parts = _Parts()
    skin_slots = None
    for i, node in enumerate(file.nodes):
        if node.mesh < 0:
            continue
        for prim in file.meshes[node.mesh].primitives:
            if node.skin == character.skin and prim.joints is not None:
                if skin_slots is None:
                    skin_slots = _skin_slots(character, parts, skin, gsik_of)
                parts.add(prim, skin_slots[prim.joints], prim.weights)
            else:
                j = _attachment(character, gsik_of, i)
                bind = np.linalg.inv(rest_T[j]) @ _C4 @ character.rest_world[i]
                slot = parts.slot(sk.joint_frame[j], bind)
                n = len(prim.positions)
                parts.add(prim, np.full((n, 1), slot, dtype=np.int64), np.ones((n, 1)))
    return parts.binding()


def _skin_slots(character: Character, parts: _Parts, skin, gsik_of: dict[int, int]) -> np.ndarray:
    """(n_skin_joints,) slot of each skin joint: its gsik joint's frame, bind ``C @ scale @ inverse bind``."""
    sk = character.skeleton
    slots = []
    for s, node in enumerate(skin.joints):
        scale = np.diag([*(np.linalg.norm(character.rest_world[node][:3, :3], axis=0).mean(),) * 3, 1.0])
        slots.append(parts.slot(sk.joint_frame[gsik_of[node]], _C4 @ scale @ skin.inverse_bind[s]))
    return np.array(slots, dtype=np.int64)


def _attachment(character: Character, gsik_of: dict[int, int], node: int) -> int:
    """The gsik joint a rigid mesh node moves with: its nearest ancestor joint, else the top (0)."""
    a = character.file.nodes[node].parent
    while a >= 0 and a not in gsik_of:
        a = character.file.nodes[a].parent
    return gsik_of.get(a, 0)
