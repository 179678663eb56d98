"""A skeleton as plain data for recognition (:class:`Rig`), made from a BVH clip or a gsik skeleton."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from gsik.errors import HumanoidError, show_value


@dataclass(frozen=True, eq=False)
class Rig:
    """Any skeleton, as recognition reads it.

    Attributes:
        names: (n_joints,) joint names, parents before children.
        parents: (n_joints,) parent index per joint, -1 for a root.
        rest_positions: (n_joints, 3) world rest positions, any unit (read-only).
    """

    names: tuple[str, ...]
    parents: tuple[int, ...]
    rest_positions: np.ndarray

    def __post_init__(self) -> None:
        names, parents = tuple(str(n) for n in self.names), tuple(int(p) for p in self.parents)
        rest = np.array(self.rest_positions, dtype=float)
        if rest.shape != (len(names), 3) or not np.isfinite(rest).all():
            raise HumanoidError(f"rig rest_positions: expected finite ({len(names)}, 3), got shape {rest.shape}")
        if len(parents) != len(names):
            raise HumanoidError(f"rig: {len(names)} names but {len(parents)} parents")
        for j, p in enumerate(parents):
            if not -1 <= p < j:
                raise HumanoidError(f"rig joint {show_value(names[j])}: parent {p} is not an earlier joint")
        if len(set(names)) != len(names):
            raise HumanoidError("rig: joint names repeat: " + show_value(sorted({n for n in names
                                                                               if names.count(n) > 1})))
        rest.flags.writeable = False
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "rest_positions", rest)

    @property
    def n_joints(self) -> int:
        return len(self.names)

    @cached_property
    def children(self) -> tuple[tuple[int, ...], ...]:
        """Each joint's children, in order."""
        out: list[list[int]] = [[] for _ in self.names]
        for j, p in enumerate(self.parents):
            if p >= 0:
                out[p].append(j)
        return tuple(tuple(c) for c in out)

    @cached_property
    def depth(self) -> np.ndarray:
        """(n_joints,) number of ancestors of each joint."""
        d = np.zeros(self.n_joints, dtype=int)
        for j, p in enumerate(self.parents):
            d[j] = d[p] + 1 if p >= 0 else 0
        return d

    def ancestors(self, j: int) -> list[int]:
        """``j``'s ancestors, nearest first."""
        out = []
        while self.parents[j] >= 0:
            j = self.parents[j]
            out.append(j)
        return out

    def subtree(self, j: int) -> list[int]:
        """``j`` and its descendants, in order."""
        out = [j]
        for c in self.children[j]:
            out += self.subtree(c)
        return out

    def is_ancestor(self, a: int, b: int) -> bool:
        """Whether ``a`` is a strict ancestor of ``b``."""
        return a in self.ancestors(b)

    def path(self, a: int, b: int) -> list[int]:
        """The joints strictly between ancestor ``a`` and its descendant ``b``, from ``a`` down."""
        up = self.ancestors(b)
        return list(reversed(up[:up.index(a)])) if a in up else []


def rig_from_clip(clip) -> Rig:
    """A BVH clip's rig (:class:`gsik.io.bvh.BvhClip`): its joints and End Sites, rest = OFFSETs summed down."""
    rest = np.zeros((clip.n_joints, 3))
    for j, joint in enumerate(clip.joints):
        if joint.parent >= 0:
            rest[j] = rest[joint.parent] + joint.offset
    return Rig(tuple(j.name for j in clip.joints), tuple(j.parent for j in clip.joints), rest)


def rig_from_skeleton(skeleton) -> Rig:
    """A gsik skeleton's rig: its joints and sites (each at its frame) become joints, rest = its rest pose."""
    from gsik.kinematics import world_frames

    frame_of = {**dict(zip(skeleton.joint_names, skeleton.joint_frame)),
                **dict(zip(skeleton.site_names, skeleton.site_frame))}
    names = sorted(frame_of, key=lambda n: (int(frame_of[n]), n not in skeleton.joint_names))
    index = {n: k for k, n in enumerate(names)}
    at_frame: dict[int, str] = {}
    for n in names:
        at_frame.setdefault(int(frame_of[n]), n)
    parents = []
    for n in names:
        f = int(frame_of[n])
        if at_frame[f] != n:  # a site on a joint's own frame hangs off that joint
            parents.append(index[at_frame[f]])
            continue
        f = int(skeleton.frame_parent[f])
        while f >= 0 and f not in at_frame:
            f = int(skeleton.frame_parent[f])
        parents.append(index[at_frame[f]] if f >= 0 else -1)
    positions = world_frames(skeleton, skeleton.rest)[1]
    return Rig(tuple(names), tuple(parents), positions[[int(frame_of[n]) for n in names]])


__all__ = ["Rig", "rig_from_clip", "rig_from_skeleton"]
