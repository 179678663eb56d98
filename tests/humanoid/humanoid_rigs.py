"""Small humanoid test rigs of every naming convention, in T- or A-pose, y- or z-up (plain data and BVH clips).

One body: hips at 100 units, legs 95 long, arms 53 long from the shoulder, facing +z (y up) with its left side
+x; z-up rigs are the same turned (y -> z, z -> -y: facing -y, left +x). Each convention names the joints and adds
its own helpers (twist, share and roll bones, ASF's hip joints, MakeHuman's shoulder helper, fingers, End Sites).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsik.humanoid import Rig
from gsik.io.bvh import BvhClip, BvhJoint

#: Rest positions of the canonical body parts (y up, facing +z, left +x, T-pose).
BODY = {
    "hips": (0, 100, 0), "spine": (0, 110, 0), "chest": (0, 125, 0), "upperChest": (0, 140, 0),
    "neck": (0, 152, 0), "head": (0, 162, 0), "headTop": (0, 182, 0),
    "Shoulder": (3, 148, 0), "UpperArm": (17, 148, 0), "LowerArm": (45, 148, 0), "Hand": (70, 148, 0),
    "Finger": (78, 148, 0), "UpperLeg": (9, 95, 0), "LowerLeg": (9, 52, 0), "Foot": (9, 8, 0),
    "Toes": (9, 1, 12), "ToesEnd": (9, 0, 18),
}


@dataclass(frozen=True)
class Convention:
    """How one convention names the body: ``(name, part)`` rows, ``{s}`` the side's word in ``sides``.

    ``part`` is a :data:`BODY` key (a limb part without its side), ``"at:<part>"`` for a helper at that part's
    place, ``"twist:<part>"`` for a twist/share helper at the part with a short child, or ``"trunk<k>"`` for
    the k-th of ``n_trunk`` joints spaced between the hips and the neck. ``expect``: canonical bone -> name.
    """

    name: str
    trunk: tuple[tuple[str, str], ...]
    arm: tuple[tuple[str, str], ...]
    leg: tuple[tuple[str, str], ...]
    sides: tuple[str, str]
    expect: dict


def _c(name, trunk, arm, leg, sides, expect):
    return Convention(name, tuple(trunk), tuple(arm), tuple(leg), sides, expect)


def _limbs(arm, leg, clav=None):
    """The canonical bones of one side's arm and leg rows (templates): {part: name template}."""
    bones = dict(zip(("UpperArm", "LowerArm", "Hand"), arm))
    bones.update(zip(("UpperLeg", "LowerLeg", "Foot"), leg))
    if clav:
        bones["Shoulder"] = clav
    return bones


