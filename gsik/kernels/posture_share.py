"""The posture level's share of a prioritised step, bounded on its own: a trust region for the learned prior's move.

A prioritised step is the target levels' step plus the posture level's move in what they leave free
(:func:`gsik.kernels.posture_level.prioritized_step_posture`). That move is flat for the targets only to first
order: a long one breaks a met target level by its second order, the trial is refused at that level and a restoring
step (a second prioritised solve at the trial pose, :func:`gsik.kernels.accept.restore`) brings it back. With the
bundled prior on bench_drag's studio drag the posture's move reached the whole step bound (``max_step``, 0.25 rad)
in 174 of 300 frames, where the moves of the trials accepted at once were ~0.07 rad.

:func:`bounded_step` solves the same levels and scales the posture's share ``s = dq - dq_targets`` (the step minus
the target levels' step) to at most ``bound`` [rad] in its largest component: ``dq = dq_targets + t s``,
``t = min(1, bound / max|s|)``. ``s`` lies in the target levels' free basis, so the targets' linearised errors do
not change, and ``dq`` stays in the (convex) box between two steps inside it. A share within the bound leaves the
step bit for bit :func:`~gsik.kernels.posture_level.prioritized_step_posture`'s.
"""

from __future__ import annotations

from gsik._jit import njit
from gsik.kernels import priority
from gsik.kernels.posture_level import _posture_level, prioritized_step_posture

#: The bound [rad] on the posture's share of a step with a full posture factor (the learned prior:
#: :attr:`gsik.kernels.control.PostureRows.share`); 0: none, the default. On bench_drag's studio drag (one step a
#: frame) 0.07 took restoring steps 174 -> 0 and the step 3.0x -> 1.9x a plain one, but the studio's settle by steps
#: then stopped at a less likely body than the rest posture's (tests/app/test_posture.py: Mahalanobis 9.9 against
#: 4.7 with the whole share), so it stays off until the settle test knows a bounded share (README, issue 20).
POSTURE_SHARE = 0.0


@njit(cache=True, _nrt=True)
def bounded_step(rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, normal, bound, dq,
                 below):
    """:func:`~gsik.kernels.posture_level.prioritized_step_posture` (same arguments before ``bound``, ``dq`` (n,)
    [rad] out) with the posture level's share scaled to at most ``bound`` [rad] (its largest component). The bound
    applies where the posture's level is solved by its normal equations (``normal`` (n, n)) and ``bound > 0``; else
    the step is :func:`~gsik.kernels.posture_level.prioritized_step_posture`'s. ``below`` (n,): the target levels'
    step (scratch). Returns ``(status, largest component of the share before bounding [rad], 0 when not bounded)``."""
    posture = dampings.shape[0] - 1
    if not bound > 0.0 or normal.shape[0] == 0 or posture < 0 \
            or starts[posture + 1] - starts[posture] != normal.shape[0]:
        return prioritized_step_posture(rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol,
                                        box_rel_tol, normal, dq), 0.0
    n = dq.shape[0]
    wk, last = priority.begin(starts, dampings, lo, dq)
    status, z0, rz, identity = priority.solve_levels(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol,
                                                     box_tol, box_rel_tol, posture, last, dq)
    if status != priority.OK:
        return status, 0.0
    below[:] = dq
    if rz > 0:
        if identity:
            priority._identity_into(wk.Zt, n)
        _posture_level(wk, rows, errors, starts[posture], starts[posture + 1], normal, z0, rz, dq, lo, hi,
                       dampings[posture], box_tol, box_rel_tol)
    priority.clip(dq, lo, hi)
    largest = 0.0
    for d in range(n):
        a = abs(dq[d] - below[d])
        if a > largest:
            largest = a
    if largest > bound:
        t = bound / largest
        for d in range(n):
            dq[d] = below[d] + t * (dq[d] - below[d])
        priority.clip(dq, lo, hi)
    return priority.OK, largest
