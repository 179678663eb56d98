"""The pelvis's orientation from a clip's hips and spine, well defined or refused.

The frame is built from two robust directions: left hip to right hip (x),
and from the hips' midpoint towards a spine joint, less its part along x (z).
A spine joint on the line through the hips (a common export puts the first
spine joint exactly between them) gives no z: then a farther joint (the neck)
is used, and where none is off that line the clip is refused, naming the
frame and the joints. Every frame is checked to be a rotation before use.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gsik.errors import RetargetError

#: Least distance of the up point from the line through the hips, as a fraction of the hips' width.
MIN_UP_OFFSET = 0.1
#: Largest deviation of a pelvis frame from a rotation (|R^T R - I|, |det R - 1|).
ROTATION_TOLERANCE = 1e-6


def unit(v: np.ndarray) -> np.ndarray:
    """``v`` (..., 3) scaled to unit length along its last axis (zero vectors stay zero)."""
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def pelvis_frames(left_hip: np.ndarray, right_hip: np.ndarray, neck: np.ndarray) -> np.ndarray:
    """(n, 3, 3) pelvis orientations from (n, 3) points: x left hip to right hip, z towards the neck, y forward."""
    x = unit(right_hip - left_hip)
    z = neck - 0.5 * (left_hip + right_hip)
    z = unit(z - np.sum(z * x, axis=-1, keepdims=True) * x)
    return np.stack([x, np.cross(z, x), z], axis=-1)


def up_offsets(left_hip: np.ndarray, right_hip: np.ndarray, point: np.ndarray) -> np.ndarray:
    """(n,) distance of ``point`` from the line through the hips over the hips' width (points (n, 3))."""
    axis = right_hip - left_hip
    width = np.linalg.norm(axis, axis=-1)
    z = point - 0.5 * (left_hip + right_hip)
    x = unit(axis)
    perp = np.linalg.norm(z - np.sum(z * x, axis=-1, keepdims=True) * x, axis=-1)
    return perp / np.maximum(width, 1e-300)


def up_reference(points: Mapping[str, np.ndarray], joints: Mapping[str, str], clip: str = "clip") -> str:
    """Which of ``points``' ``"waist"`` and ``"neck"`` (in that order) the pelvis's z can point to in every frame.

    Args:
        points: ``left_hip``, ``right_hip`` and the candidates, each (n, 3) clip positions per frame.
        joints: the clip joint of each key, for messages.
        clip: the clip's name, for messages.

    Raises:
        RetargetError: the hip joints coincide in a frame, or no candidate is off their line in every frame
            (the message names the clip, the frame and the joints).
    """
    left, right = points["left_hip"], points["right_hip"]
    width = np.linalg.norm(right - left, axis=-1)
    scale = max(float(np.max(np.abs(np.concatenate([left, right])))), 1e-300)
    if np.any(width <= 1e-9 * scale):
        i = int(np.argmin(width))
        raise RetargetError(f"{clip}: frame {i}: the hip joints {joints['left_hip']!r} and {joints['right_hip']!r} "
                            f"coincide: the pelvis frame is undefined (map other joints in a mapping file)")
    worst = {}
    for f in ("waist", "neck"):
        if f in points:
            off = up_offsets(left, right, points[f])
            if off.min() >= MIN_UP_OFFSET:
                return f
            worst[f] = (int(np.argmin(off)), float(off.min()))
    said = "; ".join(f"{joints[f]!r} is {d:.3g} hip widths off it in frame {i}" for f, (i, d) in worst.items())
    raise RetargetError(f"{clip}: the pelvis frame is degenerate: no spine joint stands off the line through the "
                        f"hips {joints['left_hip']!r} and {joints['right_hip']!r} ({said}; at least "
                        f"{MIN_UP_OFFSET:g} needed)")


def check_rotations(R: np.ndarray, what: str) -> None:
    """:class:`RetargetError` naming ``what`` and the first bad frame unless every R (n, 3, 3) is a rotation."""
    finite = np.isfinite(R).all(axis=(1, 2))
    R = np.where(finite[:, None, None], R, 0.0)
    err = np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max(axis=(1, 2))
    err = np.where(finite, np.maximum(err, np.abs(np.linalg.det(R) - 1.0)), np.inf)
    bad = ~(err <= ROTATION_TOLERANCE)  # NaN counts as bad
    if bad.any():
        i = int(np.argmax(bad))
        raise RetargetError(f"{what}: frame {i} is not a rotation (deviation {err[i]:.3g}); nothing written")


def rig_lean(left_hip: np.ndarray, right_hip: np.ndarray, spine: np.ndarray, neck: np.ndarray) -> np.ndarray:
    """The rig's constant turn (3, 3) from the pelvis frame through its first spine joint to the true pelvis.

    The first spine joint is rigid with the hips in most rigs, but not straight
    above them; the turn is the mean, over the clip's frames (points (n, 3)),
    from that frame to the one through the neck: the waist is straight on
    average. (A rig's rest pose cannot tell: many are not standing.)
    """
    lean = np.transpose(pelvis_frames(left_hip, right_hip, spine), (0, 2, 1)) @ pelvis_frames(left_hip, right_hip,
                                                                                             neck)
    U, _, Vt = np.linalg.svd(lean.mean(axis=0))
    return U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt


__all__ = ["pelvis_frames", "rig_lean", "up_reference", "up_offsets", "check_rotations", "MIN_UP_OFFSET"]