CONVENTIONS = [
    _c("mixamo", [("mixamorig:Hips", "hips"), ("mixamorig:Spine", "spine"), ("mixamorig:Spine1", "chest"),
                  ("mixamorig:Spine2", "upperChest"), ("mixamorig:Neck", "neck"), ("mixamorig:Head", "head"),
                  ("mixamorig:HeadTop_End", "headTop")],
       [("mixamorig:{s}Shoulder", "Shoulder"), ("mixamorig:{s}Arm", "UpperArm"), ("mixamorig:{s}ForeArm", "LowerArm"),
        ("mixamorig:{s}Hand", "Hand"), ("mixamorig:{s}HandIndex1", "Finger")],
       [("mixamorig:{s}UpLeg", "UpperLeg"), ("mixamorig:{s}Leg", "LowerLeg"), ("mixamorig:{s}Foot", "Foot"),
        ("mixamorig:{s}ToeBase", "Toes"), ("mixamorig:{s}Toe_End", "ToesEnd")],
       ("Left", "Right"),
       {"hips": "mixamorig:Hips", "spine": "mixamorig:Spine", "neck": "mixamorig:Neck", "head": "mixamorig:Head",
        **_limbs(("mixamorig:{s}Arm", "mixamorig:{s}ForeArm", "mixamorig:{s}Hand"),
                 ("mixamorig:{s}UpLeg", "mixamorig:{s}Leg", "mixamorig:{s}Foot"), "mixamorig:{s}Shoulder"),
        "Toes": "mixamorig:{s}ToeBase"}),
    _c("character_creator", [("CC_Base_BoneRoot", "at:hips"), ("CC_Base_Hip", "hips"), ("CC_Base_Waist", "spine"),
                             ("CC_Base_Spine01", "chest"), ("CC_Base_Spine02", "upperChest"),
                             ("CC_Base_NeckTwist01", "neck"), ("CC_Base_NeckTwist02", "mid:neck"),
                             ("CC_Base_Head", "head"), ("CC_Base_FacialBone", "at:head")],
       [("CC_Base_{s}_Clavicle", "Shoulder"), ("CC_Base_{s}_Upperarm", "UpperArm"),
        ("CC_Base_{s}_UpperarmTwist01", "twist:UpperArm"), ("CC_Base_{s}_Forearm", "LowerArm"),
        ("CC_Base_{s}_ElbowShareBone", "twist:LowerArm"), ("CC_Base_{s}_Hand", "Hand"),
        ("CC_Base_{s}_Mid1", "Finger")],
       [("CC_Base_{s}_Thigh", "UpperLeg"), ("CC_Base_{s}_ThighTwist01", "twist:UpperLeg"),
        ("CC_Base_{s}_Calf", "LowerLeg"), ("CC_Base_{s}_KneeShareBone", "twist:LowerLeg"),
        ("CC_Base_{s}_Foot", "Foot"), ("CC_Base_{s}_ToeBaseShareBone", "twist:Toes"), ("CC_Base_{s}_ToeBase", "Toes"),
        ("CC_Base_{s}_BigToe1", "ToesEnd")],
       ("L", "R"),
       {"hips": "CC_Base_Hip", "spine": "CC_Base_Waist", "neck": "CC_Base_NeckTwist01", "head": "CC_Base_Head",
        **_limbs(("CC_Base_{s}_Upperarm", "CC_Base_{s}_Forearm", "CC_Base_{s}_Hand"),
                 ("CC_Base_{s}_Thigh", "CC_Base_{s}_Calf", "CC_Base_{s}_Foot"), "CC_Base_{s}_Clavicle"),
        "Toes": "CC_Base_{s}_ToeBase"}),
    _c("unreal", [("root", "at:Floor"), ("pelvis", "hips"), ("spine_01", "trunk0"), ("spine_02", "trunk1"),
                  ("spine_03", "trunk2"), ("spine_04", "trunk3"), ("spine_05", "trunk4"), ("neck_01", "neck"),
                  ("neck_02", "mid:neck"), ("head", "head")],
       [("clavicle_{s}", "Shoulder"), ("upperarm_{s}", "UpperArm"), ("upperarm_twist_01_{s}", "twist:UpperArm"),
        ("lowerarm_{s}", "LowerArm"), ("lowerarm_twist_01_{s}", "twist:LowerArm"), ("hand_{s}", "Hand"),
        ("index_01_{s}", "Finger")],
       [("thigh_{s}", "UpperLeg"), ("thigh_twist_01_{s}", "twist:UpperLeg"), ("calf_{s}", "LowerLeg"),
        ("calf_twist_01_{s}", "twist:LowerLeg"), ("foot_{s}", "Foot"), ("ball_{s}", "Toes")],
       ("l", "r"),
       {"hips": "pelvis", "spine": "spine_01", "neck": "neck_01", "head": "head",
        **_limbs(("upperarm_{s}", "lowerarm_{s}", "hand_{s}"), ("thigh_{s}", "calf_{s}", "foot_{s}"), "clavicle_{s}"),
        "Toes": "ball_{s}"}),
    _c("unity_vrm", [("Hips", "hips"), ("Spine", "spine"), ("Chest", "chest"), ("UpperChest", "upperChest"),
                     ("Neck", "neck"), ("Head", "head")],
       [("{s}Shoulder", "Shoulder"), ("{s}UpperArm", "UpperArm"), ("{s}LowerArm", "LowerArm"), ("{s}Hand", "Hand"),
        ("{s}IndexProximal", "Finger")],
       [("{s}UpperLeg", "UpperLeg"), ("{s}LowerLeg", "LowerLeg"), ("{s}Foot", "Foot"), ("{s}Toes", "Toes")],
       ("Left", "Right"),
       {"hips": "Hips", "spine": "Spine", "neck": "Neck", "head": "Head",
        **_limbs(("{s}UpperArm", "{s}LowerArm", "{s}Hand"), ("{s}UpperLeg", "{s}LowerLeg", "{s}Foot"), "{s}Shoulder"),
        "Toes": "{s}Toes"}),
    _c("cmu_asf", [("root", "hips"), ("lowerback", "spine"), ("upperback", "chest"), ("thorax", "upperChest"),
                   ("lowerneck", "neck"), ("upperneck", "mid:neck"), ("head", "head")],
       [("{s}clavicle", "Shoulder"), ("{s}humerus", "UpperArm"), ("{s}radius", "LowerArm"), ("{s}wrist", "Hand"),
        ("{s}hand", "Finger"), ("{s}thumb", "twist:Finger")],
       [("{s}hipjoint", "at:hips"), ("{s}femur", "UpperLeg"), ("{s}tibia", "LowerLeg"), ("{s}foot", "Foot"),
        ("{s}toes", "Toes")],
       ("l", "r"),
       {"hips": "root", "spine": "lowerback", "neck": "lowerneck", "head": "head",
        **_limbs(("{s}humerus", "{s}radius", "{s}wrist"), ("{s}femur", "{s}tibia", "{s}foot"), "{s}clavicle"),
        "Toes": "{s}toes"}),
    _c("rigify", [("DEF-spine", "hips"), ("DEF-spine.001", "spine"), ("DEF-spine.002", "chest"),
                  ("DEF-spine.003", "upperChest"), ("DEF-neck", "neck"), ("DEF-head", "head")],
       [("DEF-shoulder.{s}", "Shoulder"), ("DEF-upper_arm.{s}", "UpperArm"), ("DEF-upper_arm.{s}.001", "mid:UpperArm"),
        ("DEF-forearm.{s}", "LowerArm"), ("DEF-forearm.{s}.001", "mid:LowerArm"), ("DEF-hand.{s}", "Hand")],
       [("DEF-pelvis.{s}", "twist:hips"), ("DEF-thigh.{s}", "UpperLeg"), ("DEF-thigh.{s}.001", "mid:UpperLeg"),
        ("DEF-shin.{s}", "LowerLeg"), ("DEF-shin.{s}.001", "mid:LowerLeg"), ("DEF-foot.{s}", "Foot"),
        ("DEF-toe.{s}", "Toes")],
       ("L", "R"),
       {"hips": "DEF-spine", "spine": "DEF-spine.001", "neck": "DEF-neck", "head": "DEF-head",
        **_limbs(("DEF-upper_arm.{s}", "DEF-forearm.{s}", "DEF-hand.{s}"),
                 ("DEF-thigh.{s}", "DEF-shin.{s}", "DEF-foot.{s}"), "DEF-shoulder.{s}"),
        "Toes": "DEF-toe.{s}"}),
    _c("max_biped", [("Bip01", "at:hips"), ("Bip01 Pelvis", "hips"), ("Bip01 Spine", "spine"),
                     ("Bip01 Spine1", "chest"), ("Bip01 Spine2", "upperChest"), ("Bip01 Neck", "neck"),
                     ("Bip01 Head", "head"), ("Bip01 HeadNub", "headTop")],
       [("Bip01 {s} Clavicle", "Shoulder"), ("Bip01 {s} UpperArm", "UpperArm"), ("Bip01 {s} Forearm", "LowerArm"),
        ("Bip01 {s} Hand", "Hand"), ("Bip01 {s} Finger0", "Finger")],
       [("Bip01 {s} Thigh", "UpperLeg"), ("Bip01 {s} Calf", "LowerLeg"), ("Bip01 {s} Foot", "Foot"),
        ("Bip01 {s} Toe0", "Toes"), ("Bip01 {s} Toe0Nub", "ToesEnd")],
       ("L", "R"),
       {"hips": "Bip01 Pelvis", "spine": "Bip01 Spine", "neck": "Bip01 Neck", "head": "Bip01 Head",
        **_limbs(("Bip01 {s} UpperArm", "Bip01 {s} Forearm", "Bip01 {s} Hand"),
                 ("Bip01 {s} Thigh", "Bip01 {s} Calf", "Bip01 {s} Foot"), "Bip01 {s} Clavicle"),
        "Toes": "Bip01 {s} Toe0"}),
    _c("daz", [("hip", "hips"), ("pelvis", "at:hips"), ("abdomenLower", "spine"), ("abdomenUpper", "chest"),
               ("chestLower", "upperChest"), ("neckLower", "neck"), ("head", "head")],
       [("{s}Collar", "Shoulder"), ("{s}ShldrBend", "UpperArm"), ("{s}ShldrTwist", "mid:UpperArm"),
        ("{s}ForearmBend", "LowerArm"), ("{s}ForearmTwist", "mid:LowerArm"), ("{s}Hand", "Hand")],
       [("{s}ThighBend", "UpperLeg"), ("{s}ThighTwist", "mid:UpperLeg"), ("{s}Shin", "LowerLeg"), ("{s}Foot", "Foot"),
        ("{s}Toe", "Toes")],
       ("l", "r"),
       {"hips": "hip", "spine": "abdomenLower", "neck": "neckLower", "head": "head",
        **_limbs(("{s}ShldrBend", "{s}ForearmBend", "{s}Hand"), ("{s}ThighBend", "{s}Shin", "{s}Foot"), "{s}Collar"),
        "Toes": "{s}Toe"}),
    _c("daz_genesis2", [("hip", "hips"), ("abdomen", "spine"), ("abdomen2", "chest"), ("chest", "upperChest"),
                        ("neck", "neck"), ("head", "head")],
       [("{s}Collar", "Shoulder"), ("{s}Shldr", "UpperArm"), ("{s}ForeArm", "LowerArm"), ("{s}Hand", "Hand")],
       [("{s}Thigh", "UpperLeg"), ("{s}Shin", "LowerLeg"), ("{s}Foot", "Foot"), ("{s}Toe", "Toes")],
       ("l", "r"),
       {"hips": "hip", "spine": "abdomen", "neck": "neck", "head": "head",
        **_limbs(("{s}Shldr", "{s}ForeArm", "{s}Hand"), ("{s}Thigh", "{s}Shin", "{s}Foot"), "{s}Collar"),
        "Toes": "{s}Toe"}),
    _c("makehuman", [("root", "hips"), ("spine05", "spine"), ("spine04", "trunk1"), ("spine03", "trunk2"),
                     ("spine02", "trunk3"), ("spine01", "trunk4"), ("neck01", "neck"), ("neck02", "mid:neck"),
                     ("head", "head")],
       [("clavicle.{s}", "Shoulder"), ("shoulder01.{s}", "mid:Shoulder"), ("upperarm01.{s}", "UpperArm"),
        ("upperarm02.{s}", "mid:UpperArm"), ("lowerarm01.{s}", "LowerArm"), ("lowerarm02.{s}", "mid:LowerArm"),
        ("wrist.{s}", "Hand"), ("finger1-1.{s}", "Finger")],
       [("pelvis.{s}", "mid:UpperLeg"), ("upperleg01.{s}", "UpperLeg"), ("upperleg02.{s}", "mid:UpperLeg"),
        ("lowerleg01.{s}", "LowerLeg"), ("lowerleg02.{s}", "mid:LowerLeg"), ("foot.{s}", "Foot"),
        ("toe1-1.{s}", "Toes")],
       ("L", "R"),
       {"hips": "root", "spine": "spine05", "neck": "neck01", "head": "head",
        **_limbs(("upperarm01.{s}", "lowerarm01.{s}", "wrist.{s}"), ("upperleg01.{s}", "lowerleg01.{s}", "foot.{s}"),
                 "clavicle.{s}"),
        "Toes": "toe1-1.{s}"}),
    _c("mocap_collar", [("Hips", "hips"), ("Chest", "spine"), ("Chest2", "chest"), ("Neck", "neck"), ("Head", "head")],
       [("{s}Collar", "Shoulder"), ("{s}Shoulder", "UpperArm"), ("{s}Elbow", "LowerArm"), ("{s}Wrist", "Hand")],
       [("{s}Hip", "UpperLeg"), ("{s}Knee", "LowerLeg"), ("{s}Ankle", "Foot"), ("{s}Toe", "Toes")],
       ("Left", "Right"),
       {"hips": "Hips", "spine": "Chest", "neck": "Neck", "head": "Head",
        **_limbs(("{s}Shoulder", "{s}Elbow", "{s}Wrist"), ("{s}Hip", "{s}Knee", "{s}Ankle"), "{s}Collar"),
        "Toes": "{s}Toe"}),
    _c("side_suffix_dot_underscore", [("Hips", "hips"), ("Spine", "spine"), ("Neck", "neck"), ("Head", "head")],
       [("Clavicle_{s}", "Shoulder"), ("Upper_Arm_{s}", "UpperArm"), ("Forearm_{s}", "LowerArm"), ("Hand_{s}", "Hand")],
       [("Thigh.{s}", "UpperLeg"), ("Shin.{s}", "LowerLeg"), ("Foot.{s}", "Foot"), ("Toe.{s}", "Toes")],
       ("L", "R"),
       {"hips": "Hips", "spine": "Spine", "neck": "Neck", "head": "Head",
        **_limbs(("Upper_Arm_{s}", "Forearm_{s}", "Hand_{s}"), ("Thigh.{s}", "Shin.{s}", "Foot.{s}"), "Clavicle_{s}"),
        "Toes": "Toe.{s}"}),
    _c("side_prefix_underscore", [("Hips", "hips"), ("Spine", "spine"), ("Neck", "neck"), ("Head", "head")],
       [("{s}_Clavicle", "Shoulder"), ("{s}_UpperArm", "UpperArm"), ("{s}_LowerArm", "LowerArm"), ("{s}_Hand", "Hand")],
       [("{s}_UpperLeg", "UpperLeg"), ("{s}_LowerLeg", "LowerLeg"), ("{s}_Foot", "Foot"), ("{s}_Toe", "Toes")],
       ("L", "R"),
       {"hips": "Hips", "spine": "Spine", "neck": "Neck", "head": "Head",
        **_limbs(("{s}_UpperArm", "{s}_LowerArm", "{s}_Hand"), ("{s}_UpperLeg", "{s}_LowerLeg", "{s}_Foot"),
                 "{s}_Clavicle"),
        "Toes": "{s}_Toe"}),
]
#: Joints named by number only: recognised by the tree's shape.
NUMBERED = _c("numbers", [("0", "hips"), ("1", "spine"), ("2", "chest"), ("3", "neck"), ("4", "head"),
                          ("5", "headTop")],
              [("{s}0", "Shoulder"), ("{s}1", "UpperArm"), ("{s}2", "LowerArm"), ("{s}3", "Hand"), ("{s}4", "Finger")],
              [("{s}5", "UpperLeg"), ("{s}6", "LowerLeg"), ("{s}7", "Foot"), ("{s}8", "Toes")],
              ("1", "2"),
              {"hips": "0", "spine": "1", "neck": "3", "head": "4",
               **_limbs(("{s}1", "{s}2", "{s}3"), ("{s}5", "{s}6", "{s}7"), "{s}0"), "Toes": "{s}8"})


