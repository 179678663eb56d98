"""Bones from names, settled by the chain: each limb read from its end up, the trunk from the hips to the head.

Of several joints named for one part, the one nearest the root wins
(``Spine`` before ``Spine1``, ASF's ``lwrist`` before ``lhand``, Rigify's
``DEF-thigh.L`` before ``DEF-thigh.L.001``); a twist, roll or share joint
counts only where no other joint has the part (Character Creator's
``NeckTwist01``). Each bone must lie on its chain: the lower arm above the
hand, the upper arm above the lower arm, and so on.
"""

from __future__ import annotations

from typing import NamedTuple

from gsik.humanoid.names import Label
from gsik.humanoid.rig import Rig

#: Confidence of a bone its name gives directly, and of one whose name needed the chain to settle.
NAMED, SETTLED = 0.95, 0.85


class Found(NamedTuple):
    """One bone found: the joint index and how sure the finding is (0..1)."""

    joint: int
    confidence: float


class _Candidates:
    """The joints of each (kind, side), main joints before twist/roll/share ones."""

    def __init__(self, rig: Rig, labels: list[Label]):
        self.rig, self.labels = rig, labels

    def of(self, kind: str, side: str | None, below: int | None = None, above: int | None = None) -> list[int]:
        """Joints labelled ``kind`` on ``side``, descendants of ``below`` and ancestors of ``above`` when given,
        main ones first, then by depth (nearest the root first)."""
        rig = self.rig
        out = [j for j, lab in enumerate(self.labels) if lab.kind == kind and lab.side == side
               and lab.helper not in ("end",)
               and (below is None or rig.is_ancestor(below, j)) and (above is None or rig.is_ancestor(j, above))]
        return sorted(out, key=lambda j: (self.labels[j].helper is not None, rig.depth[j], j))

    def first(self, *args, **kwargs) -> int | None:
        c = self.of(*args, **kwargs)
        return c[0] if c else None


def _sure(labels: list[Label], j: int, settled: bool = False) -> Found:
    return Found(j, SETTLED if settled or labels[j].helper else NAMED)


def _leg(c: _Candidates, side: str, out: dict[str, Found]) -> None:
    """One leg: foot, then the lower leg above it, the upper leg above that (a sided hip where no thigh), toes."""
    labels, s = c.labels, side
    foot = c.first("foot", s)
    lower = c.first("lowerLeg", s, above=foot) if foot is not None else c.first("lowerLeg", s)
    below = lower if lower is not None else foot  # without a named shin, the thigh is sought above the foot
    if below is not None:
        upper = c.first("upperLeg", s, above=below)
        hip = c.of("sidehip", s, above=below)
        if upper is None and hip and lower is not None:
            out[f"{s}UpperLeg"] = Found(max(hip, key=lambda j: c.rig.depth[j]), SETTLED)
        elif upper is not None:
            out[f"{s}UpperLeg"] = _sure(labels, upper)
    if lower is not None:
        out[f"{s}LowerLeg"] = _sure(labels, lower)
    if foot is not None:
        out[f"{s}Foot"] = _sure(labels, foot)
        toes = c.first("toes", s, below=foot)
        if toes is not None:
            out[f"{s}Toes"] = _sure(labels, toes)


def _arm(c: _Candidates, side: str, out: dict[str, Found]) -> None:
    """One arm: hand, the lower arm above it, the upper arm above that, the clavicle above that.

    A ``shoulder`` is the upper arm where no joint is named for the arm (``LeftCollar``/``LeftShoulder``,
    Daz's ``lCollar``/``lShldr``, the biped), else the clavicle where no collar is named (Mixamo), else a helper.
    """
    labels, s = c.labels, side
    hand = c.first("hand", s)
    lower = c.first("lowerArm", s, above=hand) if hand is not None else c.first("lowerArm", s)
    if hand is not None:
        out[f"{s}Hand"] = _sure(labels, hand)
    if lower is None:
        return
    out[f"{s}LowerArm"] = _sure(labels, lower)
    upper, settled = c.first("upperArm", s, above=lower), False
    if upper is None:
        shoulders = c.of("shoulder", s, above=lower)
        upper, settled = (max(shoulders, key=lambda j: (labels[j].helper is None, c.rig.depth[j]))
                          if shoulders else None), True
    if upper is None:
        return
    out[f"{s}UpperArm"] = _sure(labels, upper, settled)
    collar = c.first("collar", s, above=upper)
    if collar is None:
        collar = c.first("shoulder", s, above=upper)
    if collar is not None:
        out[f"{s}Shoulder"] = _sure(labels, collar, labels[collar].kind == "shoulder")


def _trunk(c: _Candidates, out: dict[str, Found]) -> None:
    """Head, neck above it, hips (the deepest hips-named joint above both thighs and the head), spine between."""
    rig, labels = c.rig, c.labels
    head = c.first("head", None)
    neck = c.first("neck", None, above=head) if head is not None else None
    ends = [out[b].joint for b in ("leftUpperLeg", "rightUpperLeg") if b in out] + [
        j for j in (head,) if j is not None]
    hips = [j for j in c.of("hips", None) if all(rig.is_ancestor(j, t) for t in ends)]
    if hips:
        out["hips"] = _sure(labels, max(hips, key=lambda j: (labels[j].helper is None, rig.depth[j])))
    elif len(ends) == 3:  # no joint named for the hips (Rigify's DEF-spine): where the thighs and the head meet
        common = set(rig.ancestors(ends[0])).intersection(*(rig.ancestors(e) for e in ends[1:]))
        out["hips"] = Found(max(common, key=lambda j: rig.depth[j]), SETTLED)
    if head is None:
        return
    out["head"] = _sure(labels, head)
    if neck is not None:
        out["neck"] = _sure(labels, neck)
    if "hips" not in out:
        return
    top = neck if neck is not None else head
    spine = [j for j in rig.path(out["hips"].joint, top) if labels[j].kind == "spine"]
    for bone, k in spine_bones(len(spine)).items():
        out[bone] = Found(spine[k], NAMED if bone == "spine" else SETTLED)


def spine_bones(n: int) -> dict[str, int]:
    """Which of ``n`` spine joints (hips up) are spine, chest and upperChest: first, middle, last."""
    out = {"spine": 0} if n else {}
    if n >= 2:
        out["chest"] = n // 2 if n >= 3 else 1
    if n >= 3:
        out["upperChest"] = n - 1
    return out


def bones_by_name(rig: Rig, labels: list[Label]) -> dict[str, Found]:
    """Canonical bone -> the joint its name (settled by its chain) gives, for every bone names give."""
    c = _Candidates(rig, labels)
    out: dict[str, Found] = {}
    for side in ("left", "right"):
        _leg(c, side, out)
        _arm(c, side, out)
    _trunk(c, out)
    return out


__all__ = ["Found", "bones_by_name", "spine_bones", "NAMED", "SETTLED"]
