"""Bones from the tree's shape, where names fail (numbered joints, another language).

The hips are the joint where two long, equally long branches leave (the
legs) beside a third (the spine) that itself splits into two long, equally
long branches (the arms, at the chest) beside the neck and head. Up points
from the hips to the chest. Along each limb's main chain (at each joint the
child with the longest reach), the two longest consecutive bones are the
upper and lower arm (thigh and shin); the joint after them is the hand
(foot), the one after that the toes, the one before the clavicle. The spine
is the path from the hips to the chest; on the chain above the chest the
head is the joint before the top one. Left is told from facing: the toes
point forward (else the usual facing of y-up and z-up rigs is assumed) and
left is up x forward; joints named with a side override that guess.
"""

from __future__ import annotations

import numpy as np

from gsik.humanoid.chains import Found, spine_bones
from gsik.humanoid.names import Label
from gsik.humanoid.rig import Rig

#: Confidence of a bone found by structure: facing told by the toes, or assumed.
BY_SHAPE, BY_SHAPE_GUESSED_SIDE = 0.6, 0.4
#: Two branches are a pair when their reaches differ by less than this fraction.
PAIR_TOLERANCE = 0.15
#: Least reach of a leg (arm) as a fraction of the rig's largest extent.
MIN_LEG, MIN_ARM = 0.25, 0.15


class _Shape:
    """Reaches and branches of a rig's tree (lengths from the rest pose)."""

    def __init__(self, rig: Rig):
        self.rig = rig
        p = rig.rest_positions
        self.length = np.array([np.linalg.norm(p[j] - p[q]) if q >= 0 else 0.0 for j, q in enumerate(rig.parents)])
        reach = np.zeros(rig.n_joints)  # longest path from each joint down to a leaf
        for j in reversed(range(rig.n_joints)):
            reach[j] = max((reach[c] + self.length[c] for c in rig.children[j]), default=0.0)
        self.reach = reach
        self.extent = float(np.ptp(p, axis=0).max()) if rig.n_joints else 0.0

    def branches(self, j: int) -> list[int]:
        """``j``'s children, a child at ``j``'s place with several children replaced by those (recursively)."""
        out = []
        for c in self.rig.children[j]:
            if self.length[c] <= 1e-6 * max(self.extent, 1e-12) and len(self.rig.children[c]) > 1:
                out += self.branches(c)
            else:
                out.append(c)
        return out

    def branch_reach(self, c: int) -> float:
        return float(self.reach[c] + self.length[c])

    def size(self, c: int) -> int:
        """Joints in ``c``'s subtree."""
        return 1 + sum(self.size(d) for d in self.rig.children[c])

    def pair(self, j: int, least: float) -> tuple[int, int, list[int]] | None:
        """The most alike two branches of ``j`` (as many joints, reaches within :data:`PAIR_TOLERANCE`, at least
        ``least``) and the other branches; None if there are none."""
        bs = self.branches(j)
        pairs = [(abs(self.branch_reach(a) - self.branch_reach(b)) / self.branch_reach(a), a, b)
                 for i, a in enumerate(bs) for b in bs[i + 1:]
                 if min(self.branch_reach(a), self.branch_reach(b)) >= least and self.size(a) == self.size(b)]
        pairs = [p for p in pairs if p[0] <= PAIR_TOLERANCE]
        if not pairs:
            return None
        _, a, b = min(pairs, key=lambda p: (p[0], -self.branch_reach(p[1])))
        return a, b, [c for c in bs if c not in (a, b)]

    def main_chain(self, c: int) -> list[int]:
        """From ``c`` down, at each joint the child that reaches farthest."""
        out = [c]
        while self.rig.children[out[-1]]:
            out.append(max(self.rig.children[out[-1]], key=self.branch_reach))
        return out


def _hips_and_chest(shape: _Shape) -> tuple[int, tuple[int, int], int, tuple[int, int], list[int]] | None:
    """``(hips, legs, chest, arms, head branches)``: the joint with a pair of legs whose other branch holds a joint
    with a pair of arms beside the head."""
    rig, best = shape.rig, None
    for h in range(rig.n_joints):
        legs = shape.pair(h, MIN_LEG * shape.extent)
        if legs is None or not legs[2]:
            continue
        for up in legs[2]:
            for c in rig.subtree(up):
                arms = shape.pair(c, MIN_ARM * shape.extent)
                if arms is not None and arms[2] and c not in (legs[0], legs[1]):
                    found = (h, legs[:2], c, arms[:2], arms[2])
                    if best is None or shape.branch_reach(legs[0]) > shape.branch_reach(best[1][0]):
                        best = found
                    break
    return best


def _limb(shape: _Shape, branch: int, start: int) -> dict[str, int]:
    """Along ``branch``'s main chain: the joints of the two longest consecutive bones and what follows and precedes.

    Keys ``"upper"``, ``"lower"``, ``"end"`` (hand, foot), optional ``"tip"`` (toes) and ``"root"`` (clavicle);
    ``start`` is the joint the limb leaves (its first bone starts there)."""
    chain = [start] + shape.main_chain(branch)
    seg = [shape.length[j] for j in chain[1:]]  # seg[k]: chain[k] -> chain[k + 1]
    if len(seg) < 2:
        return {}
    k = max(range(1, len(seg)), key=lambda i: seg[i - 1] + seg[i]) - 1
    if k == 0:  # the limb's first bone leaves the trunk: no joint of its own starts it
        return {}
    out = {"upper": chain[k], "lower": chain[k + 1], "end": chain[k + 2]}
    if k + 3 < len(chain):
        out["tip"] = chain[k + 3]
    if k >= 2:
        out["root"] = chain[k - 1]
    return out