def _place(part: str, side: int, n_trunk: int, a_pose: bool, body: dict | None = None) -> np.ndarray:
    """A part's rest position (y up, left +x): ``side`` +1 left, -1 right, 0 the trunk."""
    if part.startswith("trunk"):
        k = int(part[5:])
        return np.array([0.0, 100.0 + (152.0 - 100.0) * (k + 1) / (n_trunk + 1), 0.0])
    if part == "Floor":
        return np.zeros(3)
    p = np.array({**BODY, **(body or {})}[part], dtype=float)
    if a_pose and part in ("LowerArm", "Hand", "Finger"):  # the arm 45 degrees down from the shoulder joint
        d = p - np.array(BODY["UpperArm"])
        p = np.array(BODY["UpperArm"]) + np.linalg.norm(d) * np.array([np.sqrt(0.5), -np.sqrt(0.5), 0.0])
    return p * np.array([side if side else 1.0, 1.0, 1.0])


@dataclass(frozen=True)
class TestRig:
    """A generated rig, its clip (one frame of rest), and what recognition should find (bone -> joint)."""

    rig: Rig
    clip: BvhClip
    expect: dict


def build(conv: Convention, a_pose: bool = False, up: str = "y", body: dict | None = None,
          motion: np.ndarray | None = None) -> TestRig:
    """``conv``'s rig in T- or A-pose, ``up`` ``"y"`` or ``"z"``; ``body`` overrides :data:`BODY` places,
    ``motion`` (n_frames, n_channels) the clip's frames (default one frame at rest)."""
    names, parents, pos = [], [], []
    n_trunk = len(conv.trunk)

    def add(name, parent, p):
        names.append(name)
        parents.append(parent)
        pos.append(p)
        return len(names) - 1

    def place(part, side):
        kind, _, base = part.partition(":")
        if kind in ("at", "twist"):
            return _place(base, side, n_trunk, a_pose, body)
        if kind == "mid":
            nxt = {"UpperArm": "LowerArm", "LowerArm": "Hand", "UpperLeg": "LowerLeg", "LowerLeg": "Foot",
                   "Shoulder": "UpperArm", "neck": "head"}[base]
            return 0.5 * (_place(base, side, n_trunk, a_pose, body) + _place(nxt, side, n_trunk, a_pose, body))
        return _place(part, side, n_trunk, a_pose, body)

    trunk_index = {}
    last = -1
    for name, part in conv.trunk:
        if part.startswith("at:") and part != "at:Floor" and last >= 0:
            trunk_index[part] = add(name, last, place(part, 0))  # a helper beside the trunk, not on it
            continue
        last = add(name, last, place(part, 0))
        trunk_index[part] = last
    top = next(trunk_index[k] for k in ("upperChest", "trunk4", "chest", "spine") if k in trunk_index)
    hips = trunk_index["hips"]
    for side, word in ((1, conv.sides[0]), (-1, conv.sides[1])):
        for rows, parent in ((conv.arm, top), (conv.leg, hips)):
            for name, part in rows:
                name = name.format(s=word)
                if part.startswith("twist:"):
                    j = add(name, parent, place(part, side))
                    add(name + "_end", j, place(part, side) + [0.0, 3.0, 0.0])
                    continue
                parent = add(name, parent, place(part, side))
    expect = {}
    for part, name in conv.expect.items():
        if part[0].isupper():
            for s, word in (("left", conv.sides[0]), ("right", conv.sides[1])):
                expect[s + part] = name.format(s=word)
        else:
            expect[part] = name
    P = np.array(pos)
    if up == "z":
        P = P[:, [0, 2, 1]] * [1.0, -1.0, 1.0]
    rig = depth_first(Rig(tuple(names), tuple(parents), P))
    return TestRig(rig, clip_of(rig, motion), expect)


