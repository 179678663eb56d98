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

:func:`prioritized_step` runs compiled (:mod:`gsik.kernels.priority`: a pivoted
QR per level, a few microseconds); :func:`prioritized_step_svd` is the same step
in NumPy with an SVD per level (hundreds of microseconds), the reference the
tests and benchmarks check the kernel against.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from gsik.kernels import priority as kernel

#: Singular values (of a level's rows seen in the directions the higher levels leave) below this fraction of the
#: level's largest weighted row norm are treated as zero: those directions stay free for the lower levels. Measured
#: against the rows themselves, not against what is left of them: a level the higher ones already decide entirely
#: leaves only rounding (1e-17), which must not take directions from the levels below.
RANK_TOLERANCE = 1e-9
#: A step may leave the box by this much [rad] (plus :data:`BOX_RELATIVE_TOLERANCE` times its largest component)
#: without blocking, and a DOF this close to a bound is on it: rounding, which clipping removes.
#: A DOF resting on a limit that a level does not move at all gets steps of 1e-17 either way; locking it on their
#: sign, or choosing between DOFs on their bounds by rooms of 1e-18, made the step depend on rounding (and took that
#: DOF from every lower level).
BOX_TOLERANCE = 1e-12
#: The rounding of a step grows with its size (a tight box under a large step: 1e-11 seen on DOFs the level leaves).
BOX_RELATIVE_TOLERANCE = 1e-10


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


class PackedLevels(NamedTuple):
    """Levels as the kernel reads them: every level's rows one below the other.

    Attributes:
        rows: (M, n_dofs) the Jacobian rows. errors, weights: (M,).
        starts: (L + 1,) int64: level ``l`` is rows ``starts[l]:starts[l + 1]``.
    """

    rows: np.ndarray
    errors: np.ndarray
    weights: np.ndarray
    starts: np.ndarray


def pack_levels(levels: Sequence[Level], n_dofs: int) -> PackedLevels:
    """The :class:`PackedLevels` of ``levels`` (fresh C-ordered float64 arrays)."""
    starts = np.zeros(len(levels) + 1, dtype=np.int64)
    end = 0
    for i, level in enumerate(levels):
        end += len(level.error)
        starts[i + 1] = end
    rows, errors, weights = np.empty((end, n_dofs)), np.empty(end), np.empty(end)
    for i, level in enumerate(levels):  # slice by slice: cheaper than concatenating, for a handful of levels
        a, b = starts[i], starts[i + 1]
        rows[a:b] = level.jacobian
        errors[a:b] = level.error
        weights[a:b] = level.weights
    return PackedLevels(rows, errors, weights, starts)


def prioritized_step(levels: Sequence[Level], lo: np.ndarray, hi: np.ndarray,
                     damping: float | Sequence[float]) -> np.ndarray:
    """The step ``dq`` (n,) [rad] solving ``levels`` in strict priority order within ``lo <= dq <= hi``.

    Each level is a damped least-squares problem ``min |W^(1/2) (J dq - e)|^2 + damping |dq_level|^2``
    restricted to the directions the higher levels leave free and the DOFs not
    locked at a bound. ``lo <= 0 <= hi`` (n,) is required. ``damping`` is one
    value for every level or one per level.

    Raises:
        numpy.linalg.LinAlgError: if a level's weighted Jacobian, seen in the directions left to it,
            holds a non-finite number.
    """
    lo = np.array(lo, dtype=float)
    hi = np.array(hi, dtype=float)
    dampings = np.array(damping, dtype=float)
    if dampings.shape != (len(levels),):
        dampings = np.array(np.broadcast_to(dampings, (len(levels),)))
    packed = pack_levels(levels, lo.shape[0])
    dq = np.empty(lo.shape[0])
    if kernel.prioritized_step(*packed, dampings, lo, hi, RANK_TOLERANCE, BOX_TOLERANCE, BOX_RELATIVE_TOLERANCE,
                                 dq) != kernel.OK:
        raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
    return dq


def prioritized_step_svd(levels: Sequence[Level], lo: np.ndarray, hi: np.ndarray,
                         damping: float | Sequence[float]) -> np.ndarray:
    """:func:`prioritized_step` in NumPy, an SVD per level: the reference the kernel is checked against."""
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
    scale = float(np.sqrt((J * J).sum(axis=1)).max()) if J.size else 0.0
    while True:
        dq = _into_box(dq, lo, hi)
        U, s, Vt = np.linalg.svd(J @ Z, full_matrices=True)
        rank = int(np.sum(s > RANK_TOLERANCE * scale))
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


def _into_box(dq, lo, hi) -> np.ndarray:
    """``dq`` clipped into the box, and put on a bound where within :data:`BOX_TOLERANCE` of it: rounding only, but
    then every DOF resting on a bound has room 0 exactly, and a tie is broken by the DOF's index, not by rounding."""
    dq = np.clip(dq, lo, hi)
    dq = np.where(dq - lo <= BOX_TOLERANCE, lo, dq)
    return np.where(hi - dq <= BOX_TOLERANCE, hi, dq)


def _largest_fraction(dq, step, lo, hi) -> tuple[float, int]:
    """The largest ``alpha <= 1`` keeping ``dq + alpha * step`` in the box, and the DOF that blocks (-1: none)."""
    over = dq + step
    tol = BOX_TOLERANCE + BOX_RELATIVE_TOLERANCE * float(np.abs(step).max(initial=0.0))
    out = np.flatnonzero((over > hi + tol) | (over < lo - tol))
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
