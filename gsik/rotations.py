"""Rotation conversions on plain NumPy arrays.

Names follow ``x_from_y``. Quaternions are ``(w, x, y, z)``, unit norm.
Rotation vectors are axis * angle ``[rad]``. Batch forms accept leading
dimensions: ``(..., 3, 3)``, ``(..., 4)``, ``(..., 3)``.
"""

from __future__ import annotations

import math

import numpy as np

#: Largest deviation from orthonormality accepted as a rotation matrix.
ROTATION_TOLERANCE = 1e-6


def skew(v: np.ndarray) -> np.ndarray:
    """The cross-product matrix ``[v]x`` of a 3-vector: ``skew(a) @ b == cross(a, b)``."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def matrix_from_axis_angle(axis: np.ndarray, angle) -> np.ndarray:
    """Rotation matrices (..., 3, 3) turning ``angle`` (scalar or (...)) [rad] about the unit ``axis`` (3,)."""
    k = skew(np.asarray(axis, dtype=float))
    angle = np.asarray(angle, dtype=float)
    s = np.sin(angle)[..., None, None]
    c = np.cos(angle)[..., None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def matrix_from_cos_sin(axis: int, cos: np.ndarray, sin: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) about coordinate axis 0 (x), 1 (y) or 2 (z), from cos and sin (...).

    Taking cos and sin rather than the angle lets a caller pass exact values
    (a BVH file's 90 degrees gives exactly 0 and 1).
    """
    cos = np.asarray(cos, dtype=float)
    sin = np.asarray(sin, dtype=float)
    i, j = (axis + 1) % 3, (axis + 2) % 3  # the plane the rotation turns
    R = np.zeros(cos.shape + (3, 3))
    R[..., axis, axis] = 1.0
    R[..., i, i] = cos
    R[..., j, j] = cos
    R[..., i, j] = -sin
    R[..., j, i] = sin
    return R


def matrix_from_rotvec(rotvec: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of a rotation vector (3,) [rad] (the exp map)."""
    rotvec = np.asarray(rotvec, dtype=float)
    angle = float(np.linalg.norm(rotvec))
    if angle < 1e-12:
        return np.eye(3) + skew(rotvec)
    return matrix_from_axis_angle(rotvec / angle, angle)


def rotvec_from_matrix(R: np.ndarray) -> np.ndarray:
    """Rotation vector (3,) [rad] of a rotation matrix (3, 3) (the log map).

    Accurate over the whole range, including angles near pi where the
    antisymmetric part vanishes.
    """
    from gsik.kernels.kinematics import rotvec_from_matrix as log_map

    return log_map(np.ascontiguousarray(R, dtype=float))


def matrix_from_quaternion(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (..., 3, 3) of unit quaternions (..., 4) ``(w, x, y, z)``."""
    q = np.asarray(q, dtype=float)
    w, x, y, z = np.moveaxis(q, -1, 0)
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1 - 2 * (y * y + z * z)
    R[..., 0, 1] = 2 * (x * y - z * w)
    R[..., 0, 2] = 2 * (x * z + y * w)
    R[..., 1, 0] = 2 * (x * y + z * w)
    R[..., 1, 1] = 1 - 2 * (x * x + z * z)
    R[..., 1, 2] = 2 * (y * z - x * w)
    R[..., 2, 0] = 2 * (x * z - y * w)
    R[..., 2, 1] = 2 * (y * z + x * w)
    R[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def quaternion_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (4,) ``(w, x, y, z)`` with ``w >= 0`` of a rotation matrix (3, 3)."""
    return np.array(quaternion_from_rows(np.asarray(R, dtype=float).tolist()))


def quaternion_from_rows(m: list) -> tuple[float, float, float, float]:
    """:func:`quaternion_from_matrix` of a rotation given as nested lists (3, 3), in plain floats (fast)."""
    t = m[0][0] + m[1][1] + m[2][2]
    if t > 0.0:
        s = 2.0 * math.sqrt(t + 1.0)
        q = [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    else:
        diag = [m[0][0], m[1][1], m[2][2]]
        i = diag.index(max(diag))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + m[i][i] - m[j][j] - m[k][k], 1e-300))
        q = [0.0] * 4
        q[0] = (m[k][j] - m[j][k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j][i] + m[i][j]) / s
        q[1 + k] = (m[k][i] + m[i][k]) / s
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    sign = -1.0 if q[0] < 0.0 else 1.0
    return (sign * q[0] / norm, sign * q[1] / norm, sign * q[2] / norm, sign * q[3] / norm)


def is_rotation_matrix(R: np.ndarray, tolerance: float = ROTATION_TOLERANCE) -> bool:
    """True if ``R`` is a finite (3, 3) orthonormal matrix with determinant +1."""
    R = np.asarray(R)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        return False
    return bool(np.abs(R.T @ R - np.eye(3)).max() <= tolerance and np.linalg.det(R) > 0.0)


def angle_between(R_a: np.ndarray, R_b: np.ndarray) -> float:
    """Angle [rad] of the rotation taking ``R_b`` to ``R_a`` (0 to pi)."""
    cos = (np.trace(np.asarray(R_a).T @ np.asarray(R_b)) - 1.0) * 0.5
    return float(np.arccos(np.clip(cos, -1.0, 1.0)))


def transform(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Homogeneous transform (4, 4) from a rotation (3, 3) and a translation (3,)."""
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T
