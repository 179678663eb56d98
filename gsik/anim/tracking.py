"""Clip tracking: solve a motion's targets frame by frame, keeping the clip's body where no target says otherwise.

The core loop of motion-capture cleanup and retargeting: for each frame of a
clip take the targets' world poses from the clip's forward kinematics, pin
the IK root where the clip has it, and let the solver reach them. By default
(``follow_clip=True``) the clip's own pose of each frame (DOFs matched by
name) is where that frame's steps start and the solver's preferred posture
(the lowest priority, :meth:`gsik.Solver.set_posture`): every DOF the targets
do not need follows the clip (fingers, knees, the spine), and the targets only
move what they must. ``follow_clip=False`` is the plain solver measure: frame
0 from the rest pose, every later frame warm-started from the previous
frame's answer, no posture.

Targets are any joints or sites of the skeleton; by default the skeleton's
effector sites are on priority 0 and any other joint or site on priority 1
(end sites over knees), which ``priorities`` changes per name."""

from __future__ import annotations

import time
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from gsik import validate
from gsik.errors import SkeletonError, SolverError, choices
from gsik.kinematics import world_frames
from gsik.anim.motion import Motion
from gsik.rotations import transform
from gsik.skeleton import Skeleton
from gsik.solver import Solver, Status
from gsik.targets import Target

#: Priority of targets on joints or sites that are not effectors (knees under the end sites).
JOINT_PRIORITY = 1


class TrackSummary(NamedTuple):
    """Figures of a track over its frames from ``first_frame`` on.

    Attributes:
        frames: Number of frames summarised.
        mean_position_error: Mean over frames and effectors [m].
        max_position_error: Largest [m].
        median_position_error: Median over frames of each frame's largest error [m].
        mean_orientation_error: Mean [rad] (0 without orientation targets).
        max_orientation_error: Largest [rad].
        median_frame_seconds: Median solver time per frame [s].
        max_frame_seconds: Largest solver time of a frame [s].
    """

    frames: int
    mean_position_error: float
    max_position_error: float
    median_position_error: float
    mean_orientation_error: float
    max_orientation_error: float
    median_frame_seconds: float
    max_frame_seconds: float


