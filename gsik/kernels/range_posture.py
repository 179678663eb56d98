"""The posture's level of the range-space step (:mod:`gsik.kernels.range_space`): the last level, ``P = L^T L``
(:func:`gsik.kernels.posture_level.normal_matrix`), below the target rows ``C`` it holds.

Its step from ``dq`` is ``u = H^-1 (b - C^T lam)``, ``C H^-1 C^T lam = C H^-1 b``, ``H = P + damping I``,
``b = L^T e - P dq``: the minimiser of the level's damped quadratic with ``C u = 0``. ``H^-1`` is a scaling for a
diagonal ``P`` and, for a full one, inverted once ``P`` is seen twice in a row and kept while it and the damping
stay (:func:`posture_kind`). Where the step meets the box, the DOF that blocks it is locked at its bound as the QR
path's active set locks it (:func:`gsik.kernels.posture_level._posture_level`): its unit row held beside ``C`` and
the level solved again from there (:func:`posture_box`), up to :data:`LOCKS` DOFs.

The kernels allocate nothing (``_nrt=False``); those that sum do so as :func:`gsik.kernels.rows.dot_sum`
(:data:`~gsik.kernels.rows.SUMS`), calling only this module's, :mod:`gsik.kernels.triangular`'s and inlined helpers;
:func:`posture_kind` and :func:`posture_box` call the QR path's kernels and keep exact IEEE order.
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit
from gsik.kernels import priority
from gsik.kernels.posture_level import is_diagonal
from gsik.kernels.rows import SUMS, dot_sum
from gsik.kernels.triangular import backward, factor, forward
from gsik.kernels.vector import combine_rows, subtract_rows

#: Where :attr:`gsik.kernels.range_space.RangeWork.state` holds: the damping ``Hinv`` and the posture's kind were
#: made for; the kind (:data:`UNSEEN`, :data:`DIAGONAL`, :data:`FULL`); whether ``Hinv`` holds that full posture's
#: inverse (1/0); the steps :func:`~gsik.kernels.range_space.prioritized_step_range_in` made by the normal equations
#: and those it left to the QR path (counts, for benchmarks and tests).
S_DAMPING, S_KIND, S_INVERTED, S_TAKEN, S_DECLINED = range(5)
#: A posture's kind: ``key`` not seen twice in a row yet (the QR path steps: a matrix that changes every step, the
#: targets' curvature in a settle, is never inverted); diagonal (``H^-1`` a scaling); full (``Hinv`` kept).
UNSEEN, DIAGONAL, FULL = 0.0, 1.0, 2.0
#: Most DOFs the posture's level locks at the box here (each one more row held); a step that locks more is the QR's.
LOCKS = 4


@njit(cache=True, _nrt=False)
def posture_kind(rw, P, damping, invert):
    """:data:`DIAGONAL` or :data:`FULL` (``rw.Hinv`` then ``(P + damping I)^-1``) for the posture's normal matrix
    ``P`` (n, n), or :data:`UNSEEN` where ``P`` or the damping differ from the last call's (kept for the next), or a
    full ``P`` is not inverted (``invert`` False and not inverted yet; or ``P + damping I`` not positive definite):
    the QR path steps."""
    n = P.shape[0]
    st, key = rw.state, rw.key
    a, b = key.view(np.int64), P.view(np.int64)
    same = st[S_DAMPING] == damping
    for i in range(n):
        for j in range(n):
            if a[i, j] != b[i, j]:
                same = False
                key[i, j] = P[i, j]
    if not same:
        st[S_DAMPING], st[S_KIND], st[S_INVERTED] = damping, UNSEEN, 0.0
        return UNSEEN
    if st[S_KIND] == UNSEEN:
        st[S_KIND] = DIAGONAL if is_diagonal(P) else FULL
    if st[S_KIND] == FULL and st[S_INVERTED] == 0.0:
        if not (invert and _invert(rw, P, damping)):
            return UNSEEN
        st[S_INVERTED] = 1.0
    return st[S_KIND]


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _invert(rw, P, damping):
    """``rw.Hinv = (P + damping I)^-1`` (n, n), by its Cholesky factor (in ``rw.Hf``); False if not positive
    definite."""
    n = P.shape[0]
    Hf, Hinv = rw.Hf, rw.Hinv
    for i in range(n):
        for j in range(i + 1):
            Hf[i, j] = P[i, j]
        Hf[i, i] += damping
    if not factor(Hf, 0, n, 0.0):
        return False
    for c in range(n):
        col = Hinv[c]  # H^-1 e_c, stored as a row (H^-1 is symmetric)
        col[:] = 0.0
        col[c] = 1.0
        forward(Hf, 0, n, col)
        backward(Hf, 0, n, col)
    return True


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _posture_rhs(rows, errors, start, stop, P, dq, hb):
    """``hb = L^T e - P dq`` (n,): the posture level's right-hand side (its rows ``start:stop`` are ``L``, weights
    1)."""
    n = dq.shape[0]
    for d in range(n):
        hb[d] = -dot_sum(P[d], dq)
    combine_rows(errors[start:stop], rows[start:stop], hb)


@njit(cache=True, _nrt=False, fastmath=SUMS, inline="always")
def _inverse_rhs(rw, kind, rows, errors, start, stop, P, dq):
    """``rw.hb = H^-1 b`` (n,), ``b = L^T e - P dq`` (:func:`_posture_rhs`): by rows of the symmetric ``rw.Hinv``
    (:data:`FULL`), or scaled by the diagonal ``H^-1`` in ``rw.Hf[0]`` (:data:`DIAGONAL`)."""
    hb = rw.hb
    if kind == FULL:
        b = rw.step
        _posture_rhs(rows, errors, start, stop, P, dq, b)
        hb[:] = 0.0
        combine_rows(b, rw.Hinv, hb)
    else:
        h = rw.Hf[0]
        _posture_rhs(rows, errors, start, stop, P, dq, hb)
        for d in range(dq.shape[0]):
            hb[d] *= h[d]


@njit(cache=True, _nrt=False, fastmath=SUMS, inline="always")
def _held_step(rw, held, F, CH):
    """``rw.step = H^-1 b - CH^T lam`` (n,), ``F F^T lam = C H^-1 b``: the posture's step with the rows ``rw.C[:held]``
    held (``F`` (held, held): the factor of ``C H^-1 C^T``; ``CH``: ``C H^-1`` or a multiple matching ``F``)."""
    C, hb, lam, step = rw.C, rw.hb, rw.y, rw.step
    for i in range(held):
        lam[i] = dot_sum(C[i], hb)
    forward(F, 0, held, lam)
    backward(F, 0, held, lam)
    for d in range(hb.shape[0]):
        step[d] = hb[d]
    subtract_rows(lam, CH, held, step)


@njit(cache=True, _nrt=False, fastmath=SUMS)
def posture_full(rw, m, rows, errors, start, stop, P, dq):
    """The posture's step with the target rows ``rw.C[:m]`` held, ``rw.Hinv`` its damped inverse, into
    ``rw.step``; False if ``C H^-1 C^T`` is not positive definite."""
    Y, G, Hinv, C = rw.Y, rw.G, rw.Hinv, rw.C
    _inverse_rhs(rw, FULL, rows, errors, start, stop, P, dq)
    for i in range(m):  # Y = C H^-1, G = C H^-1 C^T (lower)
        yi = Y[i]
        yi[:] = 0.0
        combine_rows(C[i], Hinv, yi)
        for j in range(i + 1):
            G[i, j] = dot_sum(Y[i], C[j])
    if not factor(G, 0, m, 0.0):
        return False
    _held_step(rw, m, G, Y)
    return True


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _diagonal_gram(rw, m):
    """``rw.Y[:m] = C H^-1`` and ``rw.G`` its factored ``C H^-1 C^T`` for the diagonal ``H^-1`` in ``rw.Hf[0]``;
    False if not positive definite."""
    Y, G, C, h = rw.Y, rw.G, rw.C, rw.Hf[0]
    for i in range(m):
        yi, ci = Y[i], C[i]
        for d in range(h.shape[0]):
            yi[d] = ci[d] * h[d]
        for j in range(i + 1):
            G[i, j] = dot_sum(Y[i], C[j])
    return factor(G, 0, m, 0.0)


@njit(cache=True, _nrt=False, fastmath=SUMS)
def posture_diagonal(rw, m, rows, errors, start, stop, P, damping, dq):
    """The posture's step for a diagonal ``P`` (``H^-1`` a scaling) with the target rows ``rw.C[:m]`` held, into
    ``rw.step``; False if ``C H^-1 C^T`` is not positive definite. A uniform one's ``C H^-1 C^T`` is the Gram
    matrix's, already factored."""
    h = rw.Hf[0]  # H^-1's diagonal (n,)
    uniform = True
    for d in range(dq.shape[0]):
        h[d] = 1.0 / (P[d, d] + damping)
        uniform = uniform and P[d, d] == P[0, 0]
    _inverse_rhs(rw, DIAGONAL, rows, errors, start, stop, P, dq)
    # uniform: C H^-1 C^T = K / (P_00 + damping), lam = K^-1 C H^-1 b (H^-1 b in hb), the Gram factor's and C's
    if uniform:
        _held_step(rw, m, rw.F, rw.C)
        return True
    if not _diagonal_gram(rw, m):
        return False
    _held_step(rw, m, rw.G, rw.Y)
    return True


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _lock(rw, kind, held, d, least):
    """DOF ``d``'s unit row held beside the rows ``rw.C[:held]``: appended to ``C``, ``Y = C H^-1`` and the factor
    of ``G = C H^-1 C^T`` (its last row, as :func:`~gsik.kernels.triangular.factor` would make it); False if its
    pivot is not above ``least`` times ``sqrt(H^-1[d, d])`` (the unit row nearly in the held rows' span: the QR
    decides)."""
    C, Y, G = rw.C, rw.Y, rw.G
    C[held] = 0.0
    C[held, d] = 1.0
    yl = Y[held]  # H^-1 e_d: a row of the symmetric H^-1, or the diagonal's entry
    if kind == FULL:
        for c in range(yl.shape[0]):
            yl[c] = rw.Hinv[d, c]
    else:
        yl[:] = 0.0
        yl[d] = rw.Hf[0, d]
    for j in range(held + 1):
        G[held, j] = dot_sum(Y[held], C[j])
    forward(G, 0, held, G[held])  # the factor's new row: its block above solved against the row
    s = G[held, held] - dot_sum(G[held, :held], G[held, :held])
    if not s > least * least * Y[held, d]:
        return False
    G[held, held] = math.sqrt(s)
    return True


