"""Every retarget checks its own result before it is written: rotations, joint errors, planted feet.

Three conditions (:class:`Tolerances`):

1. **Frames are rotations**: every skeleton frame's world rotation in every
   frame is orthonormal with determinant +1 (within
   :attr:`Tolerances.rotation`).
2. **Mapped joints follow the clip**: each mapped frame's p95 distance from
   the clip's target is at most :attr:`Tolerances.position_fraction` of the
   target skeleton's height (2%: 36 mm on a 1.8 m body).
3. **Feet stay planted where the clip's are**: over the frames the clip has a
   foot planted (:mod:`gsik.anim.contacts`), the retargeted foot's p95 speed
   is at most :attr:`Tolerances.slide_fraction` body heights per second.

A result outside any of them is :class:`RetargetCheck` with ``ok`` False;
its :meth:`~RetargetCheck.message` names the worst joints and frames and the
reason: a joint limit (a degree of freedom above the joint is at its limit
there), a degenerate frame (a rotation that is not one, or a pelvis frame the
clip's hips cannot define), or the mapping (nothing else explains it).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from gsik.anim.motion import Motion
from gsik.errors import ToleranceError

#: Joints named in a message at most.
WORST_SHOWN = 3


@dataclass(frozen=True)
class Tolerances:
    """What a retargeted result must meet.

    Attributes:
        position_fraction: Largest p95 error of a mapped joint, in body heights.
        slide_fraction: Largest p95 speed of a planted foot, in body heights per second.
        rotation: Largest deviation of a world rotation from orthonormal (``|RᵀR - I|``, ``|det R - 1|``).
        limit_margin: A degree of freedom this close to a limit counts as at it [rad].
    """

    position_fraction: float = 0.02
    slide_fraction: float = 0.02
    rotation: float = 1e-6
    limit_margin: float = 1e-3


class JointError(NamedTuple):
    """One mapped frame's error against the clip's target [m]: p95, max and the clip frame of the max."""

    frame: str
    clip_joint: str
    p95: float
    max: float
    worst_frame: int


class RotationCheck(NamedTuple):
    """The worst deviation of a world rotation from a rotation, and where (skeleton frame, clip frame)."""

    error: float
    frame: str
    clip_frame: int


@dataclass(frozen=True)
class RetargetCheck:
    """The check of one retargeted clip (lengths [m], speeds [m/s]).

    Attributes:
        height: The target skeleton's height.
        joints: Every mapped frame's error, worst p95 first.
        rotations: The worst world rotation.
        slide_before: p95 planted-foot speed of the targets before pinning (as the clip asks).
        slide_after: p95 planted-foot speed of the result.
        tolerances: What was asked.
        reasons: Why the result is outside its tolerance; empty when it is within.
    """

    height: float
    joints: tuple[JointError, ...]
    rotations: RotationCheck
    slide_before: float
    slide_after: float
    tolerances: Tolerances
    reasons: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.reasons

    @property
    def worst_p95(self) -> float:
        """The largest p95 error of a mapped joint [m] (0 with none)."""
        return self.joints[0].p95 if self.joints else 0.0

    def message(self, what: str = "the result") -> str:
        """One sentence for the error: what is outside, the worst joints and frames, and why."""
        return f"{what} is outside its tolerance: {'; '.join(self.reasons)} (use --force to write it anyway)"

    def raise_if_outside(self, what: str = "the result") -> None:
        """:class:`~gsik.errors.ToleranceError` with :meth:`message` unless ``ok``."""
        if not self.ok:
            raise ToleranceError(self.message(what))


def rotation_check(motion: Motion) -> RotationCheck:
    """The largest deviation from a rotation of any skeleton frame's world rotation in any frame of ``motion``."""
    worst = RotationCheck(0.0, motion.skeleton.frame_names[0], 0)
    eye = np.eye(3)
    for i in range(motion.n_frames):
        R = motion.frames(i)[0]
        ortho = np.abs(np.transpose(R, (0, 2, 1)) @ R - eye).max(axis=(1, 2))
        dev = np.maximum(ortho, np.abs(np.linalg.det(R) - 1.0))
        dev = np.where(np.isfinite(dev), dev, np.inf)
        k = int(np.argmax(dev))
        if dev[k] > worst.error:
            worst = RotationCheck(float(dev[k]), motion.skeleton.frame_names[k], i)
    return worst


