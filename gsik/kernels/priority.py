"""The strict-priority step kernel: :func:`gsik.priority.prioritized_step` compiled.

The levels come packed (:func:`gsik.priority.pack_levels`): every level's rows one below the other,
``starts[l]:starts[l + 1]`` the rows of level ``l``. The free directions are kept as the rows of ``Zt``
(an orthonormal basis, one direction a row, ``Zt[z0:z0 + rz]`` live): the next basis is a row offset or one
small product, never a copy of the transpose.

Per level, a Householder QR with column pivoting of ``A^T = (J Z)^T`` (rz, m) gives the rank ``k``
(pivots above ``rank_tol`` times the first), the row space of ``A`` (the first ``k`` columns of ``Q``) and
the directions left free below (the other columns). The damped least-squares step in the row space is the
``k x k`` Cholesky solve ``(R_k R_k^T + damping I) y = R_k P^T r``, ``z = Q_k y``: the same step as the SVD's
``V_k diag(s / (s^2 + damping)) U_k^T r`` (both minimise ``|A z - r|^2 + damping |z|^2`` over the row space).
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit
from gsik.kernels.pgs import _cholesky_solve

#: Status :func:`prioritized_step` returns: done, or a level's matrix held a non-finite number.
OK, NOT_FINITE = 0, 1


@njit(cache=True)
def prioritized_step(rows, errors, weights, starts, dampings, lo, hi, rank_tol, dq):
    """Strict-priority damped least squares within ``lo <= dq <= hi``, into ``dq`` (n,) [rad].

    Args:
        rows: (M, n) every level's Jacobian rows, level by level. errors, weights: (M,) their errors and
            weights (>= 0). starts: (L + 1,) int64, level ``l`` is rows ``starts[l]:starts[l + 1]``.
        dampings: (L,) each level's damping. lo, hi: (n,) the box, ``lo <= 0 <= hi``.
        rank_tol: Pivots below this fraction of a level's first are rank-deficient directions.
        dq: (n,) out: the step.

    Returns:
        :data:`OK`, or :data:`NOT_FINITE` when a level's matrix held a non-finite number (``dq`` is then undefined).
    """
    n = lo.shape[0]
    n_levels = dampings.shape[0]
    m_max = 0
    last = -1  # the last level with rows: the free basis is needed only above it
    for lv in range(n_levels):
        m = starts[lv + 1] - starts[lv]
        if m > 0:
            last = lv
            m_max = max(m_max, m)
    # One buffer, cut: Zt, Qn (n, n) the free basis and the next one; G (n, n) the damped normal matrix; V (n, n)
    # the Householder vectors, one a row; Jw, A (m_max, n) a level's weighted rows and J Z; ew, res, norm (m_max,);
    # beta, y, z, step, w (n,).
    buf = np.empty(4 * n * n + 2 * m_max * n + 3 * m_max + 5 * n)
    Zt = buf[:n * n].reshape((n, n))
    Qn = buf[n * n:2 * n * n].reshape((n, n))
    G = buf[2 * n * n:3 * n * n].reshape((n, n))
    V = buf[3 * n * n:4 * n * n].reshape((n, n))
    o = 4 * n * n
    Jw = buf[o:o + m_max * n].reshape((m_max, n))
    A = buf[o + m_max * n:o + 2 * m_max * n].reshape((m_max, n))
    o += 2 * m_max * n
    ew, res, norm = buf[o:o + m_max], buf[o + m_max:o + 2 * m_max], buf[o + 2 * m_max:o + 3 * m_max]
    o += 3 * m_max
    beta, y, z, step, w = buf[o:o + n], buf[o + n:o + 2 * n], buf[o + 2 * n:o + 3 * n], buf[o + 3 * n:o + 4 * n], \
        buf[o + 4 * n:o + 5 * n]
    locked = np.zeros(n, dtype=np.bool_)
    dq[:] = 0.0
    # The free basis: the identity at first (flagged, so the first level skips the product J Z).
    z0, rz, identity = 0, n, True
    for lv in range(last + 1):
        if rz == 0:
            break
        s, m = starts[lv], starts[lv + 1] - starts[lv]
        for i in range(m):
            sw = math.sqrt(weights[s + i])
            ew[i] = sw * errors[s + i]
            for d in range(n):
                Jw[i, d] = sw * rows[s + i, d]
        while True:
            k = _factor(Jw, ew, dq, Zt, z0, rz, identity, m, rank_tol, A, res, norm, V, beta)
            if k < 0:
                return NOT_FINITE
            k = _damped_solve(A, res, m, k, dampings[lv], G, y)
            _step_from(y, k, rz, V, beta, Zt, z0, identity, locked, z, step)
            alpha, blocking = _largest_fraction(dq, step, lo, hi)
            if blocking < 0:
                for d in range(n):
                    dq[d] += step[d]
                if lv < last and k > 0:
                    rz = _null_basis(V, beta, k, rz, Zt, z0, identity, Qn)
                    z0, identity = 0, False
                break
            for d in range(n):
                dq[d] += alpha * step[d]
            dq[blocking] = hi[blocking] if step[blocking] > 0.0 else lo[blocking]
            locked[blocking] = True
            if identity:
                _identity_into(Zt, n)
                identity = False
            if _without_dof(Zt, z0, rz, blocking, w):
                z0 += 1
                rz -= 1
            if rz == 0:
                break
    for d in range(n):
        dq[d] = min(max(dq[d], lo[d]), hi[d])  # rounding only: the loop keeps dq in the box
    return OK


@njit(cache=True, inline="always")
def _dot(X, i, Y, j, start, stop):
    """``X[i, start:stop] @ Y[j, start:stop]`` with four accumulators: the rows are short (tens), so one chain of
    dependent adds, not the multiplies, would bound it (and they are too short for LLVM's vector loops)."""
    r0 = r1 = r2 = r3 = 0.0
    d = start
    while d + 4 <= stop:
        r0 += X[i, d] * Y[j, d]
        r1 += X[i, d + 1] * Y[j, d + 1]
        r2 += X[i, d + 2] * Y[j, d + 2]
        r3 += X[i, d + 3] * Y[j, d + 3]
        d += 4
    while d < stop:
        r0 += X[i, d] * Y[j, d]
        d += 1
    return (r0 + r1) + (r2 + r3)


@njit(cache=True, inline="always")
def _axpy(X, i, a, Y, j, start, stop):
    """``X[i, start:stop] += a * Y[j, start:stop]``."""
    for d in range(start, stop):
        X[i, d] += a * Y[j, d]


@njit(cache=True)
def _identity_into(Zt, n):
    for i in range(n):
        for d in range(n):
            Zt[i, d] = 0.0
        Zt[i, i] = 1.0


@njit(cache=True)
def _factor(Jw, ew, dq, Zt, z0, rz, identity, m, rank_tol, A, res, norm, V, beta):
    """``A = J Z`` (m, rz) and the residual ``r = e - J dq``; then the pivoted QR of ``A^T``, in place.

    Afterwards the rows of ``A`` and ``res`` are in pivot order, ``A[c, i]`` (``i < k``, ``i <= c``) is
    ``R[i, c]``, and reflection ``j`` is ``I - beta[j] v v^T`` with ``v = V[j, j:rz]``. Returns the rank ``k``,
    or -1 if ``A`` held a non-finite number.
    """
    n = Jw.shape[1]
    total = 0.0
    for i in range(m):
        res[i] = ew[i] - _dot1(Jw, i, dq, n)
        for c in range(rz):
            A[i, c] = Jw[i, c] if identity else _dot(Jw, i, Zt, z0 + c, 0, n)
        norm[i] = _dot(A, i, A, i, 0, rz)
        total += norm[i]
    if not math.isfinite(total):
        return -1
    first = 0.0
    for j in range(min(m, rz)):
        p = j
        for c in range(j + 1, m):
            if norm[c] > norm[p]:
                p = c
        if j == 0:
            first = math.sqrt(norm[p])
        if not math.sqrt(norm[p]) > rank_tol * first:
            return j
        if p != j:
            for i in range(rz):
                A[j, i], A[p, i] = A[p, i], A[j, i]
            res[j], res[p] = res[p], res[j]
            norm[p] = norm[j]
        _reflect_pivot(A, j, rz, V, beta)
        for c in range(j + 1, m):
            _axpy(A, c, -beta[j] * _dot(V, j, A, c, j, rz), V, j, j, rz)
            norm[c] = _dot(A, c, A, c, j + 1, rz)  # recomputed, not downdated: no cancellation to guard against
    return min(m, rz)


@njit(cache=True, inline="always")
def _dot1(X, i, x, stop):
    """``X[i, :stop] @ x[:stop]``."""
    r0 = r1 = 0.0
    d = 0
    while d + 2 <= stop:
        r0 += X[i, d] * x[d]
        r1 += X[i, d + 1] * x[d + 1]
        d += 2
    if d < stop:
        r0 += X[i, d] * x[d]
    return r0 + r1


@njit(cache=True)
def _reflect_pivot(A, j, rz, V, beta):
    """The reflection ``I - beta[j] v v^T`` (``v = V[j, j:rz]``) that maps ``A[j, j:rz]`` onto its first axis."""
    for i in range(j, rz):
        V[j, i] = A[j, i]
    s2 = _dot(A, j, A, j, j, rz)
    x0 = A[j, j]
    alpha = -math.sqrt(s2) if x0 >= 0.0 else math.sqrt(s2)
    V[j, j] = x0 - alpha
    beta[j] = 1.0 / (s2 - x0 * alpha)  # 2 / |v|^2, |v|^2 = 2 (s2 - x0 alpha)
    A[j, j] = alpha
    for i in range(j + 1, rz):
        A[j, i] = 0.0


@njit(cache=True)
def _damped_solve(A, res, m, k, damping, G, y):
    """``y`` (k,) solving ``(R_k R_k^T + damping I) y = R_k P^T r``; returns ``k``, lowered while that matrix is not
    numerically positive definite (only without damping, at a level all but rank-deficient)."""
    while k > 0:
        for i in range(k):
            for i2 in range(i + 1):
                G[i, i2] = 0.0
            y[i] = 0.0
        for c in range(m):
            for i in range(min(c + 1, k)):
                y[i] += A[c, i] * res[c]
                _axpy(G, i, A[c, i], A, c, 0, i + 1)
        for i in range(k):
            G[i, i] += damping
        if _cholesky_solve(G, y, k):
            return k
        k -= 1
    return 0


@njit(cache=True)
def _step_from(y, k, rz, V, beta, Zt, z0, identity, locked, z, step):
    """``step = Z Q [y; 0]`` (n,), zero on the locked DOFs."""
    n = step.shape[0]
    for i in range(rz):
        z[i] = y[i] if i < k else 0.0
    for j in range(k - 1, -1, -1):
        _reflect_into(z, V, j, beta[j], rz)
    if identity:
        for d in range(n):
            step[d] = z[d]
    else:
        step[:] = 0.0
        for c in range(rz):
            for d in range(n):
                step[d] += z[c] * Zt[z0 + c, d]
    for d in range(n):
        if locked[d]:
            step[d] = 0.0


@njit(cache=True, inline="always")
def _reflect_into(x, V, j, b, stop):
    """``x[j:stop] -= b v (v @ x[j:stop])``, ``v = V[j, j:stop]``: one reflection of a vector."""
    dot = 0.0
    for i in range(j, stop):
        dot += V[j, i] * x[i]
    dot *= b
    for i in range(j, stop):
        x[i] -= dot * V[j, i]


@njit(cache=True)
def _largest_fraction(dq, step, lo, hi):
    """The largest ``alpha <= 1`` keeping ``dq + alpha * step`` in the box, and the DOF that blocks (-1: none)."""
    best = math.inf
    blocking = -1
    for d in range(dq.shape[0]):
        over = dq[d] + step[d]
        if over > hi[d] or over < lo[d]:
            room = ((hi[d] if step[d] > 0.0 else lo[d]) - dq[d]) / step[d]
            if room < best:
                best = room
                blocking = d
    if blocking < 0:
        return 1.0, -1
    return max(best, 0.0), blocking


@njit(cache=True)
def _null_basis(V, beta, k, rz, Zt, z0, identity, Qn):
    """The free basis below this level, ``(Z Q[:, k:])^T``, into ``Zt[:rz - k]``; returns ``rz - k``.

    Each row of ``Q[:, k:]^T`` is ``H_0 ... H_(k-1) e_(k+a)``, the reflections applied last to first: the
    vector stays zero above the reflection's start, so each costs only its own length.
    """
    n = Zt.shape[1]
    left = rz - k
    for a in range(left):
        for i in range(rz):
            Qn[a, i] = 0.0
        Qn[a, k + a] = 1.0
        for j in range(k - 1, -1, -1):
            _axpy(Qn, a, -beta[j] * _dot(V, j, Qn, a, j, rz), V, j, j, rz)
    if identity:
        for a in range(left):
            for d in range(n):
                Zt[a, d] = Qn[a, d]
        return left
    # Rows z0 ... of Zt are read while rows 0 ... are written: through V's spare rows k ... as a buffer.
    for a in range(left):
        for d in range(n):
            V[k + a, d] = 0.0
        for c in range(rz):
            _axpy(V, k + a, Qn[a, c], Zt, z0 + c, 0, n)
    for a in range(left):
        for d in range(n):
            Zt[a, d] = V[k + a, d]
    return left


@njit(cache=True)
def _without_dof(Zt, z0, rz, dof, w):
    """Turn the live rows of ``Zt`` so that only the first moves DOF ``dof`` (it is then dropped: returns True);
    False when no row moves it (the basis stays)."""
    n = Zt.shape[1]
    s2 = 0.0
    for c in range(rz):
        s2 += Zt[z0 + c, dof] * Zt[z0 + c, dof]
    norm = math.sqrt(s2)
    if norm < 1e-12:
        return False
    # A Householder reflection maps the column's direction u onto the first axis; the other rows span its complement.
    u0 = Zt[z0, dof] / norm
    u0 += 1.0 if u0 >= 0.0 else -1.0
    uu = u0 * u0 + (s2 - Zt[z0, dof] ** 2) / s2
    w[:] = 0.0
    for c in range(rz):
        uc = u0 if c == 0 else Zt[z0 + c, dof] / norm
        for d in range(n):
            w[d] += uc * Zt[z0 + c, d]
    scale = 2.0 / uu
    for c in range(rz):
        uc = (u0 if c == 0 else Zt[z0 + c, dof] / norm) * scale
        for d in range(n):
            Zt[z0 + c, d] -= uc * w[d]
    for c in range(rz):
        Zt[z0 + c, dof] = 0.0  # exactly, not to rounding
    return True
