"""The strict-priority step kernel: :func:`gsik.priority.prioritized_step` compiled.

The levels come packed (:func:`gsik.priority.pack_levels`): every level's rows one below the other,
``starts[l]:starts[l + 1]`` the rows of level ``l``. The free directions are kept as the rows of ``Zt``
(an orthonormal basis, one direction a row, ``Zt[z0:z0 + rz]`` live): the next basis is a row offset or one
small product, never a copy of the transpose.

Per level, a Householder QR with column pivoting of ``A^T = (J Z)^T`` (rz, m) gives the rank ``k`` (pivots
above ``rank_tol`` times the level's largest row norm), the row space of ``A`` (the first ``k`` columns of
``Q``) and the directions left free below (the other columns, ``Z Q[:, k:]``: the reflections applied to the rows of
``Zt`` in place, the next basis its rows from ``z0 + k``). The damped least-squares step in the row space is the
``k x k`` Cholesky solve ``(R_k R_k^T + damping I) y = R_k P^T r``, ``z = Q_k y``: the same step as the SVD's
``V_k diag(s / (s^2 + damping)) U_k^T r`` (both minimise ``|A z - r|^2 + damping |z|^2`` over the row space).

Every matrix a reflection turns is stored with the reflected index first (``A^T`` as (rz, m) rows, the weighted
rows transposed, the basis as rows): a reflection is then two sweeps of ``x += a * row`` over contiguous rows, which
LLVM turns into vector operations, instead of one short dot product per row (a chain of dependent adds; about three
times slower at these sizes).

A caller that steps often keeps one :class:`Work` (:func:`make_work`, sized by :func:`largest_level`) and steps in
it (:func:`prioritized_step_in`: a controller's, :attr:`gsik.kernels.control.ControlWork.priority`); allocating the
buffers took ~1 µs of a ~28 µs step. The kernels that allocate nothing are compiled without numba's reference
counting (``_nrt=False``, as in :mod:`gsik.kernels.kinematics`). Those that allocate the step's buffers
(:func:`make_work`, :func:`prioritized_step`) say ``_nrt=True``: a kernel that leaves it unset inherits its caller's
setting when compiled from one.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik._jit import njit
from gsik.kernels.null_basis import identity_into, null_basis, reflect_rows, without_dof
from gsik.kernels.pgs import _cholesky_solve
from gsik.kernels.rows import axpy, axpy1, dot, dot1, reflect

#: Status :func:`prioritized_step` returns: done, or a level's matrix held a non-finite number.
OK, NOT_FINITE = 0, 1
# A row's pivot norm^2 is downdated (one subtraction) until it has fallen below this fraction of its last exact value,
# then recomputed: beyond that the subtraction would cancel (LAPACK's xLAQP2 test, on squares).
_RECOMPUTE_BELOW = math.sqrt(np.finfo(np.float64).eps)


class Work(NamedTuple):
    """The kernel's buffers (:func:`make_work`), for ``n`` DOFs and levels of at most ``m`` rows.

    Attributes:
        Zt: (n, n) the free basis, one direction a row (live rows ``z0:z0 + rz``).
        V: (n, n) the Householder vectors, one a row. G: (n, n) the damped normal matrix.
        JwT: (n, m) the level's weighted rows, transposed. AT0: (n, m) ``(J Z)^T``. AT: (n, m) ``(J Z)^T``, factored.
        ew, res, norm2, norm2_exact, w: (m,) weighted errors, residual, pivot norms^2, a reflection's products.
        beta, y, z, step, u, zw: (n,). locked: (n,) bool, the DOFs held at a bound.
        span: (2, n) int64, the columns ``span[0, d]:span[1, d]`` of ``JwT``'s row ``d`` that hold its nonzeros.
    """

    Zt: np.ndarray
    V: np.ndarray
    G: np.ndarray
    JwT: np.ndarray
    AT0: np.ndarray
    AT: np.ndarray
    ew: np.ndarray
    res: np.ndarray
    norm2: np.ndarray
    norm2_exact: np.ndarray
    w: np.ndarray
    beta: np.ndarray
    y: np.ndarray
    z: np.ndarray
    step: np.ndarray
    u: np.ndarray
    zw: np.ndarray
    locked: np.ndarray
    span: np.ndarray


@njit(cache=True, _nrt=True)
def make_work(n, m):
    """A :class:`Work` for ``n`` DOFs and levels of at most ``m`` rows (uninitialised but ``locked``, all False): one
    allocation, cut."""
    sizes = (n * n, n * n, n * n, n * m, n * m, n * m, m, m, m, m, m, n, n, n, n, n, n)
    ends = np.cumsum(np.array(sizes))
    buf = np.empty(ends[-1])
    return Work(buf[:ends[0]].reshape((n, n)), buf[ends[0]:ends[1]].reshape((n, n)),
                buf[ends[1]:ends[2]].reshape((n, n)), buf[ends[2]:ends[3]].reshape((n, m)),
                buf[ends[3]:ends[4]].reshape((n, m)), buf[ends[4]:ends[5]].reshape((n, m)),
                buf[ends[5]:ends[6]], buf[ends[6]:ends[7]], buf[ends[7]:ends[8]], buf[ends[8]:ends[9]],
                buf[ends[9]:ends[10]], buf[ends[10]:ends[11]], buf[ends[11]:ends[12]], buf[ends[12]:ends[13]],
                buf[ends[13]:ends[14]], buf[ends[14]:ends[15]], buf[ends[15]:ends[16]], np.zeros(n, dtype=np.bool_),
                np.empty((2, n), dtype=np.int64))


@njit(cache=True, _nrt=True)
def prioritized_step(rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, dq):
    """:func:`prioritized_step_in` in buffers of its own (allocated: for a caller that steps once)."""
    wk = make_work(lo.shape[0], largest_level(starts, dampings.shape[0]))
    return prioritized_step_in(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, dq)


@njit(cache=True, _nrt=False)
def prioritized_step_in(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, dq):
    """Strict-priority damped least squares within ``lo <= dq <= hi``, into ``dq`` (n,) [rad].

    Args:
        wk: the :class:`Work` to step in, for ``n`` DOFs and at least :func:`largest_level` rows (what it held
            before does not matter).
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
    last = begin(wk, starts, dampings, dq)
    status, _, _, _ = solve_levels(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol,
                                   last + 1, last, dq)
    if status == OK:
        clip(dq, lo, hi)
    return status


