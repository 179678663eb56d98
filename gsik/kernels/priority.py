"""The strict-priority step kernel: :func:`gsik.priority.prioritized_step` compiled.

The levels come packed (:func:`gsik.priority.pack_levels`): every level's rows one below the other,
``starts[l]:starts[l + 1]`` the rows of level ``l``. The free directions are kept as the rows of ``Zt``
(an orthonormal basis, one direction a row, ``Zt[z0:z0 + rz]`` live): the next basis is a row offset or one
small product, never a copy of the transpose.

Per level, a Householder QR with column pivoting of ``A^T = (J Z)^T`` (rz, m) gives the rank ``k`` (pivots
above ``rank_tol`` times the level's largest row norm), the row space of ``A`` (the first ``k`` columns of
``Q``) and the directions left free below (the other columns). The damped least-squares step in the row space is the
``k x k`` Cholesky solve ``(R_k R_k^T + damping I) y = R_k P^T r``, ``z = Q_k y``: the same step as the SVD's
``V_k diag(s / (s^2 + damping)) U_k^T r`` (both minimise ``|A z - r|^2 + damping |z|^2`` over the row space).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik._jit import njit
from gsik.kernels.pgs import _cholesky_solve

#: Status :func:`prioritized_step` returns: done, or a level's matrix held a non-finite number.
OK, NOT_FINITE = 0, 1
# A row's pivot norm^2 is downdated (one subtraction) until it has fallen below this fraction of its last exact value,
# then recomputed: beyond that the subtraction would cancel (LAPACK's xLAQP2 test, on squares).
_RECOMPUTE_BELOW = math.sqrt(np.finfo(np.float64).eps)


class Work(NamedTuple):
    """The kernel's buffers (:func:`make_work`), for ``n`` DOFs and levels of at most ``m`` rows.

    Attributes:
        Zt: (n, n) the free basis, one direction a row (live rows ``z0:z0 + rz``). Qn: (n, n) the next one.
        V: (n, n) the Householder vectors, one a row. G: (n, n) the damped normal matrix.
        Jw: (m, n) the level's weighted rows. A0: (m, n) ``J Z``. A: (m, n) ``J Z``, factored.
        RT: (n, m) ``R``'s leading rows. ew, res, norm2, norm2_exact: (m,) weighted errors, residual, pivot norms^2.
        beta, y, z, step, u: (n,). locked: (n,) bool, the DOFs held at a bound.
    """

    Zt: np.ndarray
    Qn: np.ndarray
    V: np.ndarray
    G: np.ndarray
    Jw: np.ndarray
    A0: np.ndarray
    A: np.ndarray
    RT: np.ndarray
    ew: np.ndarray
    res: np.ndarray
    norm2: np.ndarray
    norm2_exact: np.ndarray
    beta: np.ndarray
    y: np.ndarray
    z: np.ndarray
    step: np.ndarray
    u: np.ndarray
    locked: np.ndarray


@njit(cache=True)
def make_work(n, m):
    """A :class:`Work` (uninitialised but ``locked``, all False): one allocation, cut."""
    sizes = (n * n, n * n, n * n, n * n, m * n, m * n, m * n, n * m, m, m, m, m, n, n, n, n, n)
    ends = np.cumsum(np.array(sizes))
    buf = np.empty(ends[-1])
    return Work(buf[:ends[0]].reshape((n, n)), buf[ends[0]:ends[1]].reshape((n, n)),
                buf[ends[1]:ends[2]].reshape((n, n)), buf[ends[2]:ends[3]].reshape((n, n)),
                buf[ends[3]:ends[4]].reshape((m, n)), buf[ends[4]:ends[5]].reshape((m, n)),
                buf[ends[5]:ends[6]].reshape((m, n)), buf[ends[6]:ends[7]].reshape((n, m)),
                buf[ends[7]:ends[8]], buf[ends[8]:ends[9]], buf[ends[9]:ends[10]], buf[ends[10]:ends[11]],
                buf[ends[11]:ends[12]], buf[ends[12]:ends[13]], buf[ends[13]:ends[14]], buf[ends[14]:ends[15]],
                buf[ends[15]:ends[16]], np.zeros(n, dtype=np.bool_))


@njit(cache=True)
def prioritized_step(rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, dq):
    """Strict-priority damped least squares within ``lo <= dq <= hi``, into ``dq`` (n,) [rad].

    Args:
        rows: (M, n) every level's Jacobian rows, level by level. errors, weights: (M,) their errors and
            weights (>= 0). starts: (L + 1,) int64, level ``l`` is rows ``starts[l]:starts[l + 1]``.
        dampings: (L,) each level's damping. lo, hi: (n,) the box, ``lo <= 0 <= hi``.
        rank_tol: Pivots below this fraction of a level's largest weighted row norm are rank-deficient directions.
        box_tol, box_rel_tol: A step leaving the box by no more than ``box_tol`` [rad] plus ``box_rel_tol`` times its
            largest component does not block (rounding; clipped).
        dq: (n,) out: the step.

    Returns:
        :data:`OK`, or :data:`NOT_FINITE` when a level's matrix held a non-finite number (``dq`` is then undefined).
    """
    n = lo.shape[0]
    m_max = 0
    last = -1  # the last level with rows: the free basis is needed only above it
    for lv in range(dampings.shape[0]):
        if starts[lv + 1] > starts[lv]:
            last = lv
            m_max = max(m_max, starts[lv + 1] - starts[lv])
    wk = make_work(n, m_max)
    dq[:] = 0.0
    # The free basis: the identity at first (flagged: the first level needs no product J Z, no stored basis).
    z0, rz, identity = 0, n, True
    for lv in range(last + 1):
        if rz == 0:
            break
        m = _weigh(rows, errors, weights, starts[lv], starts[lv + 1], wk.Jw, wk.ew)
        scale = _project(wk.Jw, m, wk.Zt, z0, rz, identity, wk.A0)
        if not math.isfinite(scale):
            return NOT_FINITE
        z0, rz, identity = _solve_level(wk, m, z0, rz, identity, dq, lo, hi, dampings[lv], rank_tol * scale, box_tol,
                                        box_rel_tol, lv < last)
    for d in range(n):
        dq[d] = min(max(dq[d], lo[d]), hi[d])  # rounding only: the loop keeps dq in the box
    return OK


@njit(cache=True)
def _weigh(rows, errors, weights, start, stop, Jw, ew):
    """``Jw = sqrt(w) J``, ``ew = sqrt(w) e`` of rows ``start:stop``; returns their count."""
    for i in range(stop - start):
        sw = math.sqrt(weights[start + i])
        ew[i] = sw * errors[start + i]
        for d in range(rows.shape[1]):
            Jw[i, d] = sw * rows[start + i, d]
    return stop - start


@njit(cache=True)
def _project(Jw, m, Zt, z0, rz, identity, A0):
    """``A0 = J Z`` (m, rz); returns the largest row norm of ``J`` (not finite if ``A0`` or ``J`` holds a non-finite
    number)."""
    n = Jw.shape[1]
    total = 0.0
    scale = 0.0
    for i in range(m):
        for c in range(rz):
            A0[i, c] = Jw[i, c] if identity else _dot(Jw, i, Zt, z0 + c, 0, n)
        total += _dot(A0, i, A0, i, 0, rz)
        scale = max(scale, _dot(Jw, i, Jw, i, 0, n))
    return math.sqrt(scale) if math.isfinite(total) else math.nan


@njit(cache=True)
def _solve_level(wk, m, z0, rz, identity, dq, lo, hi, damping, pivot_tol, box_tol, box_rel_tol, basis_needed):
    """One level's active-set loop on ``dq`` (and ``wk.locked``); returns the free basis left below it
    ``(z0, rz, identity)`` (only when ``basis_needed``: else as it stood)."""
    n = dq.shape[0]
    while True:
        _into_box(dq, lo, hi, box_tol)
        k = _factor(wk, m, rz, dq, pivot_tol)
        k = _damped_solve(wk, m, k, damping)
        _step_from(wk, k, rz, z0, identity)
        alpha, blocking = _largest_fraction(dq, wk.step, lo, hi, box_tol, box_rel_tol)
        if blocking < 0:
            for d in range(n):
                dq[d] += wk.step[d]
            if basis_needed and k > 0:
                return 0, _null_basis(wk, k, rz, z0, identity), False
            return z0, rz, identity
        for d in range(n):
            dq[d] += alpha * wk.step[d]
        dq[blocking] = hi[blocking] if wk.step[blocking] > 0.0 else lo[blocking]
        wk.locked[blocking] = True
        if identity:
            _identity_into(wk.Zt, n)
            identity = False
        scale = _without_dof(wk.Zt, z0, rz, blocking, wk.u, wk.z)
        if scale > 0.0:
            _reflect_columns(wk.A0, m, rz, wk.u, scale)
            z0 += 1
            rz -= 1
        if rz == 0:
            return z0, rz, identity


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
def _dot1(X, i, x, start, stop):
    """``X[i, start:stop] @ x[start:stop]``."""
    r0 = r1 = 0.0
    d = start
    while d + 2 <= stop:
        r0 += X[i, d] * x[d]
        r1 += X[i, d + 1] * x[d + 1]
        d += 2
    if d < stop:
        r0 += X[i, d] * x[d]
    return r0 + r1


@njit(cache=True, inline="always")
def _axpy(X, i, a, Y, j, start, stop):
    """``X[i, start:stop] += a * Y[j, start:stop]``, four at a time, each four's loads before its stores: LLVM then
    packs them into one vector operation without having to prove that X and Y do not overlap."""
    d = start
    while d + 4 <= stop:
        x0, x1, x2, x3 = X[i, d], X[i, d + 1], X[i, d + 2], X[i, d + 3]
        y0, y1, y2, y3 = Y[j, d], Y[j, d + 1], Y[j, d + 2], Y[j, d + 3]
        X[i, d], X[i, d + 1], X[i, d + 2], X[i, d + 3] = x0 + a * y0, x1 + a * y1, x2 + a * y2, x3 + a * y3
        d += 4
    while d < stop:
        X[i, d] += a * Y[j, d]
        d += 1


@njit(cache=True, inline="always")
def _axpy1(x, a, Y, j, start, stop):
    """``x[start:stop] += a * Y[j, start:stop]``."""
    for d in range(start, stop):
        x[d] += a * Y[j, d]


@njit(cache=True)
def _identity_into(Zt, n):
    for i in range(n):
        for d in range(n):
            Zt[i, d] = 0.0
        Zt[i, i] = 1.0


@njit(cache=True)
def _factor(wk, m, rz, dq, pivot_tol):
    """The pivoted QR of ``A^T`` (``A = wk.A0``) into ``wk.A``, and the residual ``r = e - J dq`` into ``wk.res``.

    Afterwards the rows of ``A`` and ``res`` are in pivot order, ``A[c, i]`` (``i < k``, ``i <= c``) is
    ``R[i, c]``, and reflection ``j`` is ``I - beta[j] v v^T`` with ``v = V[j, j:rz]``. Returns the rank ``k``: the
    pivots above ``pivot_tol``.
    """
    A, res, norm2, exact = wk.A, wk.res, wk.norm2, wk.norm2_exact
    for i in range(m):
        res[i] = wk.ew[i] - _dot1(wk.Jw, i, dq, 0, dq.shape[0])
        for c in range(rz):
            A[i, c] = wk.A0[i, c]
        norm2[i] = exact[i] = _dot(A, i, A, i, 0, rz)
    for j in range(min(m, rz)):
        p = j
        for c in range(j + 1, m):
            if norm2[c] > norm2[p]:
                p = c
        if not math.sqrt(norm2[p]) > pivot_tol:
            return j
        if p != j:
            for i in range(rz):
                A[j, i], A[p, i] = A[p, i], A[j, i]
            res[j], res[p] = res[p], res[j]
            norm2[p], exact[p] = norm2[j], exact[j]
        _reflect_pivot(A, j, rz, wk.V, wk.beta)
        for c in range(j + 1, m):
            _axpy(A, c, -wk.beta[j] * _dot(wk.V, j, A, c, j, rz), wk.V, j, j, rz)
            norm2[c] -= A[c, j] * A[c, j]
            if norm2[c] <= _RECOMPUTE_BELOW * exact[c]:
                norm2[c] = exact[c] = _dot(A, c, A, c, j + 1, rz)
    return min(m, rz)


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
def _damped_solve(wk, m, k, damping):
    """``wk.y`` (k,) solving ``(R_k R_k^T + damping I) y = R_k P^T r``; returns ``k``, lowered while that matrix is
    not numerically positive definite (only without damping, at a level all but rank-deficient)."""
    RT, G, y = wk.RT, wk.G, wk.y
    for i in range(k):  # R's rows, contiguous: R[i, c] = A[c, i] for c >= i
        for c in range(i, m):
            RT[i, c] = wk.A[c, i]
    while k > 0:
        for i in range(k):
            y[i] = _dot1(RT, i, wk.res, i, m)
            for i2 in range(i + 1):
                G[i, i2] = _dot(RT, i, RT, i2, i, m)
            G[i, i] += damping
        if _cholesky_solve(G, y, k):
            return k
        k -= 1
    return 0


@njit(cache=True)
def _step_from(wk, k, rz, z0, identity):
    """``wk.step = Z Q [y; 0]`` (n,), zero on the locked DOFs."""
    z, step = wk.z, wk.step
    n = step.shape[0]
    for i in range(rz):
        z[i] = wk.y[i] if i < k else 0.0
    for j in range(k - 1, -1, -1):
        b = -wk.beta[j] * _dot1(wk.V, j, z, j, rz)
        for i in range(j, rz):
            z[i] += b * wk.V[j, i]
    if identity:
        for d in range(n):
            step[d] = z[d]
    else:
        step[:] = 0.0
        for c in range(rz):
            _axpy1(step, z[c], wk.Zt, z0 + c, 0, n)
    for d in range(n):
        if wk.locked[d]:
            step[d] = 0.0


@njit(cache=True)
def _into_box(dq, lo, hi, box_tol):
    """``dq`` clipped into the box and put on a bound where within ``box_tol`` of it (rounding only: every DOF on a
    bound then has room 0 exactly, and ties go by index, not by rounding)."""
    for d in range(dq.shape[0]):
        v = min(max(dq[d], lo[d]), hi[d])
        if v - lo[d] <= box_tol:
            v = lo[d]
        if hi[d] - v <= box_tol:
            v = hi[d]
        dq[d] = v


@njit(cache=True)
def _largest_fraction(dq, step, lo, hi, box_tol, box_rel_tol):
    """The largest ``alpha <= 1`` keeping ``dq + alpha * step`` in the box (widened by ``box_tol`` and ``box_rel_tol``
    times the step's largest component), and the DOF that blocks (-1: none)."""
    size = 0.0
    for d in range(dq.shape[0]):
        size = max(size, abs(step[d]))
    tol = box_tol + box_rel_tol * size
    best = math.inf
    blocking = -1
    for d in range(dq.shape[0]):
        over = dq[d] + step[d]
        if over > hi[d] + tol or over < lo[d] - tol:
            room = ((hi[d] if step[d] > 0.0 else lo[d]) - dq[d]) / step[d]
            if room < best:
                best = room
                blocking = d
    if blocking < 0:
        return 1.0, -1
    return max(best, 0.0), blocking


@njit(cache=True)
def _null_basis(wk, k, rz, z0, identity):
    """The free basis below this level, ``(Z Q[:, k:])^T``, into ``wk.Zt[:rz - k]``; returns ``rz - k``.

    Each row of ``Q[:, k:]^T`` is ``H_0 ... H_(k-1) e_(k+a)``, the reflections applied last to first: the
    vector stays zero above the reflection's start, so each costs only its own length.
    """
    Zt, Qn, V = wk.Zt, wk.Qn, wk.V
    n = Zt.shape[1]
    left = rz - k
    for a in range(left):
        for i in range(rz):
            Qn[a, i] = 0.0
        Qn[a, k + a] = 1.0
    for j in range(k - 1, -1, -1):  # the rows are independent: reflection by reflection, not row by row
        for a in range(left):
            _axpy(Qn, a, -wk.beta[j] * _dot(V, j, Qn, a, j, rz), V, j, j, rz)
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
def _without_dof(Zt, z0, rz, dof, u, w):
    """Turn the live rows of ``Zt`` by the reflection ``I - scale u u^T`` (``u`` (rz,) filled here) so that only the
    first moves DOF ``dof``; returns ``scale`` (the caller then drops that row), or 0 when no row moves it.
    ``w``: (n,) scratch."""
    n = Zt.shape[1]
    s2 = 0.0
    for c in range(rz):
        s2 += Zt[z0 + c, dof] * Zt[z0 + c, dof]
    norm = math.sqrt(s2)
    if norm < 1e-12:
        return 0.0
    # The reflection maps the column's direction onto the first axis; the other rows span its complement.
    uu = 0.0
    for c in range(rz):
        u[c] = Zt[z0 + c, dof] / norm
    u[0] += 1.0 if u[0] >= 0.0 else -1.0
    for c in range(rz):
        uu += u[c] * u[c]
    scale = 2.0 / uu
    w[:] = 0.0
    for c in range(rz):
        _axpy1(w, u[c], Zt, z0 + c, 0, n)
    for c in range(rz):
        a = -scale * u[c]
        for d in range(n):
            Zt[z0 + c, d] += a * w[d]
        Zt[z0 + c, dof] = 0.0  # exactly, not to rounding
    return scale


@njit(cache=True)
def _reflect_columns(A0, m, rz, u, scale):
    """``A0 = (A0 (I - scale u u^T))[:, 1:]``: ``J Z`` after :func:`_without_dof` turned ``Z``, without the product."""
    for i in range(m):
        t = -scale * _dot1(A0, i, u, 0, rz)
        for c in range(1, rz):
            A0[i, c - 1] = A0[i, c] + t * u[c]
