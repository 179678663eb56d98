"""A skinned glTF character as a gsik skeleton: the skin's joints as ball joints, recognised as a humanoid.

Conventions:

* **Joints.** Every joint of the skin (the skin with the most joints when there are several) becomes a gsik joint
  of the same name, with three one-DOF rotations about its own local axes, x then y then z (DOF names
  ``"<joint>.x"`` ...). Its rest (all angles 0) is the file's rest pose: the joint's offset and fixed orientation
  are where the file's nodes place it, so the file's node rotation of a pose is ``rest rotation @ Rx Ry Rz``.
* **Top.** Above the skin's top joints sits a fixed joint named after their common parent node (Blender's armature
  object), or ``"scene"`` when they have none: the character's placement in the world.
* **Humanoid.** :func:`gsik.humanoid.recognise` names the joints; the recognised ones get human ranges
  (:mod:`gsik.io.gltf.ranges`), every other joint (fingers, twist, face, props) zero ranges: it stays at its rest
  angles. Effector sites ``head``, ``pelvis``, ``left_hand``, ``right_hand``, ``left_foot``, ``right_foot`` sit
  at their joints, named so for every naming (the biped's names: the studio pins the pelvis and feet by them, and
  poses move between characters); the IK root is the right foot; :attr:`Character.poles` names the knee and elbow
  joints for pole targets.
* **Names.** A gsik joint has its node's name, except a node named like an effector (Unreal's ``head`` and
  ``pelvis``): its joint is ``<name>_joint`` (:data:`gsik.io.names.RENAMED_JOINT`); the file keeps its name
  (gsik writes by node, :attr:`Character.file_names`). Pose files of older gsik, which named those effectors
  ``<name>_site`` and kept the joint's name, still read (:mod:`gsik.io.pose.legacy`).
* **Units and axes.** Metres; the file's y-up world turned to gsik's z up (:mod:`gsik.io.gltf.axes`), as Blender's
  importer does. Joints must have a uniform world scale.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

import numpy as np

from gsik.errors import GltfError
from gsik.humanoid.bones import POLE_BONES
from gsik.io.gltf.axes import gsik_from_gltf, node_world, rigid
from gsik.io.gltf.model import GltfFile
from gsik.io.gltf.ranges import RestFrame, joint_limits
from gsik.io.gltf.read import read_gltf
from gsik.io.names import RENAMED_JOINT, unique_name
from gsik.skeleton import JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton

#: Effector site -> the canonical (VRM) bone it sits on, in the order the skeleton lists them.
EFFECTOR_BONES = {"head": "head", "pelvis": "hips", "left_hand": "leftHand", "right_hand": "rightHand",
                  "left_foot": "leftFoot", "right_foot": "rightFoot"}
ROOT_EFFECTOR = "right_foot"
#: Most skin joints made into a skeleton (three DOFs each, within gsik's solver's limits).
MAX_JOINTS = 600
_AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@dataclass(frozen=True, eq=False)
class Character:
    """A glTF character ready to pose.

    Attributes:
        file: The file read.
        skeleton: Its gsik skeleton (joint 0 the fixed top, then one joint per skin joint).
        skin: Index of the skin the skeleton is made of.
        joint_nodes: (n_joints,) node index of each gsik joint (the top's node, or -1 for ``"scene"``).
        recognition: What :func:`gsik.humanoid.recognise` found.
        effectors: Effector name (``"head"`` ...) -> the site that carries it.
        poles: Pole name (``"left_knee"`` ...) -> the joint it bends.
        rest_world: (n_nodes, 4, 4) every node's world transform at rest, in the file's axes.
        bind_q: (n_dofs,) [rad] the skeleton's angles at the file's rest pose (zeros for a file read).
    """

    file: GltfFile
    skeleton: Skeleton
    skin: int
    joint_nodes: tuple[int, ...]
    recognition: object
    effectors: Mapping[str, str]
    poles: Mapping[str, str]
    rest_world: np.ndarray
    bind_q: np.ndarray

    @property
    def name(self) -> str:
        return self.skeleton.name

    @property
    def file_names(self) -> tuple[str, ...]:
        """The file's name (n_joints,) of each gsik joint's node (``"scene"`` for a made-up top): the joint's own
        name but where the node's is an effector's (see :data:`gsik.io.names.RENAMED_JOINT`) or repeats another's."""
        return tuple("scene" if n < 0 else self.file.nodes[n].name for n in self.joint_nodes)


def read_character(path: str | os.PathLike, overrides: Mapping[str, str] | None = None) -> Character:
    """Read a skinned glTF character (``.glb``/``.gltf``) and make it a posable gsik skeleton.

    Args:
        path: The file.
        overrides: Canonical bone -> joint name, winning over recognition (see :func:`gsik.humanoid.recognise`).

    Raises:
        GltfError: a bad file (see :func:`~gsik.io.gltf.read.read_gltf`), no skin, joints with a non-uniform scale.
        HumanoidError: the skin is not a humanoid (the required bones are missing).
    """
    return character_from_file(read_gltf(path), overrides)


def character_from_file(file: GltfFile, overrides: Mapping[str, str] | None = None) -> Character:
    """:func:`read_character` of a file already read."""
    from gsik.humanoid import Rig, recognise

    skin = _main_skin(file)
    world = node_world(file.nodes)
    b = _Builder(file, skin, gsik_from_gltf(world))
    rig = Rig(b.file_names[1:], tuple(p - 1 for p in b.parents[1:]), b.positions[1:].copy())
    recognition = _on_joints(recognise(rig, overrides), dict(zip(b.file_names, b.names)))
    b.add_joints(recognition)
    effectors = b.add_effectors(recognition)
    name = os.path.splitext(os.path.basename(file.path))[0] or "gltf"
    skeleton = build_skeleton(name, b.specs, b.sites, b.segments(), effectors=list(effectors.values()),
                              root=effectors[ROOT_EFFECTOR], source=file.path)
    poles = {pole: recognition.bones[bone] for pole, bone in POLE_BONES.items() if bone in recognition.bones}
    world.flags.writeable = False
    node_of = dict(zip(b.names, b.nodes))  # the builder orders joints its own way
    return Character(file, skeleton, skin, tuple(node_of[n] for n in skeleton.joint_names), recognition,
                     MappingProxyType(effectors), MappingProxyType(poles), world, np.zeros(skeleton.n_dofs))


def _on_joints(recognition, joint_of: Mapping[str, str]):
    """``recognition`` (made on the file's names) with the gsik joints' names (:data:`RENAMED_JOINT`)."""
    return replace(recognition, bones=MappingProxyType({b: joint_of[j] for b, j in recognition.bones.items()}),
                   ignored=MappingProxyType({joint_of[j]: why for j, why in recognition.ignored.items()}))


def _main_skin(file: GltfFile) -> int:
    if not file.skins:
        raise GltfError(f"{file.path}: the file has no skin: gsik poses skinned characters (an armature with a "
                        "mesh bound to it)")
    return max(range(len(file.skins)), key=lambda k: len(file.skins[k].joints))


class _Builder:
    """The skin's joints in parent-first order, their rest frames in gsik's world, then the skeleton's specs.

    Attributes:
        nodes: (n,) node index per gsik joint (-1 for a synthetic top); names, parents (gsik joint indices).
        R, positions: (n, 3, 3) world rotations and (n, 3) world positions [m] at rest, gsik's axes.
    """

    def __init__(self, file: GltfFile, skin: int, world: np.ndarray) -> None:
        self.file = file
        joints = set(file.skins[skin].joints)
        top = self._top_node(joints)
        order = sorted(joints, key=lambda j: (self._depth(j), j))
        if len(order) > MAX_JOINTS:
            raise GltfError(f"{file.path}: skin {file.skins[skin].name!r} has {len(order):,} joints; gsik poses at "
                            f"most {MAX_JOINTS:,}")
        self.nodes = [top, *order]
        self.index = {n: i for i, n in enumerate(self.nodes) if i > 0}
        self.parents = [-1] + [self._joint_parent(j, top) for j in order]
        frames = [np.eye(4) if top < 0 else world[top]] + [world[j] for j in order]
        rigid_frames = [rigid(M) for M in frames]
        self.R = np.array([r for r, _, _ in rigid_frames])
        self.positions = np.array([p for _, p, _ in rigid_frames])
        taken: set[str] = set()
        self.names = []
        for n in self.nodes:
            self.names.append(unique_name("scene" if n < 0 else file.nodes[n].name, taken))
            taken.add(self.names[-1])
        self.file_names = tuple(self.names)  # what recognition reads
        self.names = [unique_name(RENAMED_JOINT.format(n), taken) if n in EFFECTOR_BONES else n for n in self.names]
        self.specs: list[JointSpec] = []
        self.sites: list[SiteSpec] = []

    def _depth(self, j: int) -> int:
        d = 0
        while self.file.nodes[j].parent != -1:
            j, d = self.file.nodes[j].parent, d + 1
        return d

    def _ancestors(self, j: int) -> list[int]:
        out = []
        while self.file.nodes[j].parent != -1:
            j = self.file.nodes[j].parent
            out.append(j)
        return out

    def _top_node(self, joints: set[int]) -> int:
        """The deepest node above every top joint of the skin, -1 when only the scene is."""
        tops = [j for j in joints if not set(self._ancestors(j)) & joints]
        common = None
        for j in tops:
            chain = self._ancestors(j)
            common = chain if common is None else [n for n in common if n in chain]
        return common[0] if common else -1

    def _joint_parent(self, j: int, top: int) -> int:
        """The gsik index of ``j``'s nearest ancestor that is a skin joint, else the top (0)."""
        for a in self._ancestors(j):
            if a in self.index:
                return self.index[a]
        return 0

    def _rest(self, i: int, forward: np.ndarray) -> RestFrame:
        children = [c for c, p in enumerate(self.parents) if p == i]
        bone = (np.mean([self.positions[c] for c in children], axis=0) - self.positions[i]) if children \
            else np.zeros(3)
        return RestFrame(self.R[i], bone, forward)

    def add_joints(self, recognition) -> None:
        """The top (fixed) and one ball joint per skin joint, ranges from ``recognition``."""
        bone_of = {joint: bone for bone, joint in recognition.bones.items()}
        forward = np.asarray(recognition.forward, dtype=float)
        self.specs = [JointSpec(self.names[0], None, tuple(self.positions[0]), (), self.R[0])]
        for i in range(1, len(self.nodes)):
            p = self.parents[i]
            offset = self.R[p].T @ (self.positions[i] - self.positions[p])
            limits = joint_limits(bone_of.get(self.names[i]), self._rest(i, forward))
            rotations = tuple(RotationSpec(axis, lo, hi, 0.0, "xyz"[k])
                              for k, (axis, (lo, hi)) in enumerate(zip(_AXES, limits)))
            self.specs.append(JointSpec(self.names[i], self.names[p], tuple(offset), rotations,
                                        self.R[p].T @ self.R[i]))

    def add_effectors(self, recognition) -> dict[str, str]:
        """A site per effector at its recognised joint; returns effector -> site name."""
        effectors = {}
        for effector, bone in EFFECTOR_BONES.items():  # no joint has an effector's name (RENAMED_JOINT)
            self.sites.append(SiteSpec(effector, recognition.joint(bone), (0.0, 0.0, 0.0)))
            effectors[effector] = effector
        return effectors

    def segments(self) -> list[SegmentSpec]:
        """One segment per joint with children, drawn to each child joint."""
        segments = []
        for i, name in enumerate(self.names):
            ends = tuple(self.names[c] for c, p in enumerate(self.parents) if p == i)
            if ends and i > 0:
                segments.append(SegmentSpec(name, name, ends))
        return segments