@njit(cache=True, _nrt=False)
def largest_level(starts, levels):
    """The most rows (>= 0) of the first ``levels`` levels of ``starts`` (L + 1,): the rows a :class:`Work` needs."""
    m_max = 0
    for lv in range(levels):
        m_max = max(m_max, starts[lv + 1] - starts[lv])
    return m_max


@njit(cache=True, _nrt=False)
def begin(wk, starts, dampings, dq):
    """The last level with rows (-1: none); ``dq`` zeroed and ``wk.locked`` all False (no DOF held yet)."""
    last = -1  # the last level with rows: the free basis is needed only above it
    for lv in range(dampings.shape[0]):
        if starts[lv + 1] > starts[lv]:
            last = lv
    dq[:] = 0.0
    wk.locked[:] = False
    return last


@njit(cache=True, _nrt=False)
def solve_levels(wk, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol, box_rel_tol, stop, last, dq):
    """Levels ``0 ... stop - 1`` into ``dq`` (the free basis kept below each level before ``last``); returns
    ``(status, z0, rz, identity)``: :data:`OK` or :data:`NOT_FINITE`, and the free basis left (``wk.Zt``'s rows
    ``z0:z0 + rz``, or the unstored identity)."""
    # The free basis: the identity at first (flagged: the first level needs no product J Z, no stored basis).
    z0, rz, identity = 0, lo.shape[0], True
    for lv in range(stop):
        if rz == 0:
            break
        m = _weigh(rows, errors, weights, starts[lv], starts[lv + 1], wk.JwT, wk.ew, wk.w, wk.span)
        scale = _project(wk.JwT, m, wk.Zt, z0, rz, identity, wk.AT0, wk.w, wk.span)
        if not math.isfinite(scale):
            return NOT_FINITE, z0, rz, identity
        z0, rz, identity = _solve_level(wk, m, z0, rz, identity, dq, lo, hi, dampings[lv], rank_tol * scale, box_tol,
                                        box_rel_tol, lv < last)
    return OK, z0, rz, identity


@njit(cache=True, _nrt=False)
def clip(dq, lo, hi):
    """``dq`` (n,) clipped into the box (rounding only: the levels keep it there)."""
    for d in range(dq.shape[0]):
        dq[d] = min(max(dq[d], lo[d]), hi[d])


@njit(cache=True, _nrt=False)
def _weigh(rows, errors, weights, start, stop, JwT, ew, norm2, span):
    """``JwT = (sqrt(w) J)^T``, ``ew = sqrt(w) e`` of rows ``start:stop``, ``norm2`` their squared row norms,
    ``span`` the nonzero columns of each row of ``JwT`` (a posture's diagonal factor: one each); returns their
    count."""
    m = stop - start
    n = rows.shape[1]
    for d in range(n):
        span[0, d] = m
        span[1, d] = 0
    for i in range(m):
        sw = math.sqrt(weights[start + i])
        ew[i] = sw * errors[start + i]
        s = 0.0
        for d in range(n):
            v = sw * rows[start + i, d]
            JwT[d, i] = v
            s += v * v
            if v != 0.0:
                span[0, d] = min(span[0, d], i)
                span[1, d] = i + 1
        norm2[i] = s
    return m


