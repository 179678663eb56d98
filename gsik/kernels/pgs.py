"""Projected Gauss-Seidel kernels: the paper's sweeps, and the exact bounded minimiser.

Both work in place on ``x`` and write sweeps, residual and last change into
``stats`` (indices :data:`~gsik.kernels.O_SWEEPS` ...). The kernels that allocate nothing are compiled without
numba's reference counting (``_nrt=False``, as in :mod:`gsik.kernels.kinematics`).
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit
from gsik.kernels import O_RESIDUAL, O_SWEEPS, O_UPDATE


@njit(cache=True, inline="always")
def _row_residual(A, b, x, i, n):
    """``b[i] - A[i] @ x`` with four accumulators: the add chain, not the multiplies, bounds a sweep."""
    r0 = b[i]
    r1 = 0.0
    r2 = 0.0
    r3 = 0.0
    j = 0
    while j + 4 <= n:
        r0 -= A[i, j] * x[j]
        r1 -= A[i, j + 1] * x[j + 1]
        r2 -= A[i, j + 2] * x[j + 2]
        r3 -= A[i, j + 3] * x[j + 3]
        j += 4
    while j < n:
        r0 -= A[i, j] * x[j]
        j += 1
    return (r0 + r1) + (r2 + r3)


@njit(cache=True, _nrt=False)
def _projected_residual(A, b, x, lo, hi):
    """``|b - A x|`` over the unknowns not held at a bound by an outward-pointing residual."""
    res2 = 0.0
    n = b.shape[0]
    for i in range(n):
        r = _row_residual(A, b, x, i, n)
        if not ((x[i] <= lo[i] and r < 0.0) or (x[i] >= hi[i] and r > 0.0)):
            res2 += r * r
    return math.sqrt(res2)


@njit(cache=True, _nrt=False)
def projected_gauss_seidel(A, b, x, lo, hi, sweeps, res_tol, upd_tol, x_prev, stall_tol, stats):
    """Projected Gauss-Seidel on ``A x = b`` with ``lo <= x <= hi``, in place on ``x``.

    Stops at the first of the paper's four tests: ``sweeps`` done; the
    projected residual ``|b - A x|`` below ``res_tol``; the sweep's change
    ``|dx|`` below ``upd_tol``; ``|x - x_prev|`` (the previous frame's
    solution) below ``stall_tol``. A tolerance <= 0 disables its test.
    Writes sweeps, residual and last change into ``stats``.
    """
    n = b.shape[0]
    res = 0.0
    upd = 0.0
    it = 0
    for it in range(1, sweeps + 1):
        res2 = 0.0
        upd2 = 0.0
        for i in range(n):
            r = _row_residual(A, b, x, i, n)
            xi = x[i] + r / A[i, i]
            if xi < lo[i]:
                xi = lo[i]
            elif xi > hi[i]:
                xi = hi[i]
            # A component held at a bound by a residual pushing outward satisfies its KKT condition.
            if not ((xi <= lo[i] and r < 0.0) or (xi >= hi[i] and r > 0.0)):
                res2 += r * r
            dx = xi - x[i]
            upd2 += dx * dx
            x[i] = xi
        res = math.sqrt(res2)
        upd = math.sqrt(upd2)
        if upd < upd_tol:
            break
        if res < res_tol:
            # The in-sweep estimate lags (each r_i saw only part of the sweep's updates); confirm it.
            res = _projected_residual(A, b, x, lo, hi)
            if res < res_tol:
                break
        if stall_tol > 0.0:
            d2 = 0.0
            for i in range(n):
                d2 += (x[i] - x_prev[i]) ** 2
            if math.sqrt(d2) < stall_tol:
                break
    stats[O_SWEEPS] = it
    stats[O_RESIDUAL] = res
    stats[O_UPDATE] = upd


@njit(cache=True, _nrt=False)
def _cholesky_solve(M, r, nf):
    """Solve ``M[:nf, :nf] y = r[:nf]`` in place in ``r`` (M SPD; overwritten). False if not SPD."""
    for j in range(nf):
        d = M[j, j]
        for k in range(j):
            d -= M[j, k] * M[j, k]
        if d <= 0.0:
            return False
        d = math.sqrt(d)
        M[j, j] = d
        for i in range(j + 1, nf):
            v = M[i, j]
            for k in range(j):
                v -= M[i, k] * M[j, k]
            M[i, j] = v / d
    for i in range(nf):
        v = r[i]
        for k in range(i):
            v -= M[i, k] * r[k]
        r[i] = v / M[i, i]
    for i in range(nf - 1, -1, -1):
        v = r[i]
        for k in range(i + 1, nf):
            v -= M[k, i] * r[k]
        r[i] = v / M[i, i]
    return True


@njit(cache=True, inline="always")
def strictly_inside(x, lo, hi):
    """True if every ``x[i]`` lies strictly between ``lo[i]`` and ``hi[i]``."""
    for i in range(x.shape[0]):
        if not (lo[i] < x[i] and x[i] < hi[i]):
            return False
    return True


@njit(cache=True, inline="always")
def _free_set(A, b, x, lo, hi, free):
    """Indices into ``free`` of the unknowns off their bounds or pulled inward by the gradient; returns their count."""
    nf = 0
    for i in range(b.shape[0]):
        g = -b[i]
        for j in range(b.shape[0]):
            g += A[i, j] * x[j]
        if (x[i] > lo[i] and x[i] < hi[i]) or (x[i] <= lo[i] and g < 0.0) or (x[i] >= hi[i] and g > 0.0):
            free[nf] = i
            nf += 1
    return nf


@njit(cache=True, inline="always")
def _reduced_system(A, b, x, free, nf, is_free, M, r):
    """``M[:nf, :nf] y = r[:nf]``: the free unknowns' system with the bound ones held at ``x``."""
    n = b.shape[0]
    is_free[:] = False
    for a in range(nf):
        is_free[free[a]] = True
    for a in range(nf):
        i = free[a]
        v = b[i]
        for j in range(n):
            if not is_free[j]:
                v -= A[i, j] * x[j]
        r[a] = v
        for c in range(nf):
            M[a, c] = A[i, free[c]]


