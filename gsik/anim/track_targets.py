"""What a track follows: the target names and their clip frames, per-target options, the clip's poses per frame."""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from gsik import validate
from gsik.anim.motion import Motion
from gsik.errors import SkeletonError, SolverError, choices
from gsik.rotations import transform
from gsik.skeleton import Skeleton
from gsik.targets import Target

#: Priority of targets on joints or sites that are not effectors (knees under the end sites).
JOINT_PRIORITY = 1


def clip_frame(clip_skeleton: Skeleton, name: str, what: str) -> int:
    try:
        return clip_skeleton.frame_of(name)
    except SkeletonError:
        raise SolverError(f"the clip's skeleton {clip_skeleton.name!r} has no joint or site {name!r} for {what}; "
                          f"joints: {choices(clip_skeleton.joint_names)}; sites: {choices(clip_skeleton.site_names)}"
                          ) from None


def effector_pairs(skeleton: Skeleton, clip_sk: Skeleton, effectors, root: str) -> dict[str, str]:
    """``{joint or site of skeleton: clip joint or site it follows}``, the root left out (it is pinned)."""
    available = [n for n in skeleton.effector_sites if n != root]
    pairs = _requested_pairs(clip_sk, effectors, available)
    pairs.pop(root, None)  # pinned where the clip has it: tracked exactly
    allowed = set(skeleton.joint_names) | set(skeleton.site_names)
    for name in pairs:
        if name not in allowed:
            others = [n for n in [*skeleton.joint_names, *skeleton.site_names] if n not in available and n != root]
            raise SolverError(f"{name!r} is not an effector of skeleton {skeleton.name!r}; "
                              f"effectors: {choices(available)}; other joints and sites: {choices(others)}")
    return pairs


def _requested_pairs(clip_sk: Skeleton, effectors, available: list[str]) -> dict[str, str]:
    """The pairs as asked: a mapping, names (or one name) followed by the same name, or every shared effector."""
    if isinstance(effectors, Mapping):
        return dict(effectors)
    if effectors is not None:
        return {n: n for n in ([effectors] if isinstance(effectors, str) else effectors)}
    in_clip = set(clip_sk.site_names) | set(clip_sk.joint_names)
    pairs = {n: n for n in available if n in in_clip}
    if not pairs:
        raise SolverError(f"the clip has none of the skeleton's effectors {choices(available)}; "
                          "name them with effectors={effector: clip name}")
    return pairs


def position_only_flags(names: tuple[str, ...], position_only) -> tuple[bool, ...]:
    """Per target: position only?"""
    if isinstance(position_only, (bool, np.bool_)):
        return (bool(position_only),) * len(names)
    chosen = [position_only] if isinstance(position_only, str) else list(position_only)
    unknown = [n for n in chosen if n not in names]
    if unknown:
        raise SolverError(f"position_only names {unknown[0]!r}, which is not tracked; targets: {choices(names)}")
    return tuple(n in chosen for n in names)


def priority_levels(skeleton: Skeleton, names: tuple[str, ...], priorities) -> tuple[int, ...]:
    """Per target: its level, as asked or by default (effector sites 0, other joints and sites 1)."""
    priorities = dict(priorities or {})
    unknown = [n for n in priorities if n not in names]
    if unknown:
        raise SolverError(f"priorities name {unknown[0]!r}, which is not tracked; targets: {choices(names)}")
    effectors = set(skeleton.effector_sites)
    out = []
    for n in names:
        level = priorities.get(n, 0 if n in effectors else JOINT_PRIORITY)
        validate.whole(level, f"priority of {n!r}", SolverError, 0)
        out.append(int(level))
    return tuple(out)


class TargetPlan(NamedTuple):
    """The targets: names, the clip frame each follows, position only?, priority level."""

    names: tuple[str, ...]
    clip_frames: list[int]
    position_only: tuple[bool, ...]
    priorities: tuple[int, ...]


class ClipTargets(NamedTuple):
    """What the clip asks for, per frame: root pose (F, 4, 4), targets, their positions (F, m, 3) [m] and
    orientations (F, m, 3, 3)."""

    world_from_root: np.ndarray
    targets: list[dict[str, Target]]
    positions: np.ndarray
    rotations: np.ndarray


def clip_targets(motion: Motion, root_in_clip: int, plan: TargetPlan) -> ClipTargets:
    """Targets and root poses from the clip's own forward kinematics."""
    F = motion.n_frames
    W = np.empty((F, 4, 4))
    targets: list[dict[str, Target]] = []
    target_p = np.empty((F, len(plan.names), 3))
    target_R = np.empty((F, len(plan.names), 3, 3))
    for f in range(F):
        R, p = motion.frames(f)
        W[f] = transform(R[root_in_clip], p[root_in_clip])
        target_p[f] = p[plan.clip_frames]
        target_R[f] = R[plan.clip_frames]
        targets.append({n: Target(p[c], None if only else R[c], priority=level)
                        for n, c, only, level in zip(*plan)})
    return ClipTargets(W, targets, target_p, target_R)


def clip_posture(skeleton: Skeleton, motion: Motion) -> np.ndarray:
    """(F, n_dofs) the clip's angles on ``skeleton``, DOFs matched by name (the rest pose where the clip has none)."""
    ref = np.tile(skeleton.rest, (motion.n_frames, 1))
    clip_dofs = motion.skeleton.dof_names
    for d, name in enumerate(skeleton.dof_names):
        if name in clip_dofs:
            ref[:, d] = motion.q[:, motion.skeleton.dof_index(name)]
    return np.clip(ref, skeleton.lower, skeleton.upper)