@njit(cache=True, _nrt=False)
def _project(JwT, m, Zt, z0, rz, identity, AT0, norm2, span):
    """``AT0 = (J Z)^T`` (rz, m), over the nonzeros of ``Z`` and of ``J``'s columns (``span``; a zero's product adds
    exactly nothing); returns the largest row norm of ``J`` (``norm2``: (m,) its squares), not finite if ``AT0`` or
    ``J`` holds a non-finite number."""
    n = JwT.shape[0]
    for c in range(rz):
        if identity:
            for i in range(m):
                AT0[c, i] = JwT[c, i]
            continue
        for i in range(m):
            AT0[c, i] = 0.0
        for d in range(n):
            a = Zt[z0 + c, d]
            if a != 0.0 and span[0, d] < span[1, d]:
                axpy(AT0, c, a, JwT, d, span[0, d], span[1, d])
    total = 0.0
    for c in range(rz):
        for i in range(m):
            total += AT0[c, i] * AT0[c, i]
    scale = 0.0
    for i in range(m):
        total += norm2[i]
        scale = max(scale, norm2[i])
    return math.sqrt(scale) if math.isfinite(total) else math.nan


@njit(cache=True, _nrt=False)
def _solve_level(wk, m, z0, rz, identity, dq, lo, hi, damping, pivot_tol, box_tol, box_rel_tol, basis_needed):
    """One level's active-set loop on ``dq`` (and ``wk.locked``); returns the free basis left below it
    ``(z0, rz, identity)`` (only when ``basis_needed``: else as it stood)."""
    n = dq.shape[0]
    while True:
        _into_box(dq, lo, hi, box_tol)
        ra, identity = _active_first(wk, m, z0, rz, identity)
        k = _factor(wk, m, ra, dq, pivot_tol)
        k = _damped_solve(wk, m, k, damping)
        _step_from(wk, k, ra, z0, identity)
        alpha, blocking = _largest_fraction(dq, wk.step, lo, hi, box_tol, box_rel_tol)
        if blocking < 0:
            for d in range(n):
                dq[d] += wk.step[d]
            if basis_needed and k > 0:
                if identity:
                    identity_into(wk.Zt, n)
                null_basis(wk, k, ra, z0)
                return z0 + k, rz - k, False
            return z0, rz, identity
        for d in range(n):
            dq[d] += alpha * wk.step[d]
        dq[blocking] = hi[blocking] if wk.step[blocking] > 0.0 else lo[blocking]
        wk.locked[blocking] = True
        if identity:
            identity_into(wk.Zt, n)
            identity = False
        scale = without_dof(wk.Zt, z0, rz, blocking, wk.u, wk.zw)
        if scale > 0.0:
            reflect_rows(wk.AT0, m, rz, wk.u, scale, wk.w)
            z0 += 1
            rz -= 1
        if rz == 0:
            return z0, rz, identity


@njit(cache=True, _nrt=False)
def _active_first(wk, m, z0, rz, identity):
    """The live directions this level's rows do not see (``AT0``'s rows exactly zero: a DOF none of its rows moves)
    moved behind the others, rows of ``AT0`` and ``Zt`` alike; returns ``(ra, identity)``: the directions it sees
    come first, ``ra`` of them (the level's factorisation, step and reflections need only those), and whether the
    basis is still the unstored identity."""
    AT0, Zt = wk.AT0, wk.Zt
    n = Zt.shape[1]
    ra = rz
    c = 0
    while c < ra:
        seen = False
        for i in range(m):
            if AT0[c, i] != 0.0:
                seen = True
                break
        if seen:
            c += 1
            continue
        ra -= 1
        if c == ra:
            break
        if identity:
            identity_into(Zt, n)
            identity = False
        for i in range(m):
            AT0[c, i], AT0[ra, i] = AT0[ra, i], AT0[c, i]
        for d in range(n):
            Zt[z0 + c, d], Zt[z0 + ra, d] = Zt[z0 + ra, d], Zt[z0 + c, d]
    return ra, identity


