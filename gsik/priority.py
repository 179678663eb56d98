"""Strict-priority bounded least squares: one linearised IK step over ordered task levels.

After Baerlocher and Boulic (2004), "An inverse kinematics architecture
enforcing an arbitrary number of strict priority levels". Level 0 is solved
first (damped least squares within the joint-limit box); every next level is
solved only in the null space that the levels above it leave, so it can never
change what they achieve (to first order). The box ``lo <= dq <= hi`` (the joint
limits and the step limit, as offsets from the current angles) is kept by an
active-set loop inside each level: the level's step is scaled back until the
first DOF reaches its bound, that DOF is locked for this level and all lower
ones, and the level is solved again in what remains. Locking only removes
freedom from the current and lower levels, never from the higher ones, so the
hierarchy stays strict and the limits are never crossed.

A preferred posture is the lowest level: minimise ``(q + dq - mu)^T P (q + dq - mu)``
(:func:`posture_level`), with ``P`` a full (n, n) precision matrix or per-DOF weights.

NumPy only: the systems are small (tens of DOFs), so an SVD per level costs
tens of microseconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

#: Singular values below this fraction of a level's largest are treated as zero: those
#: directions stay free for the lower levels.
RANK_TOLERANCE = 1e-9


class Level(NamedTuple):
    """One priority level of linearised tasks: minimise ``sum(weights * (jacobian @ dq - error)**2)``.

    Attributes:
        jacobian: (m, n_dofs) rows of the level's tasks.
        error: (m,) what the rows should change by (target minus current).
        weights: (m,) row weights (>= 0) trading rows off within the level.
    """

    jacobian: np.ndarray
    error: np.ndarray
    weights: np.ndarray


def posture_level(q: np.ndarray, reference: np.ndarray, precision: np.ndarray) -> Level:
    """The level minimising ``(q + dq - reference)^T P (q + dq - reference)``.

    Args:
        q: Current angles (n,) [rad].
        reference: Preferred angles (n,) [rad].
        precision: ``P``: per-DOF weights (n,) or a symmetric positive
            semi-definite matrix (n, n) (e.g. an inverse covariance).

    Returns:
        A :class:`Level` with ``jacobian = L`` where ``P = L^T L``.
    """
    return factor_level(q, reference, posture_factor(precision))


def posture_factor(precision: np.ndarray) -> np.ndarray:
    """``L`` (n, n) with ``P = L^T L``, for per-DOF weights (n,) or a PSD matrix (n, n); factor once, step often."""
    P = np.asarray(precision, dtype=float)
    if P.ndim == 1:
        return np.diag(np.sqrt(P))
    vals, vecs = np.linalg.eigh(0.5 * (P + P.T))
    return np.sqrt(np.clip(vals, 0.0, None))[:, None] * vecs.T


def factor_level(q: np.ndarray, reference: np.ndarray, factor: np.ndarray) -> Level:
    """:func:`posture_level` from a precision already factored by :func:`posture_factor`."""
    g = np.asarray(reference, dtype=float) - np.asarray(q, dtype=float)
    return Level(factor, factor @ g, np.ones(factor.shape[0]))


def prioritized_step(levels: Sequence[Level], lo: np.ndarray, hi: np.ndarray,
                     damping: float | Sequence[float]) -> np.ndarray:
    """The step ``dq`` (n,) [rad] solving ``levels`` in strict priority order within ``lo <= dq <= hi``.

    Each level is a damped least-squares problem ``min |W^(1/2) (J dq - e)|^2 + damping |dq_level|^2``
    restricted to the directions the higher levels leave free and the DOFs not
    locked at a bound. ``lo <= 0 <= hi`` (n,) is required. ``damping`` is one
    value for every level or one per level.
    """
    lo = np.asarray(lo, dtype=float)
    hi = np.asarray(hi, dtype=float)
    n = lo.shape[0]
    dq = np.zeros(n)
    locked = np.zeros(n, dtype=bool)
    Z = np.eye(n)  # orthonormal basis (n, r) of the directions still free
    dampings = np.broadcast_to(np.asarray(damping, dtype=float), (len(levels),))
    for level, lam in zip(levels, dampings):
        if Z.shape[1] == 0:
            break
        sw = np.sqrt(np.asarray(level.weights, dtype=float))
        J = sw[:, None] * np.asarray(level.jacobian, dtype=float)
        e = sw * np.asarray(level.error, dtype=float)
        dq, Z = _solve_level(J, e, dq, Z, locked, lo, hi, lam)
    return np.clip(dq, lo, hi)  # rounding only: the loop keeps dq in the box


def _solve_level(J, e, dq, Z, locked, lo, hi, damping):
    """One level's active-set loop (updates ``locked``); returns the new ``dq`` and the basis left free below it."""
    while True:
        U, s, Vt = np.linalg.svd(J @ Z, full_matrices=True)
        rank = int(np.sum(s > RANK_TOLERANCE * (s[0] if s.size else 0.0))) if s.size else 0
        z = Vt[:rank].T @ ((s[:rank] / (s[:rank] ** 2 + damping)) * (U[:, :rank].T @ (e - J @ dq)))
        step = Z @ z
        step[locked] = 0.0
        alpha, blocking = _largest_fraction(dq, step, lo, hi)
        if blocking < 0:
            return dq + step, Z @ Vt[rank:].T
        dq = dq + alpha * step
        dq[blocking] = hi[blocking] if step[blocking] > 0 else lo[blocking]
        locked[blocking] = True
        Z = _without_dof(Z, blocking)
        if Z.shape[1] == 0:
            return dq, Z


def _largest_fraction(dq, step, lo, hi) -> tuple[float, int]:
    """The largest ``alpha <= 1`` keeping ``dq + alpha * step`` in the box, and the DOF that blocks (-1: none)."""
    over = dq + step
    out = np.flatnonzero((over > hi) | (over < lo))
    if out.size == 0:
        return 1.0, -1
    s = step[out]
    room = np.where(s > 0, hi[out] - dq[out], lo[out] - dq[out]) / s  # s != 0 where dq + s left the box
    k = int(np.argmin(room))
    return max(float(room[k]), 0.0), int(out[k])


def _without_dof(Z: np.ndarray, dof: int) -> np.ndarray:
    """Basis of the directions of ``span(Z)`` that leave DOF ``dof`` unchanged."""
    row = Z[dof]
    norm = np.linalg.norm(row)
    if norm < 1e-12:
        return Z
    # A Householder reflection maps row/|row| onto the first axis; the other columns span its complement.
    u = row / norm
    u[0] += 1.0 if u[0] >= 0 else -1.0
    Z = Z - np.outer(Z @ u, u) * (2.0 / (u @ u))
    Z[dof] = 0.0  # exactly, not to rounding
    return Z[:, 1:]
