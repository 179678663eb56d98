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
from gsik.errors import SolverError
from gsik.kinematics import world_frames
from gsik.rotations import angle_between
from gsik.anim.motion import Motion
from gsik.skeleton import Skeleton
from gsik.solver import Solver, Status
from gsik.anim.track_targets import (JOINT_PRIORITY, ClipTargets, TargetPlan, clip_frame, clip_posture,
                                     clip_targets, effector_pairs, position_only_flags, priority_levels)



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
    """Track ``motion`` with ``skeleton``: per frame, solve the clip's target poses.

    Frame 0 is solved in full (:meth:`Solver.solve`, from ``q0``); every later
    frame re-pins the root, sets the new targets and takes up to
    ``steps_per_frame`` :meth:`Solver.step` calls (fewer once converged):
    with ``follow_clip`` from the clip's pose of that frame (none where it
    already meets every target), else warm-started from the previous frame.
    Only those solver calls are timed; the errors are measured afterwards by
    forward kinematics of the solved angles.

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
        follow_clip: Start each frame from the clip's pose of that frame
            (DOFs matched by name; the rest pose for the others) and prefer it
            (:meth:`Solver.set_posture`, below every target).
        posture_weight: Weight of that preferred posture per DOF (>= 0; 0:
            start from it without preferring it).
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
    root_in_clip = clip_frame(motion.skeleton, root, "the root")
    pairs = effector_pairs(skeleton, motion.skeleton, effectors, root)
    names = tuple(pairs)
    clip_frames = [clip_frame(motion.skeleton, pairs[n], f"effector {n!r}") for n in names]
    plan = TargetPlan(names, clip_frames, position_only_flags(names, position_only),
                       priority_levels(skeleton, names, priorities))
    clip = clip_targets(motion, root_in_clip, plan)
    reference = clip_posture(skeleton, motion) if follow_clip else None
    if q0 is None and reference is not None:
        q0 = reference[0]
    solver = Solver(skeleton.with_root(root), q0=q0, world_from_root=clip.world_from_root[0], sweeps=sweeps,
                    **settings)
    Q, seconds, steps, statuses = _follow(solver, clip, steps_per_frame, reference, posture_weight, progress)
    measured = _measure(skeleton, root, Q, clip, motion, plan)
    solved = Motion(skeleton, Q, (root,) * motion.n_frames, clip.world_from_root, motion.frame_time)
    return TrackResult(solved, names, *measured[:2], validate.frozen(seconds), validate.frozen(steps, np.int64),
                       tuple(statuses), *measured[2:])


def _check_inputs(skeleton: Skeleton, motion: Motion, steps_per_frame: int) -> None:
    if not isinstance(skeleton, Skeleton):
        raise SolverError(f"track_clip needs a Skeleton, got {type(skeleton).__name__}")
    if not isinstance(motion, Motion):
        raise SolverError(f"track_clip needs a gsik.anim.motion.Motion, got {type(motion).__name__}")
    validate.whole(steps_per_frame, "steps_per_frame", SolverError, 1)
    if motion.n_frames == 0:
        raise SolverError("cannot track a clip with no frames")


def _follow(solver: Solver, clip: ClipTargets, steps_per_frame: int, reference: np.ndarray | None,
            posture_weight: float, progress):
    """Solve frame 0 in full, then steps per frame; only the solver calls are timed.

    Returns ``(Q (F, n_dofs) [rad], seconds (F,), steps (F,), statuses)``.
    """
    F = len(clip.world_from_root)
    Q = np.empty((F, solver.skeleton.n_dofs))
    seconds = np.empty(F)
    steps = np.zeros(F, dtype=np.int64)
    statuses: list[Status] = []
    for f in range(F):
        start = time.perf_counter()
        if f == 0:
            if reference is not None:
                solver.set_posture(reference[0], posture_weight)
            result = solver.solve(clip.at(0))
            Q[f], status, steps[f] = result.q, result.status, result.iterations
        else:
            Q[f], status, steps[f] = _frame(solver, clip, f, reference, posture_weight, steps_per_frame)
        seconds[f] = time.perf_counter() - start
        statuses.append(status)
        if progress is not None:
            progress(f + 1, F)
    return Q, seconds, steps, statuses


def _frame(solver: Solver, clip: ClipTargets, f: int, reference: np.ndarray | None, posture_weight: float,
           steps_per_frame: int) -> tuple[np.ndarray, Status, int]:
    """One later frame: ``(q (n_dofs,) [rad], status, steps taken)``.

    With a ``reference`` (F, n_dofs) the frame starts from it and keeps it as
    the posture: what no target needs stays exactly on it, the rest moves only
    as far as the targets ask; where it already meets every target no step is
    taken. Without, the steps are warm-started from the previous frame.
    """
    solver.set_world_from_root(clip.world_from_root[f])
    if reference is not None:
        solver.set_q(reference[f])
        if _meets(solver, clip.at(f)):
            return solver.q, Status.CONVERGED, 0
        solver.set_posture(reference[f], posture_weight)
    solver.set_targets(clip.at(f))
    for k in range(steps_per_frame):
        result = solver.step()
        if result.converged:
            break
    return result.q, result.status, k + 1


def _meets(solver: Solver, targets: dict) -> bool:
    """True when the solver's current pose is within its tolerances of every target."""
    s = solver.settings
    p, R = solver.world_positions(), solver.world_rotations()
    for name, t in targets.items():
        i = solver.skeleton.frame_of(name)
        if np.linalg.norm(p[i] - t.position) > s.position_tolerance:
            return False
        if t.uses_orientation:
            if angle_between(R[i], t.rotation) > s.orientation_tolerance:
                return False
    return True


def _measure(skeleton: Skeleton, root: str, Q: np.ndarray, clip: ClipTargets, motion: Motion, plan: TargetPlan):
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
    return (validate.frozen(pos), validate.frozen(ori), tuple(body), validate.frozen(body_err),
            float(np.median(heights)))


def _shared_names(skeleton: Skeleton, clip_sk: Skeleton) -> list[str]:
    """The joints and sites of ``skeleton`` that the clip's skeleton also has, in ``skeleton``'s order."""
    theirs = set(clip_sk.joint_names) | set(clip_sk.site_names)
    return [n for n in [*skeleton.joint_names, *skeleton.site_names] if n in theirs]


__all__ = ["JOINT_PRIORITY", "BodyError", "TrackResult", "TrackSummary", "track_clip"]