def joint_errors(errors: np.ndarray, mapping: dict[str, str]) -> tuple[JointError, ...]:
    """Per mapped frame (``errors`` (n_frames, n_mapped) [m], columns in ``mapping``'s order), worst p95 first."""
    rows = [JointError(f, j, float(np.percentile(errors[:, k], 95)), float(errors[:, k].max()),
                       int(np.argmax(errors[:, k])))
            for k, (f, j) in enumerate(mapping.items())]
    return tuple(sorted(rows, key=lambda r: -r.p95))


def _at_limit(motion: Motion, frame: str, clip_frame: int, margin: float) -> str | None:
    """The first degree of freedom above ``frame`` at a limit in ``clip_frame``, as ``"name at its lower limit"``."""
    sk = motion.skeleton
    above = sk.ancestry[:, sk.frame_of(frame)]
    q = motion.q[clip_frame]
    for d in np.flatnonzero(above[sk.dof_frame]):
        for bound, side in ((sk.lower[d], "lower"), (sk.upper[d], "upper")):
            if abs(q[d] - bound) <= margin:
                return f"{sk.dof_names[d]} at its {side} limit"
    return None


def _reason(motion: Motion, row: JointError, degenerate: np.ndarray, tol: Tolerances) -> str:
    """Why ``row``'s joint is off at its worst frame: a degenerate frame, a limit, or the mapping."""
    if degenerate[row.worst_frame]:
        return "a degenerate frame (the clip's hips and spine do not define the pelvis there)"
    limit = _at_limit(motion, row.frame, row.worst_frame, tol.limit_margin)
    if limit is not None:
        return f"a limit ({limit})"
    return f"the mapping ({row.clip_joint} -> {row.frame} is not where the skeleton can follow it)"


def _joint_reasons(motion: Motion, rows: Sequence[JointError], height: float, degenerate: np.ndarray,
                   tol: Tolerances) -> list[str]:
    """One reason naming the joints over their bound (worst first, at most :data:`WORST_SHOWN`)."""
    bound = tol.position_fraction * height
    over = [r for r in rows if not r.p95 <= bound]
    if not over:
        return []
    shown = ", ".join(f"{r.frame} ({r.clip_joint}) p95 {r.p95 * 1e3:.1f} mm, max {r.max * 1e3:.1f} mm at frame "
                      f"{r.worst_frame}" for r in over[:WORST_SHOWN])
    more = f" and {len(over) - WORST_SHOWN} more" if len(over) > WORST_SHOWN else ""
    return [f"joint error p95 over {bound * 1e3:.1f} mm ({100 * tol.position_fraction:g}% of the height "
            f"{height:.3f} m): {shown}{more}; reason: {_reason(motion, over[0], degenerate, tol)}"]


def check_retarget(motion: Motion, errors: np.ndarray, mapping: dict[str, str], height: float,
                   slide: tuple[float, float], degenerate: np.ndarray | None = None,
                   tolerances: Tolerances = Tolerances()) -> RetargetCheck:
    """Check a retargeted ``motion`` against the clip.

    Args:
        motion: The result.
        errors: (n_frames, n_mapped) distance [m] of each mapped frame from the clip's target.
        mapping: Skeleton frame -> clip joint, in ``errors``' column order.
        height: The target skeleton's height [m].
        slide: Planted-foot p95 speed [m/s] of the targets before pinning and of the result.
        degenerate: (n_frames,) bool, frames whose pelvis the clip cannot define (default none).
        tolerances: The bounds.
    """
    degenerate = np.zeros(motion.n_frames, dtype=bool) if degenerate is None else np.asarray(degenerate)
    rows = joint_errors(errors, mapping)
    rot = rotation_check(motion)
    reasons = []
    if not rot.error <= tolerances.rotation:
        reasons.append(f"frame {rot.frame} is not a rotation at clip frame {rot.clip_frame} (deviation "
                       f"{rot.error:.3g}); reason: a degenerate frame")
    reasons += _joint_reasons(motion, rows, height, degenerate, tolerances)
    slide_bound = tolerances.slide_fraction * height
    if not slide[1] <= slide_bound:
        reasons.append(f"planted feet slide at p95 {slide[1]:.3f} m/s (at most {slide_bound:.3f} m/s); reason: "
                       "the pinned feet cannot be reached (a limit or the leg's length)")
    return RetargetCheck(height, rows, rot, slide[0], slide[1], tolerances, tuple(reasons))
