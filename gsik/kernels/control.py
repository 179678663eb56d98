"""The prioritised step's common path compiled: level evaluation, linearisation and packing, the trial.

:class:`gsik.control.Controller` judges a step by every level's state at the start pose and at the trial
pose (:class:`gsik.acceptance.LevelState`) and solves the levels linearised at the start pose. Here those are
compiled over named contracts, so a step is one call (:func:`step_trial`) and a halved or restoring trial one more
(:func:`trial`):

- :class:`ControlTasks`: the targets, each task's level and the bounds of its band and of convergence, and which
  error row goes to which packed row (what depends on the row weights only).
- :class:`PostureRows`: the posture's reference and its precision's factor ``L`` (``P = L^T L``), factored once
  (and ``P`` itself where the step solves a full posture's level by its normal equations).
- :class:`ControlWork`: every buffer a step writes, allocated once per controller.

The packed levels (:class:`gsik.priority.PackedLevels`) are the target levels in priority order (balance's two
rows, filled by the caller, where it sits), then the posture's rows. Balance's state and rows are the caller's
(:mod:`gsik.balance`): with balance on, the caller runs :func:`linearise`, fills its rows, then
:func:`gsik.kernels.priority.prioritized_step_in` and :func:`trial`.
numba's cache checks a kernel against its own file only: the compiled strict-priority step
(:mod:`gsik.kernels.priority`, :mod:`~gsik.kernels.posture_level`, :mod:`~gsik.kernels.range_space`) is inside this
module's cached kernels, and a change to those files alone leaves them stale (delete
``gsik/kernels/__pycache__/*.nb[ic]`` after one).
The kernels here, in :mod:`gsik.kernels.accept`, :mod:`gsik.kernels.fallback` and :mod:`gsik.kernels.gather`
allocate nothing and are compiled without numba's reference counting (``_nrt=False``, as in
:mod:`gsik.kernels.kinematics`): they copy arrays by loops (:func:`gsik.kernels.step.copy_into`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik._jit import njit
from gsik.kernels import priority
from gsik.kernels.kinematics import effector_errors, frames_into, jacobian
from gsik.kernels.posture_level import POSTURE_SHARE, is_full, normal_matrix
from gsik.kernels.range_space import RangeWork, make_range_work, prioritized_step_range_in
from gsik.kernels.rows import SUMS

# Indices of ControlWork.out: the kernel's status (gsik.kernels.priority.OK / NOT_FINITE), the trial's
# convergence (1.0 / 0.0), its targets' weighted squared error and whether a target lags (1.0 / 0.0); the full
# step's posture share's largest component before its bound [rad] (0: not bounded, :mod:`gsik.kernels.posture_level`).
O_STATUS, O_CONVERGED, O_TARGET_COST, O_LAGGING, O_SHARE = range(5)


class ControlTasks(NamedTuple):
    """The targets as the controller's kernels read them.

    Attributes:
        frame: (m,) int64 frame index of each task.
        position: (m, 3) world target positions [m]. rotation: (m, 3, 3) world target orientations.
        row_weight: (m, 6) weights of the 3 position and 3 orientation rows (0: unused).
        level: (m,) int64 the level of each task (an index into the costs).
        band: (2, m) position [m] and orientation [rad] errors within which a task counts as met (inf: unused).
        tolerance: (2, m) the errors within which a task has converged (inf: unused).
        lag: (2, m) the errors beyond which a task lags (inf: unused).
        packed_row: (M_t,) int64 the error row (``6 k + r``) of each packed target row, -1 for balance's.
        packed_weight: (M_t,) the packed target rows' weights.
        starts: (K + 1,) int64 the packed levels' row starts (the posture's last, when on).
    """

    frame: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    row_weight: np.ndarray
    level: np.ndarray
    band: np.ndarray
    tolerance: np.ndarray
    lag: np.ndarray
    packed_row: np.ndarray
    packed_weight: np.ndarray
    starts: np.ndarray


class PostureRows(NamedTuple):
    """The posture level: minimise ``|L (q + dq - reference)|^2`` (:func:`posture_rows`).

    Attributes:
        reference: (n_dofs,) the preferred angles [rad].
        factor: (k, n_dofs) ``L`` with ``P = L^T L`` (k = 0: no posture).
        gain: (1,) the share of the posture's Gauss-Newton step a step takes (its errors' scale; 1: all of it).
        normal: (n_dofs, n_dofs) ``P`` where the step solves the level by its normal equations (a square,
            well-conditioned factor: :func:`gsik.kernels.posture_level.normal_matrix`), else empty (default:
            the pivoted QR's level).
        share: (1,) the bound [rad] on the posture level's share of a step where ``normal`` is given
            (:func:`gsik.kernels.posture_level.prioritized_step_posture`; 0: none).
    """

    reference: np.ndarray
    factor: np.ndarray
    gain: np.ndarray
    normal: np.ndarray = np.zeros((0, 0))  # empty: nothing in it to change
    share: np.ndarray = np.zeros(1)  # 0: no bound (posture_rows gives each posture its own array)


def posture_rows(reference: np.ndarray | None, factor: np.ndarray) -> PostureRows:
    """The :class:`PostureRows` of a posture at ``reference`` (n,) [rad] with the factor ``factor`` (k, n) of its
    precision (``None`` and (0, n): no posture); gain 1; a well-conditioned factor's level solved by its normal
    equations (:func:`gsik.kernels.posture_level.normal_matrix`: the learned prior's, a diagonal one's), the share of
    a step of a full factor's (the learned prior's) bounded by :data:`gsik.kernels.posture_level.POSTURE_SHARE`, a
    diagonal one's not (:func:`share_of`)."""
    n = factor.shape[1]
    if reference is None:
        return PostureRows(np.zeros(n), np.zeros((0, n)), np.ones(1), np.zeros((0, n)), np.zeros(1))
    factor = np.ascontiguousarray(factor, dtype=float)
    normal = normal_matrix(factor)
    return PostureRows(np.array(reference, dtype=float), factor, np.ones(1), normal, np.array([share_of(normal)]))


