"""The posture level of the strict-priority step by its normal equations: a square posture factor at a fraction of the
pivoted QR's cost.

The posture is the last level, ``|L (q + dq - reference)|^2`` with a factor ``L`` (n, n) fixed for a controller
(``P = L^T L``, the precision). In the free basis ``Z`` the levels above leave (``rz`` directions, the rows of
:class:`gsik.kernels.priority.Work`'s ``Zt``), its damped least-squares step from ``dq`` is

    ``z = (Z^T P Z + damping I)^-1 Z^T (g - P dq)``, ``g = L^T e`` (``e`` the level's errors),

where :func:`gsik.kernels.priority.prioritized_step` runs a pivoted QR of ``(L Z)^T`` (rz, n) and a ``k x k``
Cholesky solve. For a well-conditioned ``L`` (:func:`normal_matrix`) that QR always finds full rank: each of its
pivots is at least ``sigma_min(L) / sqrt(n)`` (``sigma_min(L Z) >= sigma_min(L)``; a pivot is the largest column
norm of a block whose largest singular value is at least ``sigma_min``), far above the rank tolerance times the
largest row norm (at most ``sigma_max(L)``). Both are then the same step up to rounding. Here:

- ``Z^T P`` (rz, n) is one blocked product over contiguous rows (four directions a pass: each row of ``P`` loaded
  once per four), ``N = Z^T P Z`` (rz, rz) its dot products with the basis' rows: no level weighing, no product with
  the factor's transpose, no pivoted QR;
- when a DOF locks at the box, the basis is turned so that only its first direction moves that DOF
  (:func:`gsik.kernels.null_basis.without_dof`) and that direction dropped: ``Z^T P`` and ``N`` are turned by the
  same reflection in ``O(rz n)`` and ``O(rz^2)`` and the level re-solved by an ``rz x rz`` Cholesky factorisation, not
  factored from scratch.

The posture's share of the step (the step minus the target levels' own) is bounded on its own where ``bound`` > 0:
a trust region for the learned prior's move. That move is flat for the target levels only to first order: a long
one breaks a met target level by its second order, the trial is refused at that level and a restoring step (a
second prioritised solve at the trial pose, :func:`gsik.kernels.accept.restore`) brings it back. With the bundled
prior on bench_drag's studio drag the posture's move reached the whole step bound (``max_step``, 0.25 rad) in 174 of
300 frames, where the moves of the trials accepted at once were ~0.07 rad. The share ``s`` lies in the target
levels' free basis, so scaling it (:func:`bound_share`) leaves their linearised errors alone, and the step stays in
the (convex) box between two steps inside it; a share within the bound leaves the step bit for bit the unbounded one.
A step whose share was bounded has not settled (the posture has further to go than one step takes): the stall
window does not count it as creeping (:func:`gsik.kernels.accept.commit`), nor ``Solver.step()`` as converged.

The level's kernels allocate nothing and are compiled without numba's reference counting (``_nrt=False``, as in
:mod:`gsik.kernels.kinematics`): a controller steps in its own buffers (:func:`prioritized_step_posture_in`);
:func:`prioritized_step_posture` allocates them and says ``_nrt=True`` (see :mod:`gsik.kernels.priority`).
"""

from __future__ import annotations

import numpy as np

from gsik._jit import njit
from gsik.kernels import priority
from gsik.kernels.null_basis import identity_into, reflect_rows, without_dof
from gsik.kernels.pgs import _cholesky_solve
from gsik.kernels.rows import axpy1, dot, dot1
from gsik.kernels.step import copy_into

