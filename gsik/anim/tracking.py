"""Clip tracking: solve a motion's own effector poses frame by frame, warm-started.

The core loop of motion-capture cleanup and retargeting: for each frame of a
clip take the effectors' world poses from the clip's forward kinematics, pin
the IK root where the clip has it, and let the solver reach them starting
from the previous frame's answer. How well and how fast it follows is the
measure of the solver on real motion.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
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
        effector_names: (m,) the tracked effectors, in the error arrays' column order.
        position_errors: (n_frames, m) distance of each effector to its target [m].
        orientation_errors: (n_frames, m) angle to each target orientation [rad]
            (0 with ``position_only``).
        frame_seconds: (n_frames,) wall time of the solver's calls per frame [s]
            (frame 0 is a full solve; the others are warm-started steps).
        steps: (n_frames,) solver steps taken per frame (frame 0: linearisations).
        statuses: (n_frames,) the solver's status at the end of each frame.
    """

    motion: Motion
    effector_names: tuple[str, ...]
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    frame_seconds: np.ndarray
    steps: np.ndarray
    statuses: tuple[Status, ...]

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
    position_only: bool = False,
    q0=None,
    **settings,
) -> TrackResult:
    """Track ``motion`` with ``skeleton``: per frame, solve the clip's effector poses, warm-started.

    Frame 0 is solved in full (:meth:`Solver.solve`, from ``q0``); every later
    frame re-pins the root, sets the new targets and takes up to
    ``steps_per_frame`` warm-started :meth:`Solver.step` calls (fewer once
    converged). Only those solver calls are timed; the errors are measured
    afterwards by forward kinematics of the solved angles.

    Args:
        skeleton: The skeleton that tracks (the clip's own, or another one to
            retarget onto).
        motion: The clip.
        effectors: Effector sites of ``skeleton`` to track, each following
            the clip's joint or site of the same name; a mapping
            ``{effector: clip name}`` to follow other names (retargeting).
            Default: every effector site of ``skeleton`` (but the root) that
            the clip also has. The root, if listed, is left out: it is
            pinned where the clip has it.
        root: The IK root (a joint or site of both skeletons), pinned each
            frame where the clip has it. Default ``skeleton.root``.
        sweeps: Gauss-Seidel sweeps per step.
        steps_per_frame: Most steps per frame (>= 1).
        position_only: Track positions only (for retargeting onto a skeleton
            whose frames are oriented differently).
        q0: Starting angles (n_dofs,) [rad] for frame 0; default the rest pose.
        **settings: Other :class:`~gsik.solver.SolverSettings` fields.

    Raises:
        SolverError: an unknown effector or root (listing the valid names), a
            clip without frames, or a bad setting.
    """
    _check_inputs(skeleton, motion, steps_per_frame)
    root = skeleton.root if root is None else root
    skeleton.frame_of(root)
    root_in_clip = _clip_frame(motion.skeleton, root, "the root")
    pairs = _effector_pairs(skeleton, motion.skeleton, effectors, root)
    names = tuple(pairs)
    clip_frames = [_clip_frame(motion.skeleton, pairs[n], f"effector {n!r}") for n in names]
    clip = _clip_targets(motion, root_in_clip, names, clip_frames, position_only)
    solver = Solver(skeleton.with_root(root), q0=q0, world_from_root=clip.world_from_root[0], sweeps=sweeps,
                    **settings)
    Q, seconds, steps, statuses = _follow(solver, clip, steps_per_frame)
    eff_frames = np.array([skeleton.frame_of(n) for n in names], dtype=np.int64)
    pos, ori = _errors(skeleton, root, Q, clip, eff_frames, position_only)
    for a in (pos, ori, seconds, steps):
        a.flags.writeable = False
    solved = Motion(skeleton, Q, (root,) * motion.n_frames, clip.world_from_root, motion.frame_time)
    return TrackResult(solved, names, pos, ori, seconds, steps, tuple(statuses))


def _check_inputs(skeleton: Skeleton, motion: Motion, steps_per_frame: int) -> None:
    if not isinstance(skeleton, Skeleton):
        raise SolverError(f"track_clip needs a Skeleton, got {type(skeleton).__name__}")
    if not isinstance(motion, Motion):
        raise SolverError(f"track_clip needs a gsik.anim.motion.Motion, got {type(motion).__name__}")
    validate.whole(steps_per_frame, "steps_per_frame", SolverError, 1)
    if motion.n_frames == 0:
        raise SolverError("cannot track a clip with no frames")