def share_of(normal: np.ndarray) -> float:
    """The bound [rad] on the posture's share of a step with this :attr:`PostureRows.normal`: :data:`POSTURE_SHARE`
    for a full factor's (:func:`gsik.kernels.posture_level.is_full`), else 0 (none)."""
    return POSTURE_SHARE if is_full(normal) else 0.0


class ControlWork(NamedTuple):
    """A controller's buffers (:func:`make_work`).

    Attributes:
        J: (6m, n) the tasks' Jacobian. rows: (M, n), errors, weights: (M,) the packed levels.
        dampings: (K,) each packed level's damping. lo, hi: (n,) the box of the step. dq: (n,) the step [rad].
        q: (n,) the trial angles [rad]. R: (n_frames, 3, 3), p: (n_frames, 3) the trial's world frames.
        e: (6m,) the trial's error rows. err: (2, m) its tasks' position [m] and orientation [rad] errors.
        costs: (L + 1,) the trial's level costs, the posture's last. met: (L + 1,) bool the trial's met levels.
        M: (3, 3) scratch. out: (5,) the trial's ``O_*`` figures. below: (n,) the target levels' step [rad].
        priority: the strict-priority step's buffers (:class:`gsik.kernels.priority.Work`, for the largest packed
            level), kept between steps.
        range_work: the normal equations' buffers (:class:`gsik.kernels.range_space.RangeWork`, for the target rows),
            kept between steps (with a full posture's damped inverse).
    """

    J: np.ndarray
    rows: np.ndarray
    errors: np.ndarray
    weights: np.ndarray
    dampings: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    dq: np.ndarray
    q: np.ndarray
    R: np.ndarray
    p: np.ndarray
    e: np.ndarray
    err: np.ndarray
    costs: np.ndarray
    met: np.ndarray
    M: np.ndarray
    out: np.ndarray
    below: np.ndarray
    priority: priority.Work
    range_work: RangeWork


def make_work(n_frames: int, n_dofs: int, n_tasks: int, starts: np.ndarray, n_levels: int) -> ControlWork:
    """A :class:`ControlWork` for ``n_levels`` (L) target and balance levels packed into the levels ``starts`` (K + 1,)
    (:attr:`ControlTasks.starts`)."""
    n, m = n_dofs, n_tasks
    n_packed = int(starts[-1])
    step_work = priority.make_work(n, int(priority.largest_level(starts, len(starts) - 1)))
    for a in step_work:
        a[...] = 0  # scratch, but the same bytes in every controller: its steps are reproducible buffer for buffer
    return ControlWork(np.zeros((6 * m, n)), np.zeros((n_packed, n)), np.zeros(n_packed), np.zeros(n_packed),
                       np.zeros(len(starts) - 1), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n),
                       np.zeros((n_frames, 3, 3)), np.zeros((n_frames, 3)), np.zeros(6 * m), np.zeros((2, m)),
                       np.zeros(n_levels + 1), np.zeros(n_levels + 1, dtype=np.bool_), np.zeros((3, 3)), np.zeros(5),
                       np.zeros(n), step_work, make_range_work(int(starts[n_levels]), n))


