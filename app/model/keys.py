"""Keyed poses and baking: motions solved frame by frame from targets, off the document's own solver.

A key sequence is ``{frame: Pose}``. Frames between two keys are solved from
targets interpolated between the keys' targets (positions with a smoothstep
ease, orientations by slerp), each frame warm-started from the one before, so
the sequence plays and exports as an ordinary :class:`gsik.anim.motion.Motion`
(baked in chunks: :class:`gsik_studio.model.bake.KeyedBake`).
Scenarios' target frames are baked the same way (one solver step per frame,
as they played live before).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

import gsik
from gsik.anim.motion import Motion
from gsik.io.pose import Pose
from gsik.targets import Target
from gsik_studio.model.poses import driven_target

#: Solver steps per baked frame between keys (warm-started: a few settle it).
KEY_STEPS = 12


def slerp(q0, q1, s: float) -> np.ndarray:
    """Unit quaternion (4,) ``(w, x, y, z)`` a fraction ``s`` in [0, 1] of the short way from ``q0`` to ``q1``."""
    a, b = np.asarray(q0, dtype=float), np.asarray(q1, dtype=float)
    d = float(a @ b)
    if d < 0.0:  # the short way round
        b, d = -b, -d
    if d > 0.9995:  # nearly equal: a normalised lerp is exact enough and stable
        q = a + s * (b - a)
        return q / np.linalg.norm(q)
    theta = np.arccos(d)
    return (np.sin((1 - s) * theta) * a + np.sin(s * theta) * b) / np.sin(theta)


def smoothstep(t: float) -> float:
    """Ease in and out: 0 -> 0, 1 -> 1, zero slope at both ends."""
    return t * t * (3.0 - 2.0 * t)


def interpolated_targets(a: Pose, b: Pose, t: float) -> dict[str, Target]:
    """Targets a fraction ``t`` in [0, 1] of the way from key ``a`` to key ``b`` (effectors both have; ``a``'s flags)."""
    s = smoothstep(float(t))
    out = {}
    for name, ta in a.targets.items():
        tb = b.targets.get(name)
        if tb is None:
            out[name] = ta
            continue
        p = (1 - s) * ta.position + s * tb.position
        out[name] = ta.replace(position=p, orientation=slerp(ta.orientation, tb.orientation, s))
    return out


class _Baker:
    """A scratch solver that records a motion frame by frame (the document's solver is never touched)."""

    def __init__(self, skeleton: gsik.Skeleton, settings: gsik.SolverSettings, start: Pose):
        self.skeleton = skeleton
        self.solver = gsik.Solver(skeleton, settings=settings)
        self.targets: dict[str, Target] = {}
        self.q, self.roots, self.W = [], [], []
        self.place(start)

    def place(self, pose: Pose) -> None:
        """Jump to ``pose`` exactly: root, its placement, angles, targets."""
        if pose.root != self.solver.root:
            self.solver.set_root(pose.root)
        self.solver.set_world_from_root(pose.world_from_root)
        self.solver.set_q(np.clip(pose.q(self.skeleton), self.skeleton.lower, self.skeleton.upper))
        self.targets = {n: pose.targets[n] for n in self.solver.effector_names if n in pose.targets}
        self.solver.set_targets(self.targets)

    def drive(self, frame: Mapping[str, Target | None], steps: int) -> None:
        """New targets (None disables an effector; non-effectors skipped), then up to ``steps`` solver steps."""
        for name, t in frame.items():
            old = self.targets.get(name)
            if old is not None:
                self.targets[name] = old.replace(enabled=False) if t is None else driven_target(t, old)
        self.solver.set_targets(self.targets)
        for _ in range(steps):
            if self.solver.step().status is not gsik.Status.BUDGET_EXHAUSTED:
                break

    def record(self) -> None:
        self.q.append(self.solver.q)
        self.roots.append(self.solver.root)
        self.W.append(self.solver.world_from_root)

    def motion(self, frame_time: float) -> Motion:
        return Motion(self.skeleton, np.array(self.q), tuple(self.roots), np.array(self.W), frame_time)


def bake_target_frames(skeleton: gsik.Skeleton, settings: gsik.SolverSettings, start: Pose,
                       frames: Sequence[Mapping[str, Target | None]], frame_time: float, steps: int = 1) -> Motion:
    """A motion (len(frames) + 1 frames: ``start`` first) solving each target frame in turn, ``steps`` per frame.

    Raises:
        GsikError: a frame holds something that is not a target.
    """
    baker = _Baker(skeleton, settings, start)
    baker.record()
    for frame in frames:
        baker.drive(frame, steps)
        baker.record()
    return baker.motion(frame_time)
