"""The conventions shared by BVH export and import: units, up axes, Euler orders, and the Euler conversions."""

from __future__ import annotations

import numpy as np

from gsik.errors import BvhError
from gsik.rotations import matrix_from_cos_sin

#: File units per metre for each ``units`` choice.
UNITS_PER_METRE = {"cm": 100.0, "m": 1.0}
#: The ``up`` choices of the export.
UP_AXES = ("z", "y")
#: The world turn from gsik's z-up world to a y-up file: -90 degrees about x (z -> y, y -> -z).
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
Z_UP_TO_Y_UP.flags.writeable = False
#: Euler order of the root's and of decomposed joints' rotation channels, per up axis
#: (``"zxy"``: ``Zrotation Xrotation Yrotation``, ``R = Rz @ Rx @ Ry``).
EULER_ORDER = {"z": "zxy", "y": "yxz"}
#: The ``limits`` choices of the import.
LIMIT_MODES = ("wide", "from_motion")

AXIS_INDEX = {"x": 0, "y": 1, "z": 2}


class BvhImportWarning(UserWarning):
    """An import that could not reproduce the whole file exactly (see :attr:`BvhImport.warnings`)."""


def _order_axes(order: str) -> tuple[int, int, int]:
    o = order.lower() if isinstance(order, str) else ""
    if len(o) != 3 or set(o) != {"x", "y", "z"}:
        raise BvhError(f"Euler order must be three distinct axes from 'xyz' (like 'zxy'), got {order!r}")
    return AXIS_INDEX[o[0]], AXIS_INDEX[o[1]], AXIS_INDEX[o[2]]


def matrix_from_euler(angles: np.ndarray, order: str) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of Euler angles (..., 3) [rad].

    ``order="zxy"`` gives ``R = Rz(a[0]) @ Rx(a[1]) @ Ry(a[2])``: the BVH
    meaning of ``Zrotation Xrotation Yrotation`` (the first axis outermost).
    """
    axes = _order_axes(order)
    angles = np.asarray(angles, dtype=float)
    if angles.shape[-1:] != (3,):
        raise BvhError(f"Euler angles must have shape (..., 3), got {angles.shape}")
    R = np.broadcast_to(np.eye(3), angles.shape[:-1] + (3, 3)).copy()
    for n, axis in enumerate(axes):
        R = R @ matrix_from_cos_sin(axis, np.cos(angles[..., n]), np.sin(angles[..., n]))
    return R


def euler_from_matrix(R: np.ndarray, order: str) -> np.ndarray:
    """Euler angles (..., 3) [rad] of rotation matrices (..., 3, 3), the inverse of :func:`matrix_from_euler`.

    The middle angle is in [-pi/2, pi/2], the others in [-pi, pi]. At gimbal
    lock (middle angle +-pi/2) the last angle is 0.
    """
    i, j, k = _order_axes(order)
    R = np.asarray(R, dtype=float)
    if R.shape[-2:] != (3, 3):
        raise BvhError(f"rotation matrices must have shape (..., 3, 3), got {R.shape}")
    s = 1.0 if (j - i) % 3 == 1 else -1.0  # +1 for the cyclic orders xyz, yzx, zxy
    cos_b = np.hypot(R[..., i, i], R[..., i, j])
    b = np.arctan2(s * R[..., i, k], cos_b)
    c = np.arctan2(-s * R[..., i, j], R[..., i, i])
    a = np.arctan2(-s * R[..., j, k], R[..., k, k])
    lock = cos_b < 1e-9
    if np.any(lock):
        c = np.where(lock, 0.0, c)
        a = np.where(lock, np.arctan2(s * R[..., k, j], R[..., j, j]), a)
    return np.stack([a, b, c], axis=-1)