@njit(cache=True, _nrt=False, fastmath=SUMS)
def _resolve(rw, kind, m, held, rows, errors, start, stop, P, dq):
    """The posture's step from ``dq`` into ``rw.step`` with the rows ``rw.C[:held]`` held (``G``, ``Y`` made for
    them), zero on the DOFs locked (``rw.locked[:held - m]``)."""
    _inverse_rhs(rw, kind, rows, errors, start, stop, P, dq)
    _held_step(rw, held, rw.G, rw.Y)
    for k in range(held - m):
        rw.step[rw.locked[k]] = 0.0


@njit(cache=True, _nrt=False)
def posture_box(rw, kind, m, rows, errors, start, stop, P, dq, lo, hi, box_tol, box_rel_tol, least):
    """``dq += rw.step``, the posture's step, as the QR path's active set takes it
    (:func:`gsik.kernels.posture_level._posture_level`): as far as the box allows, the DOF that blocks it locked at
    its bound (its unit row held, :func:`_lock`) and the level solved again from there, until a step fits; False
    where a lock would be the (:data:`LOCKS` + 1)-th or not well inside full rank (:func:`_lock`, ``least``)."""
    step, n = rw.step, dq.shape[0]
    held = m
    while True:
        alpha, blocking = priority._largest_fraction(dq, step, lo, hi, box_tol, box_rel_tol)
        if blocking < 0:
            for d in range(n):
                dq[d] += step[d]
            return True
        if held - m == LOCKS or held + 1 >= n:
            return False
        if kind == DIAGONAL and held == m and not _diagonal_gram(rw, m):  # a uniform one's was not made
            return False
        for d in range(n):
            dq[d] += alpha * step[d]
        dq[blocking] = hi[blocking] if step[blocking] > 0.0 else lo[blocking]
        if not _lock(rw, kind, held, blocking, least):
            return False
        rw.locked[held - m] = blocking
        held += 1
        priority._into_box(dq, lo, hi, box_tol)
        _resolve(rw, kind, m, held, rows, errors, start, stop, P, dq)
