"""How good a solved walk is: continuity, root slide, target errors."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik.anim.gait.walk import WalkResult
from gsik.anim.motion import Motion
from gsik.rotations import angle_between


def frame_displacements(motion: Motion) -> np.ndarray:
    """(n_frames - 1,) largest world displacement of any joint or site from each frame to the next [m]."""
    sk = motion.skeleton
    points = np.concatenate([sk.joint_frame, sk.site_frame])
    P = motion.positions()[:, points]
    return np.linalg.norm(np.diff(P, axis=0), axis=2).max(axis=1, initial=0.0)


class Continuity(NamedTuple):
    """Frame-to-frame joint motion at root swaps against elsewhere.

    Attributes:
        swap_frames: Frames whose root differs from the previous frame's.
        max_swap_jump: Largest joint displacement into a swap frame [m].
        median_jump: Median of the largest joint displacement between other
            consecutive frames [m].
        max_jump: Largest joint displacement between any two consecutive frames [m].
    """

    swap_frames: tuple[int, ...]
    max_swap_jump: float
    median_jump: float
    max_jump: float

    @property
    def ratio(self) -> float:
        """``max_swap_jump / median_jump`` (0 without swaps; inf if nothing else moves)."""
        if not self.swap_frames:
            return 0.0
        return self.max_swap_jump / self.median_jump if self.median_jump > 0 else math.inf


def continuity(motion: Motion) -> Continuity:
    """Compare the joints' displacement into each root-swap frame with the median displacement."""
    d = frame_displacements(motion)
    swaps = tuple(i for i in range(1, motion.n_frames) if motion.roots[i] != motion.roots[i - 1])
    is_swap = np.zeros(d.shape[0], dtype=bool)
    is_swap[[i - 1 for i in swaps]] = True
    other = d[~is_swap]
    return Continuity(
        swaps,
        float(d[is_swap].max(initial=0.0)),
        float(np.median(other)) if other.size else 0.0,
        float(d.max(initial=0.0)),
    )


def root_slide(motion: Motion) -> float:
    """Largest drift [m] of the root's world position while it stays the root.

    Each run of consecutive frames with the same root is compared with its
    first frame. A pinned root gives 0 up to rounding.
    """
    sk = motion.skeleton
    worst = 0.0
    start = 0
    for i in range(1, motion.n_frames + 1):
        if i == motion.n_frames or motion.roots[i] != motion.roots[start]:
            f = sk.frame_of(motion.roots[start])
            first = motion.frames(start)[1][f]
            for j in range(start + 1, i):
                worst = max(worst, float(np.linalg.norm(motion.frames(j)[1][f] - first)))
            start = i
    return worst


class WalkMeasures(NamedTuple):
    """The figures of a walk (:func:`measure_walk`). Lengths [m], angles [rad].

    Attributes:
        n_frames: Frames.
        n_swaps: Root swaps.
        continuity: :class:`Continuity` of the joints' motion.
        root_slide: Drift of the stance foot while it is the root (:func:`root_slide`).
        ball_slide: Drift of the ball of the trailing foot (an effector, not
            the root) while its heel rises, against where the rise began.
        max_plant_error: Largest distance from a swinging foot to its
            footprint at the frame before the root swaps to it.
        max_plant_angle: Largest angle between that foot and flat.
        max_tracking_error: Largest position error of any effector, any frame.
        mean_sweeps: Mean Gauss-Seidel sweeps per frame.
        finite: No NaN or infinity anywhere in the angles.
    """

    n_frames: int
    n_swaps: int
    continuity: Continuity
    root_slide: float
    ball_slide: float
    max_plant_error: float
    max_plant_angle: float
    max_tracking_error: float
    mean_sweeps: float
    finite: bool

    @property
    def swap_jump_ratio(self) -> float:
        return self.continuity.ratio


def measure_walk(result: WalkResult) -> WalkMeasures:
    """Continuity at the swaps, foot slide and footprint accuracy of a solved walk."""
    motion = result.motion
    plan = result.plan
    sk = motion.skeleton
    ball_slide = 0.0
    plant_error = 0.0
    plant_angle = 0.0
    for step in plan.footsteps:
        f = sk.frame_of(step.foot)
        k = plan.sites.index(step.foot)
        # The frame before the swap: the foot's last frame as an effector, on its footprint.
        last = step.swap_frame - 1
        R_last, p_last = motion.frames(last)
        plant_error = max(plant_error, float(np.linalg.norm(p_last[f] - step.end)))
        plant_angle = max(plant_angle, angle_between(R_last[f], plan.rotations[last, k]))
        R_h, p_h = motion.frames(step.heel_frame)
        ball0 = p_h[f] + R_h[f] @ step.ball
        for j in range(step.heel_frame + 1, step.lift_frame + 1):
            R_j, p_j = motion.frames(j)
            ball_slide = max(ball_slide, float(np.linalg.norm(p_j[f] + R_j[f] @ step.ball - ball0)))
    return WalkMeasures(
        motion.n_frames,
        len(plan.swap_frames),
        continuity(motion),
        root_slide(motion),
        ball_slide,
        plant_error,
        plant_angle,
        float(result.position_errors.max(initial=0.0)),
        float(result.sweeps.mean()) if result.sweeps.size else 0.0,
        bool(np.all(np.isfinite(motion.q)) and np.all(np.isfinite(motion.world_from_root))),
    )


def format_measures(m: WalkMeasures) -> str:
    """The figures of :func:`measure_walk` as readable lines."""
    c = m.continuity
    return "\n".join([
        f"frames:                 {m.n_frames} ({m.n_swaps} root swaps)",
        f"largest joint jump at a root swap: {c.max_swap_jump * 1e3:.3f} mm "
        f"(median elsewhere {c.median_jump * 1e3:.3f} mm, ratio {c.ratio:.2f}; largest anywhere "
        f"{c.max_jump * 1e3:.3f} mm)",
        f"stance foot slide while root:      {m.root_slide:.3g} m",
        f"trailing foot's ball slide (heel rise): {m.ball_slide * 1e3:.3f} mm",
        f"footprint error at plant:          {m.max_plant_error * 1e3:.3f} mm, "
        f"{math.degrees(m.max_plant_angle):.3f} deg",
        f"largest tracking error:            {m.max_tracking_error * 1e3:.3f} mm",
        f"sweeps per frame:                  {m.mean_sweeps:.1f}",
        f"finite:                            {'yes' if m.finite else 'NO'}",
    ])

