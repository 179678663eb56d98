"""Poses as the document keeps them: the root's placement, targets at transforms, the standing pose, checks.

The one place where the studio turns transforms and playback frames into
document targets (:class:`gsik.Target`, the type pose files hold too).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import NamedTuple

import numpy as np

import gsik
from gsik.errors import PoseError, choices
from gsik.io.pose import Pose
from gsik.targets import Target
from gsik.rotations import quaternion_from_matrix


class RootPlacement(NamedTuple):
    """Where the IK root stands in the world, as a pose file stores it.

    Attributes:
        root_position: World position (3,) [m] of the root frame.
        root_orientation: World orientation of the root frame, unit quaternion (w, x, y, z).
    """

    root_position: tuple[float, float, float]
    root_orientation: tuple[float, float, float, float]

    #: World transform (4, 4) of the root frame: the pose file's own formula, so the two never differ.
    world_from_root = Pose.world_from_root

    @classmethod
    def from_transform(cls, world_from_root: np.ndarray) -> RootPlacement:
        W = np.asarray(world_from_root, dtype=float)
        return cls(tuple(W[:3, 3]), tuple(quaternion_from_matrix(W[:3, :3])))


def target_at(world_from_effector: np.ndarray, like: Target | None = None) -> Target:
    """A target at a world transform (4, 4), with the flags of ``like`` (defaults when None)."""
    if like is None:
        return Target.from_transform(world_from_effector)
    return Target.from_transform(world_from_effector, like.weight, like.position_only, like.enabled, like.priority)


def driven_target(t: Target, old: Target) -> Target:
    """A playback frame's target as a document target (position only: keep the orientation shown)."""
    if t.position_only:
        return old.replace(position=t.position, weight=t.weight, position_only=True, enabled=t.enabled)
    return t


def standing_pose(skeleton: gsik.Skeleton, flags: Mapping[str, Target], position_only: Iterable[str],
                  levels: Mapping[str, int] | None = None) -> Pose:
    """The skeleton's rest pose on its default root, targets on the effectors.

    Targets keep the enabled / weight / position-only / priority flags of ``flags``
    where it has the effector; new ones are position-only for the names in
    ``position_only`` and get priority ``levels[name]`` (0 when not given).
    """
    solver = gsik.Solver(skeleton)
    targets = {}
    for name, T in solver.effector_poses().items():
        old = flags.get(name)
        targets[name] = target_at(T, old) if old is not None else Target.from_transform(
            T, position_only=name in position_only, priority=(levels or {}).get(name, 0))
    placement = RootPlacement.from_transform(solver.world_from_root)
    return Pose(skeleton.name, skeleton.root, *placement, dict(zip(skeleton.dof_names, skeleton.rest.tolist())),
                targets)


def check_pose(skeleton: gsik.Skeleton, pose: Pose) -> None:
    """Raise :class:`gsik.PoseError` unless ``pose`` fits ``skeleton`` (angles for every DOF, a target per effector)."""
    sk = skeleton
    if pose.skeleton != sk.name:
        raise PoseError(f"pose is for skeleton {pose.skeleton!r}, this document's is {sk.name!r}")
    sk.frame_of(pose.root)
    missing = [n for n in sk.dof_names if n not in pose.joints]
    if missing:
        raise PoseError(f"pose has no angle for {choices(missing)}")
    effectors = [n for n in sk.effector_sites if n != pose.root]
    if set(pose.targets) != set(effectors):
        raise PoseError(f"pose targets {choices(pose.targets)} do not match the effectors {choices(effectors)}")