def _effector_pairs(skeleton: Skeleton, clip_sk: Skeleton, effectors, root: str) -> dict[str, str]:
    """``{effector of skeleton: clip joint or site it follows}``, the root left out (it is pinned)."""
    available = [n for n in skeleton.effector_sites if n != root]
    pairs = _requested_pairs(clip_sk, effectors, available)
    pairs.pop(root, None)  # pinned where the clip has it: tracked exactly
    allowed = set(available)
    for name in pairs:
        if name not in allowed:
            raise SolverError(f"{name!r} is not an effector of skeleton {skeleton.name!r}; "
                              f"effectors: {choices(available)}")
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


class _ClipTargets(NamedTuple):
    """What the clip asks for, per frame: root pose (F, 4, 4), the positions (F, m, 3) [m] and orientations
    (F, m, 3, 3) of the tracked effectors ``names``; :meth:`at` makes one frame's targets when it is solved
    (made all up front, 100k frames of targets took ~800 MB)."""

    world_from_root: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray
    names: tuple[str, ...]
    position_only: bool

    def at(self, f: int) -> dict[str, Target]:
        """The targets of frame ``f``."""
        p, R = self.positions[f], self.rotations[f]
        return {n: Target(p[k], None if self.position_only else R[k]) for k, n in enumerate(self.names)}


def _clip_targets(motion: Motion, root_in_clip: int, names: tuple[str, ...], clip_frames: list[int],
                  position_only: bool) -> _ClipTargets:
    """Root poses and target positions and orientations from the clip's own forward kinematics."""
    F = motion.n_frames
    W = np.empty((F, 4, 4))
    target_p = np.empty((F, len(names), 3))
    target_R = np.empty((F, len(names), 3, 3))
    for f in range(F):
        R, p = motion.frames(f)
        W[f] = transform(R[root_in_clip], p[root_in_clip])
        target_p[f] = p[clip_frames]
        target_R[f] = R[clip_frames]
    return _ClipTargets(W, target_p, target_R, names, position_only)


def _follow(solver: Solver, clip: _ClipTargets, steps_per_frame: int):
    """Solve frame 0 in full, then warm-started steps per frame; only the solver calls are timed.

    Returns ``(Q (F, n_dofs) [rad], seconds (F,), steps (F,), statuses)``.
    """
    F = len(clip.world_from_root)
    Q = np.empty((F, solver.skeleton.n_dofs))
    seconds = np.empty(F)
    steps = np.zeros(F, dtype=np.int64)
    statuses: list[Status] = []
    for f in range(F):
        targets = clip.at(f)
        start = time.perf_counter()
        if f == 0:
            result = solver.solve(targets)
            steps[f] = result.iterations
        else:
            solver.set_world_from_root(clip.world_from_root[f])
            solver.set_targets(targets)
            for k in range(steps_per_frame):
                result = solver.step()
                steps[f] = k + 1
                if result.converged:
                    break
        seconds[f] = time.perf_counter() - start
        Q[f] = result.q
        statuses.append(result.status)
    return Q, seconds, steps, statuses


def _errors(skeleton: Skeleton, root: str, Q: np.ndarray, clip: _ClipTargets, eff_frames: np.ndarray,
            position_only: bool) -> tuple[np.ndarray, np.ndarray]:
    """Distance (F, m) [m] and angle (F, m) [rad] of each effector to its target, by forward kinematics."""
    F, m = clip.positions.shape[:2]
    pos = np.empty((F, m))
    ori = np.zeros((F, m))
    for f in range(F):
        R, p = world_frames(skeleton, Q[f], clip.world_from_root[f], root)
        pos[f] = np.linalg.norm(p[eff_frames] - clip.positions[f], axis=1)
        if not position_only:
            cos = (np.einsum("kij,kij->k", R[eff_frames], clip.rotations[f]) - 1.0) * 0.5
            ori[f] = np.arccos(np.clip(cos, -1.0, 1.0))
    return pos, ori


__all__ = ["TrackResult", "TrackSummary", "track_clip"]