def depth_first(rig: Rig) -> Rig:
    """``rig`` with its joints in depth-first order (as BVH writes them)."""
    order: list[int] = []

    def visit(j):
        order.append(j)
        for c in rig.children[j]:
            visit(c)

    for j, p in enumerate(rig.parents):
        if p < 0:
            visit(j)
    new = {old: k for k, old in enumerate(order)}
    return Rig(tuple(rig.names[j] for j in order), tuple(new[rig.parents[j]] if rig.parents[j] >= 0 else -1
                                                       for j in order), rig.rest_positions[order])


ROOT = ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
ZYX = ("Zrotation", "Yrotation", "Xrotation")


def bvh_name(name: str) -> str:
    """``name`` as a BVH file can hold it (one token: spaces become underscores)."""
    return name.replace(" ", "_")


def clip_of(rig: Rig, motion: np.ndarray | None = None) -> BvhClip:
    """``rig`` as a BVH clip (leaves as End Sites named ``<parent>_end`` when so named), ``motion`` default rest."""
    P = rig.rest_positions
    joints = []
    for j, (name, p) in enumerate(zip(rig.names, rig.parents)):
        leaf = not rig.children[j] and name.endswith("_end")
        offset = P[j] - P[p] if p >= 0 else P[j]
        joints.append(BvhJoint(bvh_name(name), p, offset, () if leaf else (ROOT if p < 0 else ZYX), is_end_site=leaf))
    n = sum(len(j.channels) for j in joints)
    if motion is None or motion.shape[1] != n:  # rest, or waves of the given frame count
        motion = rest_motion(n, P[0]) if motion is None else wave_motion(len(motion), n, P[0])
    return BvhClip(tuple(joints), 1 / 30, motion)


def rest_motion(n_channels: int, root: np.ndarray) -> np.ndarray:
    """One frame at rest: the root at ``root``, no rotation."""
    m = np.zeros((1, n_channels))
    m[0, :3] = root
    return m


def wave_motion(n_frames: int, n_channels: int, root: np.ndarray, amplitude: float = 25.0) -> np.ndarray:
    """Every rotation channel swinging by up to ``amplitude`` degrees on its own phase, the root walking."""
    t = np.arange(n_frames)[:, None] / 30.0
    m = amplitude * np.sin(2.0 * np.pi * 0.7 * t + np.arange(n_channels) * 1.3)
    m[:, :3] = root + np.array([1.0, 0.0, 2.0]) * 30.0 * t
    return m
