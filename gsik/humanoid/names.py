"""What a joint's name says: its side and which part of a humanoid it is (one matcher for every convention).

A name is cut into lower-case words: namespace (``mixamorig:``), rig prefix
(``CC_Base_``, ``Bip01 ``, ``DEF-``, ``ORG-``, ``MCH-``, HumanIK's ``Character1_``) and separators
dropped, camel case split (``LeftUpLeg`` -> ``left up leg``, Daz's ``lShldr``
-> ``l shldr``), digits dropped. A side is a word ``left``/``l`` or
``right``/``r`` anywhere (``L_Thigh``, ``thigh_l``, ``upper_arm.L``,
``Bip01 L Thigh``) or a leading ``l``/``r`` glued to a part (CMU ASF's
``lfemur``). The other words, joined, name the part through :data:`PART_WORDS`
(``upleg``, ``upperleg``, ``thigh`` and ``femur`` are all an upper leg).

Words that mark a joint as not being the part: ``twist``, ``roll`` and
``share`` (a helper beside the joint; used only where nothing else has the
part, as Character Creator's ``NeckTwist01``, its only neck), finger and face
words, and ``end``/``nub``/``site`` (an End Site). Some parts are ambiguous
by name alone and are settled by the chain (:mod:`gsik.humanoid.chains`):
``shoulder`` is a clavicle before an arm (Mixamo) but the arm after a collar
(``LeftCollar``/``LeftShoulder`` mocap rigs, Daz's ``lCollar``/``lShldr``);
a sided ``hip`` is the thigh only where no thigh follows it (ASF's
``lhipjoint`` is a helper).
"""

from __future__ import annotations

import re
from typing import NamedTuple

#: Rig prefixes dropped before reading a name (after its ``namespace:``).
_PREFIX = re.compile(r"^(cc_base_|bip0*1(?=[ _]|$)[ _]?|def-|org-|mch-|mixamorig\d*[_:]?|character\d*_)",
                     re.IGNORECASE)
_WORD = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+")

#: Joined words -> part kind. ``shoulder`` and ``sidehip`` are settled by the chain; spine words all read ``spine``.
PART_WORDS = {
    **dict.fromkeys(("hips", "pelvis", "hip", "root"), "hips"),
    **dict.fromkeys(("spine", "abdomen", "abdomenlower", "abdomenupper", "waist", "lowerback", "upperback",
                     "chest", "chestlower", "chestupper", "upperchest", "thorax", "torso", "spinelower",
                     "spineupper", "back"), "spine"),
    **dict.fromkeys(("neck", "lowerneck", "upperneck", "necklower", "neckupper"), "neck"),
    **dict.fromkeys(("head", "atlas"), "head"),
    **dict.fromkeys(("headtop",), "headTop"),
    **dict.fromkeys(("collar", "clavicle", "collarbone"), "collar"),
    **dict.fromkeys(("shoulder", "shldr"), "shoulder"),
    **dict.fromkeys(("arm", "upperarm", "uparm", "humerus"), "upperArm"),
    **dict.fromkeys(("forearm", "lowerarm", "radius", "elbow", "ulna", "lowarm"), "lowerArm"),
    **dict.fromkeys(("hand", "wrist"), "hand"),
    **dict.fromkeys(("upleg", "thigh", "upperleg", "femur"), "upperLeg"),
    **dict.fromkeys(("leg", "shin", "knee", "calf", "lowerleg", "tibia", "shank", "lowleg"), "lowerLeg"),
    **dict.fromkeys(("foot", "ankle"), "foot"),
    **dict.fromkeys(("toe", "toes", "toebase", "ball", "forefoot"), "toes"),
}
#: Sided words that mean another part than unsided (a side's hip or pelvis is a helper before the thigh).
SIDED_WORDS = {"hip": "sidehip", "hips": "sidehip", "pelvis": "sidehip", "hipjoint": "sidehip"}
#: Kinds that are helpers beside the joint (their reason in ``Recognition.ignored``).
_HELPER_WORDS = {"twist": "twist", "roll": "roll", "share": "share", "sharebone": "share"}
_END_WORDS = {"end", "nub", "site", "tip"}
_FINGER_WORDS = {"thumb", "index", "middle", "mid", "ring", "pinky", "little", "finger", "fingers", "carpal",
                 "metacarpal", "palm", "big"}
_FACE_WORDS = {"eye", "eyes", "jaw", "tongue", "teeth", "facial", "face", "brow", "lip", "lips", "ear", "nose",
               "cheek", "lid", "eyelid", "upperjaw", "eyeball"}
_NOISE_WORDS = {"bone", "jnt", "bn", "bend"}
_SIDE_WORDS = {"left": "left", "l": "left", "right": "right", "r": "right"}


class Label(NamedTuple):
    """What a name says about its joint.

    Attributes:
        side: ``"left"``, ``"right"`` or ``None``.
        kind: The part (a :data:`PART_WORDS` value, ``"sidehip"``) or ``None`` when the name names none.
        helper: Why the joint is not the part itself though named for it (``"twist"``, ``"roll"``,
            ``"share"``, ``"end"``), or why it is no body part (``"finger"``, ``"face"``); ``None``.
    """

    side: str | None
    kind: str | None
    helper: str | None


def words(name: str) -> list[str]:
    """``name``'s lower-case words, namespace and rig prefix dropped (``"CC_Base_L_Thigh"`` -> ``["l", "thigh"]``)."""
    base = re.split(r"[:|]", name)[-1]
    while True:
        cut = _PREFIX.sub("", base)
        if cut == base:
            break
        base = cut
    return [w.lower() for part in re.split(r"[\s_\-.]+", base) for w in _WORD.findall(part)]


def _side(ws: list[str]) -> tuple[str | None, list[str]]:
    """The side the words name, and the words without it."""
    for i, w in enumerate(ws):
        if w in _SIDE_WORDS:
            return _SIDE_WORDS[w], ws[:i] + ws[i + 1:]
    if ws and "".join(ws) not in PART_WORDS:  # a leading l/r glued to a part: lfemur, rhand, lhipjoint
        for short in ("left", "right", "l", "r"):
            rest = ws[0][len(short):]
            if ws[0].startswith(short) and (rest in PART_WORDS or rest in SIDED_WORDS or rest in _FINGER_WORDS):
                return _SIDE_WORDS[short], [rest] + ws[1:]
    return None, ws


def label(name: str) -> Label:
    """What ``name`` says: side, part kind and helper reason (see the module docstring)."""
    side, ws = _side(words(name))
    helper = next((_HELPER_WORDS[w] for w in ws if w in _HELPER_WORDS), None)
    if any(w in _END_WORDS for w in ws):
        helper = "end"
    if any(w in _FINGER_WORDS for w in ws):
        return Label(side, None, "finger")
    if any(w in _FACE_WORDS for w in ws):
        return Label(side, None, "face")
    core = "".join(w for w in ws if not w.isdigit() and w not in _HELPER_WORDS and w not in _END_WORDS
                   and w not in _NOISE_WORDS)
    kind = SIDED_WORDS.get(core) if side and core in SIDED_WORDS else PART_WORDS.get(core)
    if helper == "end":
        return Label(side, "headTop" if kind in ("head", "headTop") else None, "end")
    return Label(side, kind, helper)


__all__ = ["Label", "label", "words", "PART_WORDS"]