@dataclass(frozen=True, eq=False)
class TrackResult:
    """The solved motion and how closely and how fast it followed the clip. Arrays are read-only.

    Attributes:
        motion: The solved motion on the tracking skeleton (root pinned per frame).
        effector_names: (m,) the tracked targets (joints or sites), in the error arrays' column order.
        position_errors: (n_frames, m) distance of each target's frame to its target [m].
        orientation_errors: (n_frames, m) angle to each target orientation [rad]
            (0 for position-only targets).
        frame_seconds: (n_frames,) wall time of the solver's calls per frame [s]
            (frame 0 is a full solve; the others are warm-started steps).
        steps: (n_frames,) solver steps taken per frame (frame 0: linearisations).
        statuses: (n_frames,) the solver's status at the end of each frame.
        body_names: (k,) every joint and site the skeleton shares with the clip.
        body_errors: (n_frames, k) distance of each of them to the clip's [m].
        body_height: The clip's height [m]: its extent along z in the median frame.
    """

    motion: Motion
    effector_names: tuple[str, ...]
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    frame_seconds: np.ndarray
    steps: np.ndarray
    statuses: tuple[Status, ...]
    body_names: tuple[str, ...]
    body_errors: np.ndarray
    body_height: float

    def summary(self, first_frame: int = 1) -> TrackSummary:
        """Mean, max and median figures from ``first_frame`` on (default 1: skip the initial full solve)."""
        n = self.position_errors.shape[0]
        first = min(max(int(first_frame), 0), n)
        pos = self.position_errors[first:]
        ori = self.orientation_errors[first:]
        sec = self.frame_seconds[first:]
        if pos.shape[0] == 0:
            return TrackSummary(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        worst = pos.max(axis=1, initial=0.0)
        return TrackSummary(
            frames=int(pos.shape[0]),
            mean_position_error=float(pos.mean()) if pos.size else 0.0,
            max_position_error=float(pos.max(initial=0.0)),
            median_position_error=float(np.median(worst)),
            mean_orientation_error=float(ori.mean()) if ori.size else 0.0,
            max_orientation_error=float(ori.max(initial=0.0)),
            median_frame_seconds=float(np.median(sec)),
            max_frame_seconds=float(sec.max()),
        )

    def body_table(self, percentile: float = 95.0) -> list[BodyError]:
        """Each shared joint and site's error over all frames, worst (at ``percentile``) first."""
        if self.body_errors.size == 0:
            return []
        p = np.percentile(self.body_errors, percentile, axis=0)
        worst = np.argmax(self.body_errors, axis=0)
        rows = [BodyError(n, float(p[k]), float(self.body_errors[worst[k], k]), int(worst[k]),
                          n in self.effector_names) for k, n in enumerate(self.body_names)]
        return sorted(rows, key=lambda r: -r.percentile_error)


class BodyError(NamedTuple):
    """One joint or site's distance to the clip over a track.

    Attributes:
        name: The joint or site.
        percentile_error: Its error at the percentile asked for, over frames [m].
        max_error: Its largest error [m] ...
        worst_frame: ... in this frame.
        tracked: True when it is one of the targets.
    """

    name: str
    percentile_error: float
    max_error: float
    worst_frame: int
    tracked: bool


def _clip_frame(clip_skeleton: Skeleton, name: str, what: str) -> int:
    try:
        return clip_skeleton.frame_of(name)
    except SkeletonError:
        raise SolverError(f"the clip's skeleton {clip_skeleton.name!r} has no joint or site {name!r} for {what}; "
                          f"joints: {choices(clip_skeleton.joint_names)}; sites: {choices(clip_skeleton.site_names)}"
                          ) from None


def track_clip(
    skeleton: Skeleton,
    motion: Motion,
    effectors: Sequence[str] | Mapping[str, str] | None = None,
    root: str | None = None,
    *,
    sweeps: int = 20,
    steps_per_frame: int = 5,
    position_only: bool | Collection[str] = False,
    priorities: Mapping[str, int] | None = None,
    follow_clip: bool = True,
    posture_weight: float = 1.0,
    q0=None,
    progress: Callable[[int, int], None] | None = None,
    **settings,
) -> TrackResult:
    """Track ``motion`` with ``skeleton``: per frame, solve the clip's target poses, warm-started.

    Frame 0 is solved in full (:meth:`Solver.solve`, from ``q0``); every later
    frame re-pins the root, sets the new targets (with ``follow_clip``: starts
    from the clip's pose and prefers it) and takes up to ``steps_per_frame``
    :meth:`Solver.step` calls (fewer once converged). Only those solver calls are timed; the errors are measured
    afterwards by forward kinematics of the solved angles.

    Args:
        skeleton: The skeleton that tracks (the clip's own, or another one to
            retarget onto).
        motion: The clip.
        effectors: Joints or sites of ``skeleton`` to track, each following
            the clip's joint or site of the same name; a mapping
            ``{name: clip name}`` to follow other names (retargeting).
            Default: every effector site of ``skeleton`` (but the root) that
            the clip also has. The root, if listed, is left out: it is
            pinned where the clip has it.
        root: The IK root (a joint or site of both skeletons), pinned each
            frame where the clip has it. Default ``skeleton.root``.
        sweeps: Gauss-Seidel sweeps per step.
        steps_per_frame: Most steps per frame (>= 1).
        position_only: Track positions only: ``True`` for every target, or
            the names of the targets to track by position only.
        priorities: ``{name: level}`` (0 most important). Default: the
            skeleton's effector sites 0, other joints and sites
            :data:`JOINT_PRIORITY`.
        follow_clip: Prefer the clip's pose of each frame (DOFs matched by
            name; the rest pose for the others) and start frame 0 from it.
        posture_weight: Weight of that preferred posture per DOF (> 0).
        q0: Starting angles (n_dofs,) [rad] for frame 0; default the clip's
            pose with ``follow_clip``, else the rest pose.
        progress: Called as ``progress(frames done, n_frames)`` after each frame.
        **settings: Other :class:`~gsik.solver.SolverSettings` fields.

    Raises:
        SolverError: an unknown target or root (listing the valid names), a
            clip without frames, or a bad setting.
    """
    _check_inputs(skeleton, motion, steps_per_frame)
    root = skeleton.root if root is None else root
    skeleton.frame_of(root)
    root_in_clip = _clip_frame(motion.skeleton, root, "the root")
    pairs = _effector_pairs(skeleton, motion.skeleton, effectors, root)
    names = tuple(pairs)
    clip_frames = [_clip_frame(motion.skeleton, pairs[n], f"effector {n!r}") for n in names]
    plan = _TargetPlan(names, clip_frames, _position_only(names, position_only),
                       _priorities(skeleton, names, priorities))
    clip = _clip_targets(motion, root_in_clip, plan)
    reference = _clip_posture(skeleton, motion) if follow_clip else None
    if q0 is None and reference is not None:
        q0 = reference[0]
    solver = Solver(skeleton.with_root(root), q0=q0, world_from_root=clip.world_from_root[0], sweeps=sweeps,
                    **settings)
    Q, seconds, steps, statuses = _follow(solver, clip, steps_per_frame, reference, posture_weight, progress)
    measured = _measure(skeleton, root, Q, clip, motion, plan)
    solved = Motion(skeleton, Q, (root,) * motion.n_frames, clip.world_from_root, motion.frame_time)
    return TrackResult(solved, names, *measured[:2], _readonly(seconds), _readonly(steps), tuple(statuses),
                       *measured[2:])


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


def _check_inputs(skeleton: Skeleton, motion: Motion, steps_per_frame: int) -> None:
    if not isinstance(skeleton, Skeleton):
        raise SolverError(f"track_clip needs a Skeleton, got {type(skeleton).__name__}")
    if not isinstance(motion, Motion):
        raise SolverError(f"track_clip needs a gsik.anim.motion.Motion, got {type(motion).__name__}")
    validate.whole(steps_per_frame, "steps_per_frame", SolverError, 1)
    if motion.n_frames == 0:
        raise SolverError("cannot track a clip with no frames")


def _effector_pairs(skeleton: Skeleton, clip_sk: Skeleton, effectors, root: str) -> dict[str, str]:
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


def _position_only(names: tuple[str, ...], position_only) -> tuple[bool, ...]:
    """Per target: position only?"""
    if isinstance(position_only, (bool, np.bool_)):
        return (bool(position_only),) * len(names)
    chosen = [position_only] if isinstance(position_only, str) else list(position_only)
    unknown = [n for n in chosen if n not in names]
    if unknown:
        raise SolverError(f"position_only names {unknown[0]!r}, which is not tracked; targets: {choices(names)}")
    return tuple(n in chosen for n in names)


def _priorities(skeleton: Skeleton, names: tuple[str, ...], priorities) -> tuple[int, ...]:
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


class _TargetPlan(NamedTuple):
    """The targets: names, the clip frame each follows, position only?, priority level."""

    names: tuple[str, ...]
    clip_frames: list[int]
    position_only: tuple[bool, ...]
    priorities: tuple[int, ...]


class _ClipTargets(NamedTuple):
    """What the clip asks for, per frame: root pose (F, 4, 4), targets, their positions (F, m, 3) [m] and
    orientations (F, m, 3, 3)."""

    world_from_root: np.ndarray
    targets: list[dict[str, Target]]
    positions: np.ndarray
    rotations: np.ndarray


def _clip_targets(motion: Motion, root_in_clip: int, plan: _TargetPlan) -> _ClipTargets:
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
    return _ClipTargets(W, targets, target_p, target_R)


def _clip_posture(skeleton: Skeleton, motion: Motion) -> np.ndarray:
    """(F, n_dofs) the clip's angles on ``skeleton``, DOFs matched by name (the rest pose where the clip has none)."""
    ref = np.tile(skeleton.rest, (motion.n_frames, 1))
    clip_dofs = motion.skeleton.dof_names
    for d, name in enumerate(skeleton.dof_names):
        if name in clip_dofs:
            ref[:, d] = motion.q[:, motion.skeleton.dof_index(name)]
    return np.clip(ref, skeleton.lower, skeleton.upper)


def _follow(solver: Solver, clip: _ClipTargets, steps_per_frame: int, reference: np.ndarray | None,
            posture_weight: float, progress):
    """Solve frame 0 in full, then warm-started steps per frame; only the solver calls are timed.

    With a ``reference`` (F, n_dofs), each frame starts from it and keeps it as
    the posture: what no target needs stays exactly on it, the rest moves only
    as far as the targets ask.

    Returns ``(Q (F, n_dofs) [rad], seconds (F,), steps (F,), statuses)``.
    """
    F = len(clip.targets)
    Q = np.empty((F, solver.skeleton.n_dofs))
    seconds = np.empty(F)
    steps = np.zeros(F, dtype=np.int64)
    statuses: list[Status] = []
    for f in range(F):
        start = time.perf_counter()
        if reference is not None:
            solver.set_posture(reference[f], posture_weight)
        if f == 0:
            result = solver.solve(clip.targets[0])
            steps[f] = result.iterations
        else:
            solver.set_world_from_root(clip.world_from_root[f])
            if reference is not None:
                solver.set_q(reference[f])
            solver.set_targets(clip.targets[f])
            for k in range(steps_per_frame):
                result = solver.step()
                steps[f] = k + 1
                if result.converged:
                    break
        seconds[f] = time.perf_counter() - start
        Q[f] = result.q
        statuses.append(result.status)
        if progress is not None:
            progress(f + 1, F)
    return Q, seconds, steps, statuses


def _measure(skeleton: Skeleton, root: str, Q: np.ndarray, clip: _ClipTargets, motion: Motion, plan: _TargetPlan):
    """By forward kinematics of the solved angles: the targets' distances (F, m) [m] and angles (F, m) [rad],
    then every shared joint and site's name, distance to the clip (F, k) [m] and the clip's height [m]."""
    F, m = clip.positions.shape[:2]
    frames = np.array([skeleton.frame_of(n) for n in plan.names], dtype=np.int64)
    body = _shared_names(skeleton, motion.skeleton)
    mine = [skeleton.frame_of(n) for n in body]
    theirs = [motion.skeleton.frame_of(n) for n in body]
    pos, ori, body_err = np.empty((F, m)), np.zeros((F, m)), np.empty((F, len(body)))
    heights = np.empty(F)
    oriented = ~np.array(plan.position_only, dtype=bool)
    for f in range(F):
        R, p = world_frames(skeleton, Q[f], clip.world_from_root[f], root)
        pos[f] = np.linalg.norm(p[frames] - clip.positions[f], axis=1)
        cos = (np.einsum("kij,kij->k", R[frames], clip.rotations[f]) - 1.0) * 0.5
        ori[f] = np.where(oriented, np.arccos(np.clip(cos, -1.0, 1.0)), 0.0)
        clip_p = motion.frames(f)[1]
        body_err[f] = np.linalg.norm(p[mine] - clip_p[theirs], axis=1)
        heights[f] = np.ptp(clip_p[:, 2])
    return (_readonly(pos), _readonly(ori), tuple(body), _readonly(body_err), float(np.median(heights)))


def _shared_names(skeleton: Skeleton, clip_sk: Skeleton) -> list[str]:
    """The joints and sites of ``skeleton`` that the clip's skeleton also has, in ``skeleton``'s order."""
    theirs = set(clip_sk.joint_names) | set(clip_sk.site_names)
    return [n for n in [*skeleton.joint_names, *skeleton.site_names] if n in theirs]


__all__ = ["JOINT_PRIORITY", "BodyError", "TrackResult", "TrackSummary", "track_clip"]
