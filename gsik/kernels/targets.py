"""A target moved in place (:meth:`gsik.Solver.move_target`): its checks and its packed row in one compiled call.

Both calls write straight into the solver's flat float64 buffer (:mod:`gsik.kernels.buffers`) element by element:
no views are cut, and they are compiled without numba's reference counting (``_nrt=False``), which halves a call
(1.1 to 0.4-0.5 µs measured on a loaded machine).
"""

from __future__ import annotations

from gsik._jit import njit
from gsik.targets import EXACT_ROTATION, MAX_COORDINATE

#: What :func:`move_position_at` and :func:`move_pose_at` return: the row written, or nothing written (the caller's
#: own checks then raise, or re-orthonormalise a rotation a little off, as :class:`gsik.Target` does).
WRITTEN, NOT_WRITTEN = 0, 1


@njit(cache=True, _nrt=False)
def move_position_at(position, floats, p_at):
    """A target's position moved to ``position`` [m] in a flat float64 buffer, its row's position at
    ``floats[p_at:p_at + 3]``, if it passes :class:`gsik.Target`'s checks as it is: three coordinates (a
    one-dimensional float64 array of any length and layout: the caller checks only type, dtype and dimensions),
    each within :data:`~gsik.targets.MAX_COORDINATE` (so finite). Returns :data:`WRITTEN`, or :data:`NOT_WRITTEN`
    with nothing changed."""
    if position.shape[0] != 3 or not _within(position, MAX_COORDINATE):
        return NOT_WRITTEN
    for a in range(3):
        floats[p_at + a] = position[a]
    return WRITTEN


@njit(cache=True, _nrt=False)
def move_pose_at(position, rotation, floats, p_at, R_at):
    """:func:`move_position_at` with a rotation matrix ``rotation`` (any two-dimensional float64 array: one not
    (3, 3) is refused), written row by row at ``floats[R_at:R_at + 9]``: its columns orthonormal within
    :data:`~gsik.targets.EXACT_ROTATION` (where ``Target`` keeps a matrix as given) and its determinant positive."""
    if position.shape[0] != 3 or rotation.shape[0] != 3 or rotation.shape[1] != 3:
        return NOT_WRITTEN
    if not (_within(position, MAX_COORDINATE) and _rotation(rotation, EXACT_ROTATION)):
        return NOT_WRITTEN
    for a in range(3):
        floats[p_at + a] = position[a]
        for b in range(3):
            floats[R_at + 3 * a + b] = rotation[a, b]
    return WRITTEN


@njit(cache=True, inline="always")
def _within(position, max_coordinate):
    """True if every coordinate of ``position`` (3,) lies within ``max_coordinate`` (so is finite)."""
    x, y, z = position[0], position[1], position[2]
    return abs(x) <= max_coordinate and abs(y) <= max_coordinate and abs(z) <= max_coordinate  # NaN fails too


@njit(cache=True, inline="always")
def _rotation(rotation, exact):
    """True if the columns of ``rotation`` (3, 3) are orthonormal within ``exact`` and its determinant positive
    (NaN fails)."""
    a00, a01, a02 = rotation[0, 0], rotation[0, 1], rotation[0, 2]
    a10, a11, a12 = rotation[1, 0], rotation[1, 1], rotation[1, 2]
    a20, a21, a22 = rotation[2, 0], rotation[2, 1], rotation[2, 2]
    off = max(abs(a00 * a00 + a10 * a10 + a20 * a20 - 1.0), abs(a01 * a01 + a11 * a11 + a21 * a21 - 1.0),
              abs(a02 * a02 + a12 * a12 + a22 * a22 - 1.0), abs(a00 * a01 + a10 * a11 + a20 * a21),
              abs(a00 * a02 + a10 * a12 + a20 * a22), abs(a01 * a02 + a11 * a12 + a21 * a22))
    det = a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20)
    return off <= exact and det > 0.0