@njit(cache=True, inline="always")
def _place_free(r, x, lo, hi, free, nf):
    """Write the free unknowns' solution ``r`` into ``x``, clamped; True if none needed clamping."""
    inside = True
    for a in range(nf):
        i = free[a]
        v = r[a]
        if v < lo[i]:
            v = lo[i]
            inside = False
        elif v > hi[i]:
            v = hi[i]
            inside = False
        x[i] = v
    return inside


@njit(cache=True)
def bounded_solve(A, b, x, lo, hi, sweeps, stats):
    """Minimise ``0.5 x^T A x - b^T x`` with ``lo <= x <= hi``: PGS with subspace minimisation.

    PGS sweeps find which unknowns sit on a bound; the others (the free set)
    are then solved exactly by Cholesky and projected back into the box,
    a few rounds, and a last PGS pass settles the bounds. Plain PGS needs
    thousands of sweeps on the ill-conditioned systems near a solution;
    this reaches the exact bounded minimiser in a few rounds. Its work arrays are made here
    (:func:`bounded_solve_in` takes them from the caller).
    """
    n = b.shape[0]
    bounded_solve_in(A, b, x, lo, hi, sweeps, stats, np.empty(n, dtype=np.int64), np.zeros(n, dtype=np.bool_),
                     np.empty((n, n)), np.empty(n))


@njit(cache=True, _nrt=False)
def bounded_solve_in(A, b, x, lo, hi, sweeps, stats, free, is_free, M, r, until_inside=False):
    """:func:`bounded_solve` with its work arrays given (contents unused, none read before it writes them): the
    free set's indices ``free`` (n,) int64, its mask ``is_free`` (n,) bool, its system ``M`` (n, n) and right-hand
    side ``r`` (n,). A frame step holds them between calls (four allocations fewer a linearisation). Returns True
    when ``x`` holds the answer.

    With ``until_inside`` the first sweeps (up to ``sweeps``) stop at one that leaves every unknown strictly inside
    its bounds: they only guess which unknowns the exact solve holds at a bound, and that guess is then "none".
    If the whole system's exact answer lies inside the bounds it is the answer (the box's minimiser: the sweeps
    after it would only move its rounding); if not, returns False with ``x`` spoilt, and the caller solves again
    from its start without ``until_inside`` (the same numbers as always where a bound is active)."""
    total = 0
    if until_inside:
        for _ in range(sweeps):
            projected_gauss_seidel(A, b, x, lo, hi, 1, 0.0, 0.0, x, 0.0, stats)
            total += 1
            if strictly_inside(x, lo, hi):
                return _whole_inside(A, b, x, lo, hi, stats, total, free, is_free, M, r)
    else:
        projected_gauss_seidel(A, b, x, lo, hi, sweeps, 0.0, 0.0, x, 0.0, stats)
        total = int(stats[O_SWEEPS])
    for _ in range(8):
        nf = _free_set(A, b, x, lo, hi, free)
        if nf == 0:
            break
        _reduced_system(A, b, x, free, nf, is_free, M, r)
        if not _cholesky_solve(M, r, nf):
            break
        if _place_free(r, x, lo, hi, free, nf):
            break
    projected_gauss_seidel(A, b, x, lo, hi, 3, 0.0, 0.0, x, 0.0, stats)
    stats[O_SWEEPS] = total + int(stats[O_SWEEPS])
    return True


@njit(cache=True, inline="always")
def _whole_inside(A, b, x, lo, hi, stats, sweeps, free, is_free, M, r):
    """The whole system's exact answer into ``x`` (clamped); True if it lies inside the bounds, then with the
    ``sweeps`` done, its projected residual and no last change in ``stats``."""
    n = b.shape[0]
    for i in range(n):
        free[i] = i
    _reduced_system(A, b, x, free, n, is_free, M, r)
    if not (_cholesky_solve(M, r, n) and _place_free(r, x, lo, hi, free, n)):
        return False
    stats[O_SWEEPS] = sweeps
    stats[O_RESIDUAL] = _projected_residual(A, b, x, lo, hi)
    stats[O_UPDATE] = 0.0
    return True
