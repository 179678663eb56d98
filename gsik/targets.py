"""Effector targets: validated once, where they enter."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gsik.errors import TargetError
from gsik.rotations import ROTATION_TOLERANCE, is_rotation_matrix, matrix_from_quaternion, quaternion_from_matrix


@dataclass(frozen=True, eq=False)
class Target:
    """A 6-DOF goal for one end-effector.

    Args:
        position: World position (3,) [m].
        orientation: World orientation as a rotation matrix (3, 3) or a unit
            quaternion (4,) ``(w, x, y, z)``; ``None`` for position only.
        weight: Relative importance (>= 0) in the weighted least squares.
        position_only: Ignore the orientation (kept, so it can be re-enabled).
        priority: Strict priority level: 0 (the default) is the most important;
            a target on level k is met only in what the levels below k leave
            free, so it never moves them. Targets on one level trade off by
            ``weight``.

    Raises:
        TargetError: on NaN or infinite values, wrong shapes, a matrix that
            is not a rotation, a quaternion that is not of unit norm, or a
            negative weight. Nothing is stored from a rejected target.

    ``position`` and ``orientation`` are stored as read-only float arrays; the
    orientation always as a (3, 3) matrix.
    """

    position: np.ndarray
    orientation: np.ndarray | None = None
    weight: float = 1.0
    position_only: bool = False
    priority: int = 0

    def __post_init__(self):
        try:
            p = np.array(self.position, dtype=float)
        except (TypeError, ValueError):
            raise TargetError(f"target position must be 3 numbers, got {self.position!r}") from None
        if p.shape != (3,):
            raise TargetError(f"target position must have shape (3,), got {p.shape}")
        if not np.all(np.isfinite(p)):
            raise TargetError(f"target position must be finite, got {p.tolist()}")
        p.flags.writeable = False
        object.__setattr__(self, "position", p)
        if self.orientation is not None:
            object.__setattr__(self, "orientation", _rotation(self.orientation))
        try:
            w = float(self.weight)
        except (TypeError, ValueError):
            raise TargetError(f"target weight must be a number, got {self.weight!r}") from None
        if not np.isfinite(w) or w < 0.0:
            raise TargetError(f"target weight must be finite and >= 0, got {self.weight!r}")
        object.__setattr__(self, "weight", w)
        object.__setattr__(self, "position_only", bool(self.position_only))
        object.__setattr__(self, "priority", _priority(self.priority))

    @property
    def uses_orientation(self) -> bool:
        """True if the orientation rows take part in the solve."""
        return self.orientation is not None and not self.position_only

    @property
    def quaternion(self) -> np.ndarray | None:
        """The orientation as a unit quaternion (4,) ``(w, x, y, z)``, or ``None``."""
        return None if self.orientation is None else quaternion_from_matrix(self.orientation)

    @classmethod
    def from_transform(cls, T: np.ndarray, weight: float = 1.0, position_only: bool = False) -> Target:
        """A target at a world transform (4, 4)."""
        T = np.asarray(T, dtype=float)
        if T.shape != (4, 4):
            raise TargetError(f"target transform must have shape (4, 4), got {T.shape}")
        return cls(T[:3, 3], T[:3, :3], weight, position_only)

    def replace(self, **changes) -> Target:
        """A copy with some fields changed (validated again)."""
        fields = dict(position=self.position, orientation=self.orientation, weight=self.weight,
                      position_only=self.position_only, priority=self.priority)
        fields.update(changes)
        return Target(**fields)


def _priority(value) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise TargetError(f"target priority must be a whole number >= 0 (0 is the most important), got {value!r}")
    return int(value)


def _rotation(value) -> np.ndarray:
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise TargetError(f"target orientation must be a 3x3 rotation matrix or a quaternion, got {value!r}") from None
    if not np.all(np.isfinite(a)):
        raise TargetError(f"target orientation must be finite, got {a.tolist()}")
    if a.shape == (4,):
        norm = float(np.linalg.norm(a))
        if abs(norm - 1.0) > ROTATION_TOLERANCE * 100:
            raise TargetError(f"target quaternion (w, x, y, z) must have unit norm, got norm {norm:.6g}")
        a = matrix_from_quaternion(a / norm)
    elif a.shape == (3, 3):
        if not is_rotation_matrix(a):
            raise TargetError("target orientation is not a rotation matrix (must be orthonormal with determinant +1)")
        # Re-orthonormalise so the kernels' log map sees an exact rotation.
        u, _, vt = np.linalg.svd(a)
        a = u @ vt
    else:
        raise TargetError(f"target orientation must have shape (3, 3) or (4,), got {a.shape}")
    a.flags.writeable = False
    return a