@njit(cache=True, _nrt=False)
def _factor(wk, m, rz, dq, pivot_tol):
    """The pivoted QR of ``A^T`` (``wk.AT0``, (rz, m)) into ``wk.AT``, and the residual ``r = e - J dq`` into
    ``wk.res``.

    Afterwards the columns of ``AT`` and ``res`` are in pivot order, ``AT[i, c]`` (``i < k``, ``i <= c``) is
    ``R[i, c]``, and reflection ``j`` is ``I - beta[j] v v^T`` with ``v = V[j, j:rz]``. Returns the rank ``k``: the
    pivots above ``pivot_tol``.
    """
    AT, res, norm2, exact = wk.AT, wk.res, wk.norm2, wk.norm2_exact
    for i in range(m):
        res[i] = wk.ew[i]
        norm2[i] = 0.0
    for d in range(dq.shape[0]):
        if dq[d] != 0.0 and wk.span[0, d] < wk.span[1, d]:
            axpy1(res, -dq[d], wk.JwT, d, wk.span[0, d], wk.span[1, d])
    for c in range(rz):
        a, a0 = AT[c, :m], wk.AT0[c, :m]
        for i in range(m):
            a[i] = a0[i]
            norm2[i] += a0[i] * a0[i]
    for i in range(m):
        exact[i] = norm2[i]
    for j in range(min(m, rz)):
        p = j
        for c in range(j + 1, m):
            if norm2[c] > norm2[p]:
                p = c
        if not math.sqrt(norm2[p]) > pivot_tol:
            return j
        if p != j:
            for i in range(rz):
                AT[i, j], AT[i, p] = AT[i, p], AT[i, j]
            res[j], res[p] = res[p], res[j]
            norm2[p], exact[p] = norm2[j], exact[j]
        _reflect_pivot(AT, j, rz, wk.V, wk.beta)
        reflect(AT, 0, wk.V, j, wk.beta[j], j, rz, j + 1, m, wk.w)
        for c in range(j + 1, m):
            norm2[c] -= AT[j, c] * AT[j, c]
            if norm2[c] <= _RECOMPUTE_BELOW * exact[c]:
                s = 0.0
                for i in range(j + 1, rz):
                    s += AT[i, c] * AT[i, c]
                norm2[c] = exact[c] = s
    return min(m, rz)


@njit(cache=True, _nrt=False)
def _reflect_pivot(AT, j, rz, V, beta):
    """The reflection ``I - beta[j] v v^T`` (``v = V[j, j:rz]``) that maps ``AT[j:rz, j]`` onto its first axis."""
    s2 = 0.0
    for i in range(j, rz):
        V[j, i] = AT[i, j]
        s2 += AT[i, j] * AT[i, j]
    x0 = AT[j, j]
    alpha = -math.sqrt(s2) if x0 >= 0.0 else math.sqrt(s2)
    V[j, j] = x0 - alpha
    beta[j] = 1.0 / (s2 - x0 * alpha)  # 2 / |v|^2, |v|^2 = 2 (s2 - x0 alpha)
    AT[j, j] = alpha
    for i in range(j + 1, rz):
        AT[i, j] = 0.0


@njit(cache=True, _nrt=False)
def _damped_solve(wk, m, k, damping):
    """``wk.y`` (k,) solving ``(R_k R_k^T + damping I) y = R_k P^T r``; returns ``k``, lowered while that matrix is
    not numerically positive definite (only without damping, at a level all but rank-deficient)."""
    AT, G, y = wk.AT, wk.G, wk.y  # R's rows: R[i, c] = AT[i, c] for c >= i
    while k > 0:
        for i in range(k):
            y[i] = dot1(AT, i, wk.res, i, m)
            for i2 in range(i + 1):
                G[i, i2] = dot(AT, i, AT, i2, i, m)
            G[i, i] += damping
        if _cholesky_solve(G, y, k):
            return k
        k -= 1
    return 0


@njit(cache=True, _nrt=False)
def _step_from(wk, k, rz, z0, identity):
    """``wk.step = Z Q [y; 0]`` (n,) over the first ``rz`` live directions, zero on the locked DOFs."""
    z, step = wk.z, wk.step
    n = step.shape[0]
    for i in range(rz):
        z[i] = wk.y[i] if i < k else 0.0
    for j in range(k - 1, -1, -1):
        b = -wk.beta[j] * dot1(wk.V, j, z, j, rz)
        for i in range(j, rz):
            z[i] += b * wk.V[j, i]
    if identity:  # the unseen directions, if any, are the last unit rows (left in place): no step along them
        for d in range(n):
            step[d] = z[d] if d < rz else 0.0
    else:
        step[:] = 0.0
        for c in range(rz):
            axpy1(step, z[c], wk.Zt, z0 + c, 0, n)
    for d in range(n):
        if wk.locked[d]:
            step[d] = 0.0


@njit(cache=True, _nrt=False)
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


@njit(cache=True, _nrt=False)
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
