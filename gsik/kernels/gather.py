"""What a prioritised frame gathers rather than builds again: a drag's moved targets, and the errors a step left.

:class:`gsik.control.Controller` keeps its targets in its own task order (by priority, then name). While a drag only
moves them, :func:`gather_targets` copies the solver's packed rows (:class:`gsik.kernels.TargetArrays`, one row per
effector) into that order in one call, instead of reading every :class:`gsik.Target` in Python. A step committed by
the compiled path has just evaluated every task's errors at the pose it leaves; :func:`gather_result` reports those
(:func:`gsik.kernels.control.report_errors`'s output, bit for bit) instead of evaluating them again.
"""

from __future__ import annotations

import numpy as np

from gsik._jit import njit
from gsik.kernels.accept import F_VALID

#: What :func:`gather_targets` returns: the targets already held (nothing written), moved (written), or declined: a
#: row out of the packed range or weighted otherwise than the controller's task (nothing written: the caller
#: retargets from the targets themselves).
SAME, MOVED, DECLINED = 0, 1, 2


@njit(cache=True, _nrt=False)
def gather_targets(position, rotation, row_weight, index, tp, tR, row_w, flags, ring):
    """Row ``index[k]`` of the packed targets (``position`` (e, 3) [m], ``rotation`` (e, 3, 3), ``row_weight`` (e, 6))
    into task ``k`` of ``tp`` (m, 3), ``tR`` (m, 3, 3), if every packed row's weights are ``row_w`` (m, 6) bit for bit.
    Every array C-contiguous float64 (``index`` int64): values compare as bits (``-0.0`` is not ``0.0``, a NaN is
    itself), as ``tobytes`` does.

    When a value changed, the controller's cached level state is dropped (``flags``: its
    :class:`~gsik.kernels.accept.LevelCache` flags) and its stall window emptied (``ring`` (2,) zeroed), as a
    retarget does. Returns :data:`SAME`, :data:`MOVED`, or :data:`DECLINED` (nothing written)."""
    wb, wc = row_weight.view(np.int64), row_w.view(np.int64)
    m = index.shape[0]
    for k in range(m):
        r = index[k]
        if r < 0 or r >= position.shape[0] or position.shape[0] != rotation.shape[0] \
                or position.shape[0] != row_weight.shape[0]:
            return DECLINED
        for j in range(6):
            if wb[r, j] != wc[k, j]:
                return DECLINED
    pb, pc = position.view(np.int64), tp.view(np.int64)
    rb, rc = rotation.view(np.int64), tR.view(np.int64)
    moved = False
    for k in range(m):
        r = index[k]
        for i in range(3):
            if pb[r, i] != pc[k, i]:
                moved = True
                pc[k, i] = pb[r, i]
            for j in range(3):
                if rb[r, i, j] != rc[k, i, j]:
                    moved = True
                    rc[k, i, j] = rb[r, i, j]
    if not moved:
        return SAME
    flags[F_VALID] = 0.0
    ring[0] = 0
    ring[1] = 0
    return MOVED


@njit(cache=True, _nrt=False)
def gather_result(q, err, index, out):
    """A result's angles and errors into ``out`` (n + 2k,): ``q`` (n,) [rad], then the position [m] and the
    orientation [rad] errors of ``k`` frames from the tasks' errors ``err`` (2, m): ``err[a, index[a, j]]``, 0
    where ``index[a, j]`` is -1 (no target, or a row the task does not use). Returns ``sum(q ** 2)`` [rad^2]
    (summed in order): finite exactly when every angle is and their squares do not overflow, the solver's test of a
    step gone non-finite, without a NumPy call of its own."""
    n, k = q.shape[0], index.shape[1]
    squares = 0.0
    for d in range(n):
        out[d] = q[d]
        squares += q[d] * q[d]
    for a in range(2):
        for j in range(k):
            i = index[a, j]
            out[n + a * k + j] = err[a, i] if i >= 0 else 0.0
    return squares
