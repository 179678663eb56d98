"""The strict-priority step by its normal equations where that is exact: every target level of full rank in the
directions the levels above leave free, and no DOF meeting its bound.

:mod:`gsik.kernels.priority` solves each level by a pivoted QR of its rows in the free basis ``Z`` and turns ``Z``
below it; :mod:`gsik.kernels.posture_level` then solves the posture in that basis. Where every target level has full
row rank there, the same steps follow from the Gram matrix ``K = C C^T`` of the weighted target rows ``C`` (the
levels stacked, (M, n)) alone:

- level ``l`` (rows ``C_l``, those above ``C_a``): the Schur complement ``S_l = C_l N_l C_l^T`` of ``K``'s block
  Cholesky factor is ``B B^T`` with ``B = C_l N_l`` (``N_l``: the projector onto the free directions), so the damped
  step ``B^T (S_l + damping I)^-1 r_l`` (``r_l = e_l - C_l dq``) is ``C_l^T y - C_a^T K_a^-1 K_al y``: the QR's step
  (both minimise ``|B u - r|^2 + damping |u|^2`` over the free directions), the next level's ``N`` the complement of
  all rows so far;
- the posture (``P = L^T L``, :func:`gsik.kernels.posture_level.normal_matrix`): ``u = H^-1 (b - C^T lam)``,
  ``C H^-1 C^T lam = C H^-1 b``, ``H = P + damping I``, ``b = L^T e - P dq``: the minimiser of the level's damped
  quadratic with ``C u = 0`` (``Z``'s orthonormal basis leaves ``|u| = |z|``).

Dense dot products over rows of ``n`` and weighted sums of rows (:func:`gsik.kernels.vector.combine_rows`, its
sums in registers), no reflections: on bench_drag's poses the step's kernel takes 5.3 / 7.3 µs against the QR
path's 13.0 / 13.3 (pins, the studio's prior; ``benchmarks/bench_priority_pieces.py``). The normal equations
square the rows' condition number, so they are taken only where it is provably small (:data:`CONDITIONED`).
:func:`range_space_step` returns False, ``dq`` then undefined, and the caller steps by the QR path (the same
step, rank decisions and active set its own) where:

- a level's Cholesky pivot falls below :data:`RANK_MARGIN` times the QR's rank tolerance (it may be
  rank-deficient: the QR decides the rank), or the target rows are not :data:`CONDITIONED`;
- a target level's step would meet the box (a DOF at its bound: the QR's active set locks it), or the posture's
  would lock more than :data:`~gsik.kernels.range_posture.LOCKS` DOFs (fewer are locked here as the QR locks them:
  :func:`~gsik.kernels.range_posture.posture_box`);
- a number is not finite;
- the posture's matrix or damping is not the last call's (:func:`~gsik.kernels.range_posture.posture_kind`: a
  full one's damped inverse is made once it holds and kept while it does), or a full one's share is not bounded:
  a solve()'s settle, whose steps swap the targets' curvature into the level, a matrix a step.

The kernels allocate nothing (``_nrt=False``, as in :mod:`gsik.kernels.kinematics`). Those that only sum (calling
nothing outside this module but inlined helpers) sum as :func:`gsik.kernels.rows.dot_sum`
(:data:`~gsik.kernels.rows.SUMS`: reassociated, so vectorised; the last bits follow the machine's vector width, the
step is the same to rounding). The others keep exact IEEE order: numba compiles a callee that sets no ``fastmath``
with its caller's, and a kernel shared with the QR or plain path must not change with whoever compiled it first.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik._jit import njit
from gsik.kernels import priority, range_posture
from gsik.kernels.posture_level import bound_share, prioritized_step_posture_in
from gsik.kernels.range_posture import DIAGONAL, LOCKS, S_DECLINED, S_INVERTED, S_TAKEN, UNSEEN
from gsik.kernels.rows import SUMS, dot_sum
from gsik.kernels.step import copy_into
from gsik.kernels.triangular import backward, factor, forward
from gsik.kernels.vector import combine_rows, subtract_rows

__all__ = ["CONDITIONED", "RANK_MARGIN", "S_DECLINED", "S_INVERTED", "S_TAKEN", "RangeWork", "make_range_work",
           "prioritized_step_range_in", "range_space_step"]

#: A target level is solved here only when every pivot of its Cholesky factor is above this many times the QR's
#: pivot tolerance (``rank_tol`` times its largest row norm): well inside full rank, where the QR finds it too.
RANK_MARGIN = 1e3
#: And only when the target rows' smallest singular value is provably at least this fraction of their largest row
#: norm ``s`` (``1 / trace(K^-1) >= (CONDITIONED s)^2``, ``K = C C^T``; the bound is within a factor of the rows'
#: count of ``lambda_min(K)``): then ``K``'s condition number is at most ``M / CONDITIONED^2`` and the normal
#: equations lose at most that times the rounding (the QR its square root): ~1e-10 of the step at M = 18.
CONDITIONED = 1e-3


class RangeWork(NamedTuple):
    """:func:`range_space_step`'s buffers, for ``M`` target rows and ``n`` DOFs (:func:`make_range_work`).

    Attributes:
        C: (M + LOCKS, n) the weighted target rows, level by level, then the posture's locked DOFs' unit rows.
        ce: (M,) the target rows' weighted errors.
        F: (M, M) the Gram matrix's block Cholesky factor (lower; row ``i`` to column ``i``).
        D: (M, M) a level's damped Schur complement, factored. Y: (M + LOCKS, n) ``C H^-1`` (the posture's level).
        G: (M + LOCKS, M + LOCKS) ``C H^-1 C^T``, factored. y: (M + LOCKS,). t: (M,). step, hb: (n,).
        Hf: (n, n) scratch (a diagonal ``H^-1`` in
        its first row; ``H``'s Cholesky factor while inverting it).
        Hinv: (n, n) ``H^-1 = (P + damping I)^-1`` of a full posture, kept while ``P`` and the damping stay.
        key: (n, n) the ``P`` last seen. state: (5,)
        :data:`gsik.kernels.range_posture.S_DAMPING` ... locked: (LOCKS,) the DOFs the posture's level locked, in
        order (:data:`~gsik.kernels.range_posture.LOCKS`).
    """

    C: np.ndarray
    ce: np.ndarray
    F: np.ndarray
    D: np.ndarray
    Y: np.ndarray
    G: np.ndarray
    y: np.ndarray
    t: np.ndarray
    step: np.ndarray
    hb: np.ndarray
    Hf: np.ndarray
    Hinv: np.ndarray
    key: np.ndarray
    state: np.ndarray
    locked: np.ndarray




def make_range_work(n_rows: int, n_dofs: int) -> RangeWork:
    """A :class:`RangeWork` for ``n_rows`` target rows and ``n_dofs`` DOFs (zeros; no posture seen)."""
    m, n, h = n_rows, n_dofs, n_rows + LOCKS
    return RangeWork(np.zeros((h, n)), np.zeros(m), np.zeros((m, m)), np.zeros((m, m)), np.zeros((h, n)),
                     np.zeros((h, h)), np.zeros(h), np.zeros(m), np.zeros(n), np.zeros(n), np.zeros((n, n)),
                     np.zeros((n, n)), np.full((n, n), np.nan), np.array([np.nan, UNSEEN, 0.0, 0.0, 0.0]),
                     np.zeros(LOCKS, dtype=np.int64))


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _weigh(rows, errors, weights, start, stop, C, ce, at):
    """The level's rows ``start:stop`` weighted into ``C``, ``ce`` from row ``at``; returns ``(rows written, their
    largest norm)`` (rows of weight 0 left out: the QR ranks them out)."""
    n = rows.shape[1]
    scale = 0.0
    out = at
    for i in range(start, stop):
        if weights[i] <= 0.0:
            continue
        sw = math.sqrt(weights[i])
        s = 0.0
        for d in range(n):
            v = sw * rows[i, d]
            C[out, d] = v
            s += v * v
        ce[out] = sw * errors[i]
        scale = max(scale, s)
        out += 1
    return out, math.sqrt(scale)


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _level(rw, a, b, dq, damping, pivot_least):
    """Level rows ``a:b`` of ``rw.C`` below rows ``0:a``: its block of the Gram factor ``rw.F`` and its damped step
    into ``rw.step`` (n,); False if its Schur complement is not well inside full rank."""
    C, F, D, y = rw.C, rw.F, rw.D, rw.y
    for i in range(a, b):
        for j in range(i + 1):
            F[i, j] = dot_sum(C[i], C[j])
    # F[a:b, :a] = K[a:b, :a] F[:a, :a]^-T, column by column: the rows' substitutions are independent, so their
    # divisions overlap (row by row, each waited on the last: the same numbers, ~0.1 µs a row slower)
    for j in range(a):
        for i in range(a, b):
            F[i, j] = (F[i, j] - dot_sum(F[i, :j], F[j, :j])) / F[j, j]
    for i in range(a, b):  # the Schur complement, and its damped copy
        for j in range(a, i + 1):
            s = F[i, j] - dot_sum(F[i, :a], F[j, :a])
            F[i, j] = s
            D[i, j] = s
        D[i, i] += damping
    if not factor(F, a, b, pivot_least) or not factor(D, a, b, 0.0):
        return False
    for i in range(a, b):
        y[i] = rw.ce[i] - dot_sum(C[i], dq)
    forward(D, a, b, y)
    backward(D, a, b, y)
    # u = C_l^T y - C_a^T K_a^-1 K_al y; K_al y = F_a (F_la^T y): t = F_la^T y, then F_a^-T t
    t = rw.t
    for j in range(a):
        s = 0.0
        for i in range(a, b):
            s += F[i, j] * y[i]
        t[j] = s
    backward(F, 0, a, t)
    step = rw.step
    step[:] = 0.0
    combine_rows(y[a:b], C[a:b], step)
    subtract_rows(t, C, a, step)
    return True


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _conditioned(F, m, X, least):
    """True if ``1 / trace(K^-1) >= least^2`` for ``K = F F^T`` (``F`` (m, m) lower triangular, ``X`` (m, m)
    scratch): ``trace(K^-1) = |F^-1|_F^2`` bounds ``1 / lambda_min(K)`` from above. ``F^-1`` is made row by row,
    ``X[i] = (e_i - F[i, :i] X[:i]) / F[i, i]`` (a weighted sum of rows, :func:`combine_rows`; the columns'
    substitutions are chains of dependent short sums). The sum is negated after it is made, not as it is made: both
    round alike."""
    total = 0.0
    for i in range(m):
        xi = X[i]
        xi[:m] = 0.0
        combine_rows(F[i, :i], X[:i], xi[:i])
        r = 1.0 / F[i, i]
        xi[i] = r
        total += r * r
        for c in range(i):
            xi[c] = -xi[c] * r
            total += xi[c] * xi[c]
    return total * least * least <= 1.0


@njit(cache=True, _nrt=False)
def _take(dq, step, lo, hi, box_tol, box_rel_tol):
    """``dq += step`` if the QR path would take it whole (:func:`gsik.kernels.priority._largest_fraction` finds no
    DOF blocking); False (``dq`` unchanged) if a DOF would block."""
    if priority._largest_fraction(dq, step, lo, hi, box_tol, box_rel_tol)[1] >= 0:
        return False
    for d in range(dq.shape[0]):
        dq[d] += step[d]
    return True


@njit(cache=True, _nrt=False)
def range_space_step(rw, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, normal,
                     bound, dq, below):
    """:func:`gsik.kernels.posture_level.prioritized_step_posture_in`'s step before its share bound (the same
    arguments; ``normal`` (n, n), the posture the last level; a full one is inverted only where its share is
    bounded, ``bound`` > 0) by the normal equations, into ``dq`` (n,) [rad], the target levels' own step into
    ``below`` (n,); False where they do not give it (see the module's docstring: ``dq`` and ``below`` are then
    undefined)."""
    posture = dampings.shape[0] - 1
    # A full posture's share is bounded in a drag's steps, never in a solve()'s settle, whose steps swap the targets'
    # curvature into its level (a matrix a step): inverted only for the former.
    kind = range_posture.posture_kind(rw, normal, dampings[posture], bound > 0.0)
    if kind == UNSEEN or starts[posture] > rw.F.shape[0]:
        return False
    dq[:] = 0.0
    m = 0
    top = 0.0  # the largest row norm
    for lv in range(posture):
        a = m
        m, scale = _weigh(rows, errors, weights, starts[lv], starts[lv + 1], rw.C, rw.ce, a)
        if m == a:
            continue
        top = max(top, scale)
        if not math.isfinite(scale) or scale == 0.0:
            return False
        priority._into_box(dq, lo, hi, box_tol)
        if not (_level(rw, a, m, dq, dampings[lv], RANK_MARGIN * rank_tol * scale)
                and _take(dq, rw.step, lo, hi, box_tol, box_rel_tol)):
            return False
    if not _conditioned(rw.F, m, rw.D, CONDITIONED * top):  # D: free once the levels are solved
        return False
    copy_into(below, dq)
    priority._into_box(dq, lo, hi, box_tol)
    start, stop = starts[posture], starts[posture + 1]
    rp = range_posture
    if kind == DIAGONAL:
        done = rp.posture_diagonal(rw, m, rows, errors, start, stop, normal, dampings[posture], dq)
    else:
        done = rp.posture_full(rw, m, rows, errors, start, stop, normal, dq)
    if not done:
        return False
    # a step that meets the box as the QR's active set takes it: DOFs that block it locked (a locking not well inside
    # full rank, or more than LOCKS: the QR's)
    if not (_take(dq, rw.step, lo, hi, box_tol, box_rel_tol)
            or rp.posture_box(rw, kind, m, rows, errors, start, stop, normal, dq, lo, hi, box_tol, box_rel_tol,
                              RANK_MARGIN * rank_tol)):
        return False
    priority.clip(dq, lo, hi)
    return True


@njit(cache=True, _nrt=False)
def prioritized_step_range_in(rw, wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol,
                              box_rel_tol, normal, bound, dq, below):
    """:func:`gsik.kernels.posture_level.prioritized_step_posture_in` (same arguments after ``rw``, a
    :class:`RangeWork` for the target rows), by :func:`range_space_step` where it gives the step (the same step to
    rounding), else by the QR path. Returns ``(status, largest component of the posture's share before bounding
    [rad], 0 when not bounded)``."""
    posture = dampings.shape[0] - 1
    n = lo.shape[0]
    if posture >= 0 and normal.shape[0] == n and starts[posture + 1] - starts[posture] == n \
            and range_space_step(rw, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol,
                                 normal, bound, dq, below):
        rw.state[S_TAKEN] += 1.0
        if bound > 0.0:
            return priority.OK, bound_share(dq, below, lo, hi, bound)
        return priority.OK, 0.0
    rw.state[S_DECLINED] += 1.0
    return prioritized_step_posture_in(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol,
                                       box_rel_tol, normal, bound, dq, below)
