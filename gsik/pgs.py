"""Projected Gauss-Seidel for bounded linear systems, as a standalone function.

The solver calls the kernels directly; this is the checked, public door to
the same code, for tests and for anyone who wants PGS alone.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.kernels import N_STATS, O_RESIDUAL, O_SWEEPS, O_UPDATE
from gsik.kernels import pgs as kernels
from gsik.errors import SolverError


class PgsInfo(NamedTuple):
    """How a PGS run ended: sweeps done, last projected residual ``|Ax - b|``, last sweep's ``|dx|``."""

    sweeps: int
    residual: float
    update: float


def _bound(value, n: int, none: float) -> np.ndarray:
    """A bound (n,): ``value`` broadcast, or ``none`` everywhere when it is None."""
    return np.full(n, none) if value is None else np.ascontiguousarray(np.broadcast_to(value, (n,)), dtype=float)


def _check(A, b, lower, upper, x0) -> tuple[np.ndarray, ...]:
    A = np.ascontiguousarray(A, dtype=float)
    b = np.ascontiguousarray(b, dtype=float)
    n = b.shape[0] if b.ndim == 1 else -1
    if b.ndim != 1 or A.shape != (n, n):
        raise SolverError(f"PGS needs A of shape (n, n) and b of shape (n,), got {A.shape} and {b.shape}")
    lo, hi = _bound(lower, n, -np.inf), _bound(upper, n, np.inf)
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(b))):
        raise SolverError("PGS needs finite A and b")
    if np.any(np.diag(A) <= 0):
        raise SolverError("PGS needs a positive diagonal (A should be symmetric positive definite)")
    if np.any(lo > hi):
        i = int(np.flatnonzero(lo > hi)[0])
        raise SolverError(f"lower bound {lo[i]} is above upper bound {hi[i]} for unknown {i}")
    x = np.zeros(n) if x0 is None else np.array(x0, dtype=float).reshape(n)
    return A, b, lo, hi, np.clip(x, lo, hi)


def projected_gauss_seidel(
    A: np.ndarray,
    b: np.ndarray,
    lower: np.ndarray | None = None,
    upper: np.ndarray | None = None,
    x0: np.ndarray | None = None,
    x_prev: np.ndarray | None = None,
    sweeps: int = 100,
    residual_tolerance: float = 1e-10,
    update_tolerance: float = 1e-10,
    stall_tolerance: float = 0.0,
) -> tuple[np.ndarray, PgsInfo]:
    """Solve ``A x = b`` (A (n, n) SPD, b (n,)) with ``lower <= x <= upper`` by PGS.

    Each unknown is clamped into its bounds as it is updated. The sweeps
    stop at the first of the paper's four tests: ``sweeps`` done, projected
    ``|Ax - b| < residual_tolerance``, a sweep's ``|dx| < update_tolerance``,
    ``|x - x_prev| < stall_tolerance`` (0 disables a tolerance test).

    Returns:
        The solution (n,) and a :class:`PgsInfo`.
    """
    A, b, lo, hi, x = _check(A, b, lower, upper, x0)
    prev = np.zeros_like(x) if x_prev is None else np.ascontiguousarray(x_prev, dtype=float)
    stats = np.zeros(N_STATS)
    kernels.projected_gauss_seidel(A, b, x, lo, hi, int(sweeps), float(residual_tolerance),
                                    float(update_tolerance), prev, float(stall_tolerance), stats)
    return x, PgsInfo(int(stats[O_SWEEPS]), float(stats[O_RESIDUAL]),
                      float(stats[O_UPDATE]))


def solve_bounded(A: np.ndarray, b: np.ndarray, lower: np.ndarray | None = None, upper: np.ndarray | None = None,
                  sweeps: int = 10) -> tuple[np.ndarray, PgsInfo]:
    """The exact minimiser of ``0.5 x^T A x - b^T x`` within the bounds: PGS plus subspace minimisation.

    ``sweeps`` PGS sweeps find the active bounds; the free unknowns are then
    solved exactly (Cholesky) and projected, a few rounds. This is what
    :meth:`gsik.Solver.solve` uses on each linearisation.
    """
    A, b, lo, hi, x = _check(A, b, lower, upper, None)
    stats = np.zeros(N_STATS)
    kernels.bounded_solve(A, b, x, lo, hi, int(sweeps), stats)
    return x, PgsInfo(int(stats[O_SWEEPS]), float(stats[O_RESIDUAL]),
                      float(stats[O_UPDATE]))
