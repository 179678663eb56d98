"""The measures :class:`gsik.stall.PostureSettle` reads of each step of a solve()'s posture settle, in one call.

Two largest magnitudes a step, each ``float(np.abs(x).max())`` bit for bit (a NaN propagates), without NumPy's two
calls (and their Python wrapper) per array: a drag's warm solve() makes three to eight such steps a frame.
"""

from __future__ import annotations

from gsik._jit import njit


@njit(cache=True, _nrt=False)
def _largest(x) -> float:
    """``max |x_i|`` of a non-empty (n,) array; NaN if any ``x_i`` is (as NumPy's maximum)."""
    m = abs(x[0])
    for i in range(1, x.shape[0]):
        a = abs(x[i])
        if a > m or a != a:
            m = a
    return m


@njit(cache=True, _nrt=False)
def largest_pair(step, moved) -> tuple:
    """``(max |step_i|, max |moved_i|)`` [rad] of a step's full step (n,) and the change it made (n,) (each
    non-empty; NaN for an array holding one)."""
    return _largest(step), _largest(moved)