#: A posture factor is solved by its normal equations when its precision ``P = L^T L`` minus this fraction of its
#: trace is still positive definite: its condition number is then below ``n / 1e-8`` and ``sigma_min(L)`` above
#: ``1e-4`` times ``sqrt(trace P)`` (at least the largest row norm), so the pivoted QR's pivots are at least
#: ``1e-4 / sqrt(n)`` of that row norm, five orders above :data:`gsik.priority.RANK_TOLERANCE`, and the normal
#: equations lose no more than ~1e-8 of the step to rounding.
WELL_CONDITIONED = 1e-8
#: The bound [rad] on the posture's share of a step with a full posture factor (the learned prior:
#: :attr:`gsik.kernels.control.PostureRows.share`; never a diagonal one's, nor in a solve()'s settling steps); 0:
#: none. On bench_drag's studio drag (one step a frame) it took restoring steps 174 -> 0 and the step 3.0x -> 1.9x a
#: plain one (README, issue 20).
POSTURE_SHARE = 0.07


def normal_matrix(factor: np.ndarray) -> np.ndarray:
    """``P = L^T L`` (n, n) of a posture factor ``L`` (k, n) whose level :func:`prioritized_step_posture` solves by
    its normal equations: a square, finite, well-conditioned one (:data:`WELL_CONDITIONED`, one Cholesky test, no
    decomposition: a conditioned prior sets a posture a frame), full (the learned prior) or diagonal (pins' start
    pose, the retargeter's rest: ``Z^T P`` is then one scaling, :func:`_basis_scaled`; on bench_drag's pins the level
    took ~15 µs by the pivoted QR); else (0, n): the pivoted QR's level (a rank-deficient one needs the QR's rank)."""
    L = np.asarray(factor, dtype=float)
    n = L.shape[1]
    none = np.zeros((0, n))
    if L.shape[0] != n or n == 0 or not np.all(np.isfinite(L)):
        return none
    P = np.ascontiguousarray(L.T @ L)
    try:
        np.linalg.cholesky(P - (WELL_CONDITIONED * np.trace(P)) * np.eye(n))
    except np.linalg.LinAlgError:
        return none
    return P


def is_full(normal: np.ndarray) -> bool:
    """True if a :func:`normal_matrix` ``normal`` (n, n) is given and not diagonal: a learned prior's, whose share of a
    step is bounded (:data:`POSTURE_SHARE`); a diagonal posture's (pins, the retargeter) never is."""
    return normal.shape[0] > 0 and not is_diagonal(normal)  # the step's own test


@njit(cache=True, _nrt=True)
def prioritized_step_posture(rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, normal,
                             bound, dq, below):
    """:func:`prioritized_step_posture_in` in buffers of its own (allocated: for a caller that steps once)."""
    wk = priority.make_work(lo.shape[0], priority.largest_level(starts, dampings.shape[0]))
    return prioritized_step_posture_in(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol,
                                       box_rel_tol, normal, bound, dq, below)


@njit(cache=True, _nrt=False)
def prioritized_step_posture_in(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol,
                                normal, bound, dq, below):
    """:func:`gsik.kernels.priority.prioritized_step_in` whose last level is a posture with the normal matrix
    ``normal`` (n, n) (:func:`normal_matrix` of its rows, weights 1), solved by its normal equations, its share of the
    step bounded by ``bound`` [rad] (> 0; else not bounded: :func:`bound_share`); ``normal`` (0, n): the pivoted
    QR's level, bit for bit :func:`~gsik.kernels.priority.prioritized_step_in`, never bounded. Same arguments before
    ``bound`` (``wk``: a :class:`~gsik.kernels.priority.Work` for every level, the posture's ``n`` rows too), same
    ``dq`` (n,) [rad] (to rounding); ``below`` (n,): scratch, the target levels' own step where the share is bounded.
    Returns ``(status, largest component of the share before bounding [rad], 0 when not bounded)``."""
    posture = dampings.shape[0] - 1
    if normal.shape[0] == 0 or posture < 0 or starts[posture + 1] - starts[posture] != normal.shape[0]:
        return priority.prioritized_step_in(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol,
                                            box_rel_tol, dq), 0.0
    last = priority.begin(wk, starts, dampings, dq)
    status, z0, rz, identity = priority.solve_levels(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol,
                                                     box_tol, box_rel_tol, posture, last, dq)
    if status != priority.OK:
        return status, 0.0
    bounded = bound > 0.0
    if bounded:
        copy_into(below, dq)
    if rz > 0:
        if identity:
            identity_into(wk.Zt, lo.shape[0])
        _posture_level(wk, rows, errors, starts[posture], starts[posture + 1], normal, z0, rz, dq, lo, hi,
                       dampings[posture], box_tol, box_rel_tol)
    priority.clip(dq, lo, hi)
    if not bounded:
        return priority.OK, 0.0
    return priority.OK, bound_share(dq, below, lo, hi, bound)