def _facing(rig: Rig, up: np.ndarray, feet: list[dict[str, int]]) -> tuple[np.ndarray, bool]:
    """The rig's forward direction and whether its toes told it (else y up faces +z, z up faces -y)."""
    p = rig.rest_positions
    toes = sum((p[f["tip"]] - p[f["end"]] for f in feet if "tip" in f), np.zeros(3))
    toes -= np.dot(toes, up) * up
    if np.linalg.norm(toes) > 1e-9:
        return toes / np.linalg.norm(toes), True
    k = int(np.argmax(np.abs(up)))
    fallback = {1: [0.0, 0.0, 1.0], 2: [0.0, -1.0, 0.0]}.get(k, [0.0, 1.0, 0.0])
    return np.array(fallback), False


def _sides(rig: Rig, labels: list[Label], pair: tuple[int, int], left: np.ndarray) -> tuple[int, int] | None:
    """``pair`` ordered (left, right): by a side its joints are named with, else by ``left``; None if unsure."""
    for a, b in (pair, pair[::-1]):
        named = {labels[j].side for j in rig.subtree(a)}
        if "left" in named and "right" not in named:
            return a, b
    p = rig.rest_positions
    d = float(np.dot(p[rig.subtree(pair[0])].mean(axis=0) - p[rig.subtree(pair[1])].mean(axis=0), left))
    return None if abs(d) < 1e-9 * max(float(np.abs(p).max()), 1e-300) else (pair if d > 0 else pair[::-1])


def _ends_at_top(shape: _Shape, labels: list[Label], chain: list[int]) -> bool:
    """Whether the chain above the chest ends in a head-top joint (an End Site, ``HeadTop``, or a last bone at
    least 1.5 times as long as the others on average: the head is long next to the neck's bones)."""
    if len(chain) < 2:
        return False
    if labels[chain[-1]].helper == "end" or labels[chain[-1]].kind == "headTop":
        return True
    before = [shape.length[j] for j in chain[1:-1]]
    return len(chain) >= 3 and shape.length[chain[-1]] >= 1.5 * float(np.mean(before))


def _head(shape: _Shape, labels: list[Label], chain: list[int]) -> int:
    """The head on the main chain above the chest: the first joint where it branches (eyes, jaw), else the top
    joint, or the one below it when the top is the head's End Site (:func:`_ends_at_top`)."""
    for j in chain:
        if len(shape.branches(j)) >= 2:
            return j
    while len(chain) > 1 and shape.length[chain[-1]] <= 1e-6 * shape.extent:
        chain = chain[:-1]  # joints at the head's place
    return chain[-2] if _ends_at_top(shape, labels, chain) else chain[-1]


def bones_by_structure(rig: Rig, labels: list[Label], found: dict[str, Found]) -> dict[str, Found]:
    """Canonical bone -> joint from the rig's shape (see the module docstring); ``{}`` when it reads no humanoid.

    ``found``: bones already found by name; their joints are not given to another bone.
    """
    shape = _Shape(rig)
    parts = _hips_and_chest(shape)
    if parts is None:
        return {}
    hips, legs, chest, arms, heads = parts
    while len(rig.children[hips]) == 1 and shape.length[rig.children[hips][0]] <= 1e-6 * shape.extent:
        hips = rig.children[hips][0]  # a root at the hips' place above them (Bip01, CC_Base_BoneRoot)
    p = rig.rest_positions
    up = p[chest] - p[hips]
    if np.linalg.norm(up) < 1e-12:
        return {}
    up = up / np.linalg.norm(up)
    leg_parts = [_limb(shape, b, hips) for b in legs]
    forward, sure = _facing(rig, up, leg_parts)
    left = np.cross(up, forward)
    conf = BY_SHAPE if sure else BY_SHAPE_GUESSED_SIDE
    out: dict[str, Found] = {"hips": Found(hips, BY_SHAPE)}
    for pair, names, start in ((legs, ("UpperLeg", "LowerLeg", "Foot", "Toes", None), hips),
                               (arms, ("UpperArm", "LowerArm", "Hand", None, "Shoulder"), chest)):
        ordered = _sides(rig, labels, pair, left)
        if ordered is None:
            continue
        for side, branch in zip(("left", "right"), ordered):
            limb = _limb(shape, branch, start)
            for key, bone in zip(("upper", "lower", "end", "tip", "root"), names):
                if bone and key in limb:
                    out[side + bone] = Found(limb[key], conf)
    spine = rig.path(hips, chest) + [chest]
    for bone, k in spine_bones(len(spine)).items():
        out[bone] = Found(spine[k], BY_SHAPE)
    head_chain = shape.main_chain(max(heads, key=lambda b: float(np.dot(p[b] - p[chest], up)) + shape.reach[b]))
    head = _head(shape, labels, head_chain)
    out["head"] = Found(head, BY_SHAPE)
    if head != head_chain[0]:
        out["neck"] = Found(head_chain[0], BY_SHAPE)
    used = {f.joint for f in found.values()}
    return {b: f for b, f in out.items() if b not in found and f.joint not in used}


__all__ = ["bones_by_structure"]
