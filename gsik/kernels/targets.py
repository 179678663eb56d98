"""A target moved in place (:meth:`gsik.Solver.move_target`): its checks and its packed row in one compiled call."""

from __future__ import annotations

from gsik._jit import njit
from gsik.targets import EXACT_ROTATION, MAX_COORDINATE

#: What :func:`move_row` returns: the row written, or nothing written (the caller's own checks then raise, or
#: re-orthonormalise a rotation a little off, as :class:`gsik.Target` does).
WRITTEN, NOT_WRITTEN = 0, 1


@njit(cache=True)
def move_position_at(position, floats, p_at):
    """A target's position moved to ``position`` [m] in a flat float64 buffer (:mod:`gsik.kernels.buffers`), its
    row's position at ``floats[p_at:p_at + 3]``: :func:`move_row` without a rotation, also checking the length (a
    one-dimensional float64 array of any length and layout: its caller checks only type, dtype and dimensions).
    :data:`NOT_WRITTEN` unless it has three coordinates within :class:`gsik.Target`'s bounds. Two arrays to unbox."""
    if position.shape[0] != 3:
        return NOT_WRITTEN
    return move_row(position, floats[:0].reshape((0, 3)), MAX_COORDINATE, EXACT_ROTATION,
                    floats[p_at:p_at + 3].reshape((1, 3)), floats[:0].reshape((0, 3, 3)), 0)


@njit(cache=True)
def move_pose_at(position, rotation, floats, p_at, R_at):
    """:func:`move_position_at` with a rotation matrix ``rotation`` (any two-dimensional float64 array: one not
    (3, 3) is refused), written row by row at ``floats[R_at:R_at + 9]``."""
    if position.shape[0] != 3 or rotation.shape[0] != 3 or rotation.shape[1] != 3:
        return NOT_WRITTEN
    return move_row(position, rotation, MAX_COORDINATE, EXACT_ROTATION, floats[p_at:p_at + 3].reshape((1, 3)),
                    floats[R_at:R_at + 9].reshape((1, 3, 3)), 0)


@njit(cache=True)
def move_row(position, rotation, max_coordinate, exact, tp, tR, k):
    """Write ``position`` (3,) [m] and ``rotation`` (3, 3) into row ``k`` of the packed targets ``tp`` (m, 3) and
    ``tR`` (m, 3, 3) if they pass :class:`gsik.Target`'s checks as they are: every coordinate within
    ``max_coordinate`` (so finite), the rotation's columns orthonormal within ``exact`` (where ``Target`` keeps
    a matrix as given) and its determinant positive. A ``rotation`` with no rows leaves the row's rotation. Returns :data:`WRITTEN`, or :data:`NOT_WRITTEN` with nothing changed."""
    x, y, z = position[0], position[1], position[2]
    if not (abs(x) <= max_coordinate and abs(y) <= max_coordinate and abs(z) <= max_coordinate):  # NaN fails too
        return NOT_WRITTEN
    if rotation.shape[0] == 3:
        a00, a01, a02 = rotation[0, 0], rotation[0, 1], rotation[0, 2]
        a10, a11, a12 = rotation[1, 0], rotation[1, 1], rotation[1, 2]
        a20, a21, a22 = rotation[2, 0], rotation[2, 1], rotation[2, 2]
        off = max(abs(a00 * a00 + a10 * a10 + a20 * a20 - 1.0), abs(a01 * a01 + a11 * a11 + a21 * a21 - 1.0),
                  abs(a02 * a02 + a12 * a12 + a22 * a22 - 1.0), abs(a00 * a01 + a10 * a11 + a20 * a21),
                  abs(a00 * a02 + a10 * a12 + a20 * a22), abs(a01 * a02 + a11 * a12 + a21 * a22))
        det = a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20)
        if not (off <= exact and det > 0.0):  # NaN fails too
            return NOT_WRITTEN
        for i in range(3):
            for j in range(3):
                tR[k, i, j] = rotation[i, j]
    tp[k, 0], tp[k, 1], tp[k, 2] = x, y, z
    return WRITTEN