@njit(cache=True, _nrt=False)
def bound_share(dq, below, lo, hi, bound):
    """The posture's share ``s = dq - below`` (the step minus the target levels' step ``below``, both (n,) [rad])
    scaled in place to at most ``bound`` [rad] in its largest component: ``dq = below + t s``,
    ``t = min(1, bound / max|s|)``, clipped into ``lo <= dq <= hi`` (rounding only: both ends are in the box).
    Returns ``max|s|`` before scaling [rad]."""
    n = dq.shape[0]
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
    return largest


@njit(cache=True, _nrt=False)
def _posture_level(wk, rows, errors, start, stop, P, z0, rz, dq, lo, hi, damping, box_tol, box_rel_tol):
    """The posture level's active-set loop on ``dq`` (and ``wk.locked``) in the free basis ``wk.Zt[z0:z0 + rz]``.

    Buffers: ``g = L^T e`` in ``wk.beta``, ``Z^T P`` in ``wk.AT0[:rz, :n]`` (its row ``c`` for the basis' row
    ``z0 + c``), ``N`` in ``wk.V``, the damped matrix in ``wk.G``, the right-hand side and solution in ``wk.y``."""
    n = dq.shape[0]
    g, ZP, N = wk.beta, wk.AT0, wk.V
    g[:] = 0.0
    for i in range(start, stop):
        if errors[i] != 0.0:
            axpy1(g, errors[i], rows, i, 0, n)
    if is_diagonal(P):
        _basis_scaled(wk.Zt, z0, rz, P, ZP)
    else:
        _basis_times(wk.Zt, z0, rz, P, ZP)
    _gram(ZP, wk.Zt, z0, rz, N)
    while True:
        priority._into_box(dq, lo, hi, box_tol)
        if not _damped_solve(wk, g, ZP, N, z0, rz, dq, damping):
            return  # not numerically positive definite (only without damping, rounding at a singular P): no step
        step = wk.step
        step[:] = 0.0
        for c in range(rz):
            axpy1(step, wk.y[c], wk.Zt, z0 + c, 0, n)
        for d in range(n):
            if wk.locked[d]:
                step[d] = 0.0
        alpha, blocking = priority._largest_fraction(dq, step, lo, hi, box_tol, box_rel_tol)
        if blocking < 0:
            for d in range(n):
                dq[d] += step[d]
            return
        for d in range(n):
            dq[d] += alpha * step[d]
        dq[blocking] = hi[blocking] if step[blocking] > 0.0 else lo[blocking]
        wk.locked[blocking] = True
        scale = without_dof(wk.Zt, z0, rz, blocking, wk.u, wk.zw)
        if scale > 0.0:
            reflect_rows(ZP, n, rz, wk.u, scale, wk.w)
            _turn(N, rz, wk.u, scale, wk.z)
            z0 += 1
            rz -= 1
        if rz == 0:
            return


