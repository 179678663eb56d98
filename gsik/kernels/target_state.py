"""The targets' state at one pose, read in one compiled call: what a prioritised attempt asks at its start and end.

:func:`target_state` evaluates every task's errors (:func:`gsik.kernels.kinematics.effector_errors`) and tests them
against the stage angle and the tolerances: booleans, as the same comparisons on the same errors in Python give them.
:func:`target_cost` is ``0.5 * sum(row_w * e**2)`` summed in the order NumPy sums a contiguous float64 array
(:func:`weighted_squares_sum`: eight accumulators over blocks of at most 128, halves above), so it is bit for bit
the NumPy expression ``0.5 * float((e * e * row_w).sum())`` it replaces (:meth:`gsik.control.Controller.target_cost`),
without its four array operations.
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels.kinematics import effector_errors

#: NumPy's pairwise summation: a block of at most this many terms is summed with eight accumulators.
BLOCK = 128
#: Most terms :func:`weighted_squares_sum` sums: one halving of NumPy's, 40 tasks (a drag's few targets; a tracked
#: 100-joint clip's ~200 are summed in NumPy by the caller).
MAX_TERMS = 240


@njit(cache=True, _nrt=False)
def target_state(R, p, frame, tp, tR, row_w, e, err, M, stage_angle, position_tolerance, orientation_tolerance):
    """``(every orientation error within stage_angle [rad], every target within the tolerances [m], [rad])`` at the
    frames ``R`` (n_frames, 3, 3), ``p`` (n_frames, 3) [m], for the tasks on frames ``frame`` (m,) aiming at ``tp``
    (m, 3) [m], ``tR`` (m, 3, 3) with row weights ``row_w`` (m, 6). A row a task does not use (weight <= 0) counts
    as error 0; a NaN error is within nothing. The errors are left in ``e`` (6 m,) and ``err`` (2, m)
    (:func:`~gsik.kernels.kinematics.effector_errors`; ``M`` (3, 3) scratch)."""
    effector_errors(R, p, frame, tp, tR, row_w, e, err, M)
    staged = within = True
    for k in range(frame.shape[0]):
        position = 0.0 if row_w[k, 0] <= 0.0 else err[0, k]
        orientation = 0.0 if row_w[k, 3] <= 0.0 else err[1, k]
        if not orientation <= stage_angle:
            staged = False
        if not (position <= position_tolerance and orientation <= orientation_tolerance):
            within = False
    return staged, within


@njit(cache=True, _nrt=False)
def target_cost(R, p, frame, tp, tR, row_w, e, err, M):
    """The targets' weighted squared error ``0.5 e^T W e`` at frames ``R``, ``p`` (arguments as
    :func:`target_state`'s), NumPy's sum bit for bit (:func:`weighted_squares_sum`); errors left in ``e``, ``err``."""
    effector_errors(R, p, frame, tp, tR, row_w, e, err, M)
    return 0.5 * weighted_squares_sum(e, row_w)  # NaN above MAX_TERMS terms: the caller sums in NumPy


@njit(cache=True, _nrt=False)
def weighted_squares_sum(e, w):
    """``((e * e).reshape(w.shape) * w).sum()`` for ``e`` (6 m,) and ``w`` (m, 6), as NumPy's ``add.reduce`` sums
    it: its start 0.0 plus the pairwise sum of the terms in order (NumPy's ``pairwise_sum``: under 8 terms one by one
    from 0.0; up to :data:`BLOCK` in eight accumulators combined as a tree, then the rest one by one; above, two halves,
    the first a multiple of 8 terms long, each summed so). At most :data:`MAX_TERMS` terms (NaN above: the caller
    sums more in NumPy: numba cannot load a cached recursion, which more halvings would take)."""
    n = e.shape[0]
    return 0.0 + _halved(e, w, 0, n) if n <= MAX_TERMS else math.nan


@njit(cache=True, _nrt=False)
def _term(e, w, i):
    """Term ``i`` of :func:`weighted_squares_sum`: ``(e[i] * e[i]) * w[i // 6, i % 6]``, NumPy's two products."""
    return (e[i] * e[i]) * w[i // 6, i % 6]


@njit(cache=True, _nrt=False)
def _block(e, w, lo, n):
    """The sum of terms ``lo`` to ``lo + n - 1``, ``n`` at most :data:`BLOCK`, in NumPy's order."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += _term(e, w, i)
        return res
    r0, r1, r2, r3 = _term(e, w, lo), _term(e, w, lo + 1), _term(e, w, lo + 2), _term(e, w, lo + 3)
    r4, r5, r6, r7 = _term(e, w, lo + 4), _term(e, w, lo + 5), _term(e, w, lo + 6), _term(e, w, lo + 7)
    end = lo + n - n % 8
    for i in range(lo + 8, end, 8):
        r0 += _term(e, w, i)
        r1 += _term(e, w, i + 1)
        r2 += _term(e, w, i + 2)
        r3 += _term(e, w, i + 3)
        r4 += _term(e, w, i + 4)
        r5 += _term(e, w, i + 5)
        r6 += _term(e, w, i + 6)
        r7 += _term(e, w, i + 7)
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    for i in range(end, lo + n):
        res += _term(e, w, i)
    return res


@njit(cache=True, _nrt=False)
def _halved(e, w, lo, n):
    """The sum of terms ``lo`` to ``lo + n - 1`` in NumPy's order, ``n`` at most :data:`MAX_TERMS`: one block, or two
    split where NumPy splits them (half the terms less the rest of a division by 8: each below ``n / 2 + 8``)."""
    if n <= BLOCK:
        return _block(e, w, lo, n)
    half = n // 2
    half -= half % 8
    return _block(e, w, lo, half) + _block(e, w, lo + half, n - half)