@njit(cache=True, _nrt=False)
def level_state(tasks, posture, q, R, p, e, err, M, costs, met):
    """Every level's state at ``q`` (n,) [rad] with world frames ``R``, ``p``: the error rows ``e`` (6m,), the tasks'
    errors ``err`` (2, m), ``costs`` (L + 1,) ``0.5 e^T W e`` per level and the posture's ``0.5 |L (q - ref)|^2``
    last, ``met`` (L + 1,) (a level is met when all its tasks are within their band; the posture never is; balance's
    are the caller's). Returns ``(converged, targets' weighted squared error, a task lags)``."""
    effector_errors(R, p, tasks.frame, tasks.position, tasks.rotation, tasks.row_weight, e, err, M)
    costs[:] = 0.0
    met[:] = True
    target = 0.0
    converged = True
    lagging = False
    for k in range(tasks.frame.shape[0]):
        c = 0.0
        for r in range(6):
            c += 0.5 * tasks.row_weight[k, r] * e[6 * k + r] * e[6 * k + r]
        lv = tasks.level[k]
        costs[lv] += c
        target += c
        for a in range(2):
            if err[a, k] > tasks.band[a, k]:
                met[lv] = False
            if err[a, k] > tasks.tolerance[a, k]:
                converged = False
            if err[a, k] > tasks.lag[a, k]:
                lagging = True
    met[met.shape[0] - 1] = False
    costs[costs.shape[0] - 1] = 0.5 * posture_squares(posture.factor, posture.reference, q)
    return converged, target, lagging


@njit(cache=True, _nrt=False, fastmath=SUMS)  # vectorised sums; it calls no kernel that would inherit them
def posture_squares(L, ref, q):
    """``|L (q - ref)|^2`` (``L`` (k, n), ``ref``, ``q`` (n,) [rad]): twice the posture's cost."""
    g2 = 0.0
    for i in range(L.shape[0]):
        li = L[i]
        s = 0.0
        for d in range(q.shape[0]):
            s += li[d] * (q[d] - ref[d])
        g2 += s * s
    return g2


@njit(cache=True, _nrt=False)
def report_errors(R, p, tasks, index, e, err, M, out):
    """The tasks' errors at frames ``R``, ``p`` (:func:`~gsik.kernels.kinematics.effector_errors` into ``e``,
    ``err``) as a result reports them: ``out`` (2, k) position [m] and orientation [rad] errors of task ``index[j]``
    in column ``j``, 0 where ``index[j]`` is -1 (no target) or the task does not use that row."""
    effector_errors(R, p, tasks.frame, tasks.position, tasks.rotation, tasks.row_weight, e, err, M)
    for j in range(index.shape[0]):
        k = index[j]
        out[0, j] = err[0, k] if k >= 0 and tasks.row_weight[k, 0] > 0.0 else 0.0
        out[1, j] = err[1, k] if k >= 0 and tasks.row_weight[k, 3] > 0.0 else 0.0


@njit(cache=True, _nrt=False)
def linearise(task_model, tasks, posture, q, R, p, e, wk):
    """The levels linearised at ``q`` (n,) [rad] (frames ``R``, ``p``; error rows ``e`` (6m,)) packed into ``wk.rows``,
    ``wk.errors``, ``wk.weights``: each target row's Jacobian row, error and weight, then the posture's rows ``L`` and
    errors ``L (reference - q)`` (weight 1). Balance's rows (``packed_row`` -1) are left for the caller."""
    jacobian(task_model, R, p, wk.J)
    n = q.shape[0]
    mt = tasks.packed_row.shape[0]
    for i in range(mt):
        r = tasks.packed_row[i]
        if r < 0:
            continue
        for d in range(n):
            wk.rows[i, d] = wk.J[r, d]
        wk.errors[i] = e[r]
        wk.weights[i] = tasks.packed_weight[i]
    posture_rows_into(posture.factor, posture.reference, posture.gain[0], q, mt, wk.rows, wk.errors, wk.weights)


@njit(cache=True, _nrt=False, fastmath=SUMS)  # vectorised sums; it calls no kernel that would inherit them
def posture_rows_into(L, ref, gain, q, at, rows, errors, weights):
    """The posture's rows ``L`` (k, n) into ``rows`` from row ``at``, their errors ``gain L (ref - q)`` and weights
    1."""
    for i in range(L.shape[0]):
        li, row = L[i], rows[at + i]
        s = 0.0
        for d in range(q.shape[0]):
            s += li[d] * (ref[d] - q[d])
        for d in range(q.shape[0]):
            row[d] = li[d]
        errors[at + i] = gain * s
        weights[at + i] = 1.0