@njit(cache=True, _nrt=False)
def _basis_times(Zt, z0, rz, P, ZP):
    """``ZP[:rz, :n] = Zt[z0:z0 + rz] @ P``: four rows a pass, each a sweep ``ZP[c] += Zt[z0 + c, d] * P[d]`` over
    ``d`` in order, skipping the DOFs the pass' directions do not move (the basis' rows are sparse: the directions no
    level above sees are unit rows, the others move only the DOFs of the chains those levels see)."""
    n = P.shape[0]
    c = 0
    while c + 4 <= rz:
        a0, a1, a2, a3 = ZP[c, :n], ZP[c + 1, :n], ZP[c + 2, :n], ZP[c + 3, :n]
        a0[:] = 0.0
        a1[:] = 0.0
        a2[:] = 0.0
        a3[:] = 0.0
        for d in range(n):
            z_0, z_1, z_2, z_3 = Zt[z0 + c, d], Zt[z0 + c + 1, d], Zt[z0 + c + 2, d], Zt[z0 + c + 3, d]
            if z_0 == 0.0 and z_1 == 0.0 and z_2 == 0.0 and z_3 == 0.0:
                continue  # a DOF none of the four directions moves (zeros add exactly nothing)
            row = P[d]
            for j in range(n):
                r = row[j]
                a0[j] += z_0 * r
                a1[j] += z_1 * r
                a2[j] += z_2 * r
                a3[j] += z_3 * r
        c += 4
    for c in range(c, rz):
        a = ZP[c, :n]
        a[:] = 0.0
        for d in range(n):
            zc = Zt[z0 + c, d]
            if zc != 0.0:
                row = P[d]
                for j in range(n):
                    a[j] += zc * row[j]


@njit(cache=True, _nrt=False)
def is_diagonal(P):
    """True if ``P`` (n, n) is zero off its diagonal (a full one says so at its first nonzero off it)."""
    n = P.shape[0]
    for d in range(n):
        row = P[d]
        for j in range(n):
            if j != d and row[j] != 0.0:
                return False
    return True


@njit(cache=True, _nrt=False)
def _basis_scaled(Zt, z0, rz, P, ZP):
    """:func:`_basis_times` for a diagonal ``P``: ``ZP[c, j] = Zt[z0 + c, j] P[j, j]``, the same numbers (the other
    terms of its sums are zeros)."""
    n = P.shape[0]
    for c in range(rz):
        a, z = ZP[c, :n], Zt[z0 + c]
        for j in range(n):
            a[j] = z[j] * P[j, j]


@njit(cache=True, _nrt=False)
def _gram(ZP, Zt, z0, rz, N):
    """``N[:rz, :rz] = ZP[:rz] @ Zt[z0:z0 + rz]^T`` (``Z^T P Z``), symmetric: the lower triangle computed, mirrored."""
    n = Zt.shape[1]
    for c in range(rz):
        for c2 in range(c + 1):
            v = dot(ZP, c, Zt, z0 + c2, 0, n)
            N[c, c2] = v
            N[c2, c] = v


@njit(cache=True, _nrt=False)
def _damped_solve(wk, g, ZP, N, z0, rz, dq, damping):
    """``wk.y`` (rz,) solving ``(N + damping I) y = Z^T g - (Z^T P) dq``; False if that matrix is not numerically
    positive definite."""
    n = dq.shape[0]
    G, y = wk.G, wk.y
    for c in range(rz):
        y[c] = dot1(wk.Zt, z0 + c, g, 0, n) - dot1(ZP, c, dq, 0, n)
        for c2 in range(c + 1):
            G[c, c2] = N[c, c2]
        G[c, c] += damping
    return _cholesky_solve(G, y, rz)


@njit(cache=True, _nrt=False)
def _turn(N, rz, u, scale, w):
    """``N[:rz - 1, :rz - 1] = (H N H)[1:, 1:]`` with ``H = I - scale u u^T`` (``u`` (rz,)): ``Z^T P Z`` after
    :func:`gsik.kernels.null_basis.without_dof` turned the basis by ``H`` and dropped its first direction. ``w``:
    (rz,) scratch."""
    uw = 0.0
    for c in range(rz):
        s = 0.0
        for c2 in range(rz):
            s += N[c, c2] * u[c2]
        w[c] = s
        uw += u[c] * s
    # H N H = N - u v^T - v u^T with v = scale N u - scale^2 (u^T N u) / 2 u
    for c in range(rz):
        w[c] = scale * w[c] - 0.5 * scale * scale * uw * u[c]
    for c in range(1, rz):
        for c2 in range(1, rz):
            N[c - 1, c2 - 1] = N[c, c2] - u[c] * w[c2] - w[c] * u[c2]