@njit(cache=True, _nrt=False)
def box(q, q_from, lower, upper, max_step, lo, hi):
    """Bounds ``lo <= dq <= hi`` (n,) of a step from ``q_from``: the limits, and the step limit ``max_step`` [rad]
    (0: none) counted from ``q``; always ``lo <= 0 <= hi``."""
    for d in range(q.shape[0]):
        a = lower[d] - q_from[d]
        b = upper[d] - q_from[d]
        if max_step > 0.0:
            a = max(a, q[d] - q_from[d] - max_step)
            b = min(b, q[d] - q_from[d] + max_step)
        lo[d] = min(a, 0.0)
        hi[d] = max(b, 0.0)


@njit(cache=True, _nrt=False)
def dampings_into(costs, near, lam, base, posture_on, out):
    """Each packed level's damping into ``out``: ``min(base, lam)`` for a level whose cost (``costs`` (L + 1,)) is
    within ``near`` (L,), ``lam`` for the others; the posture's ``base * max(1, lam / base)``."""
    for k in range(near.shape[0]):
        out[k] = min(base, lam) if costs[k] <= near[k] else lam
    if posture_on:
        out[near.shape[0]] = base * max(1.0, lam / base)


@njit(cache=True, _nrt=False)
def trial(fk, tasks, posture, root, W, lower, upper, q, dq, scale, wk):
    """The trial ``wk.q = clip(q + scale dq, lower, upper)``: its frames, errors and level state into ``wk``
    (``wk.out``'s :data:`O_CONVERGED`, :data:`O_TARGET_COST` and :data:`O_LAGGING`). ``fk``: the whole skeleton's
    :class:`~gsik.kernels.KinematicModel`, ``root`` its pinned frame at ``W`` (4, 4)."""
    for d in range(q.shape[0]):
        wk.q[d] = min(max(q[d] + scale * dq[d], lower[d]), upper[d])
    frames_into(fk.frame_parent, fk.frame_offset, fk.frame_rotation, fk.frame_axis, fk.frame_dof, wk.q, root, W,
                wk.R, wk.p)
    converged, target, lagging = level_state(tasks, posture, wk.q, wk.R, wk.p, wk.e, wk.err, wk.M, wk.costs, wk.met)
    wk.out[O_CONVERGED] = 1.0 if converged else 0.0
    wk.out[O_TARGET_COST] = target
    wk.out[O_LAGGING] = 1.0 if lagging else 0.0


@njit(cache=True, _nrt=False)
def step_trial(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e, costs, lam, base, near,
               tols, wk):
    """One prioritised step from ``q`` (n,) [rad] (frames ``R``, ``p``, error rows ``e``, level ``costs`` there) and
    its trial, into ``wk``: the levels linearised and packed (:func:`linearise`), each one's damping
    (:func:`dampings_into`, the adaptive ``lam`` and the ``base`` damping, ``near`` (L,)), the box (:func:`box`),
    the step ``wk.dq`` (:func:`gsik.kernels.range_space.prioritized_step_range_in`: every level by the normal
    equations where that is exact, else :func:`gsik.kernels.posture_level.prioritized_step_posture_in`, a full
    posture's level by its normal equations; the posture's share bounded by ``posture.share``; ``tols``: its rank,
    box and relative box tolerances,
    a tuple) and the trial at ``q + dq`` (:func:`trial`). ``wk.out[O_STATUS]``: the step kernel's status (no trial
    when not OK), ``wk.out[O_SHARE]`` the posture share's largest component before its bound."""
    linearise(task_model, tasks, posture, q, R, p, e, wk)
    posture_on = posture.factor.shape[0] > 0
    dampings_into(costs, near, lam, base, posture_on, wk.dampings)
    box(q, q, lower, upper, max_step, wk.lo, wk.hi)
    rank_tol, box_tol, box_rel_tol = tols
    status, share = prioritized_step_range_in(wk.range_work, wk.priority, wk.rows, wk.errors, wk.weights, tasks.starts,
                                              wk.dampings, wk.lo, wk.hi, rank_tol, box_tol, box_rel_tol,
                                              posture.normal, posture.share[0], wk.dq, wk.below)
    wk.out[O_STATUS] = status
    wk.out[O_SHARE] = share
    if status == priority.OK:
        trial(fk, tasks, posture, root, W, lower, upper, q, wk.dq, 1.0, wk)
