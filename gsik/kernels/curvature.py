"""The targets' curvature in the posture's level of a solve()'s settle steps: a quasi-Newton Lagrangian Hessian.

A solve() with a posture settles it by prioritised steps: each solves the posture's level, ``min |L (q + dq - ref)|^2``
in the free directions the target levels leave, by its normal equations with ``P = L^T L``
(:mod:`gsik.kernels.posture_level`). That is a Gauss-Newton step of the constrained problem ``min f(q)`` subject to
the targets ``c(q) = 0``: it leaves out the constraints' curvature ``sum_i lam_i hess c_i``, so where the targets
pull hard (long arms, the hands far from the posture's) the posture closes in by a fixed fraction a step (0.3-0.8
measured on bench_drag's drags) and the settle test runs 4-10 steps. A Newton step of the Lagrangian would take
``B = P + sum_i lam_i hess c_i`` instead of ``P``.

:func:`learn` builds ``B`` by BFGS from the steps themselves: after a step ``s = q1 - q0`` the Lagrangian's gradient
changed by ``y = P s + (J(q1) - J(q0))^T lam`` (``J`` the target rows' Jacobian, ``lam`` their least-squares
multipliers at ``q1``: ``J^T lam`` is minus the posture's gradient ``P (q1 - ref)`` projected onto the rows' span),
and ``B`` is updated so that ``B s = y``, with Powell's damping (Nocedal & Wright, Procedure 18.2) keeping it
symmetric positive definite when the curvature along ``s`` is negative. The solve swaps ``B`` for ``P`` in the
posture's level during its settle steps only (:class:`gsik.control_settle.ControlSettle`); its costs, the acceptance
rule and the settle test keep reading the true posture, so only the path to the settled pose changes, not what
settles. A drag's warm solves carry ``B`` from one frame to the next: the curvature moves little between frames.

The kernels allocate nothing and are compiled without numba's reference counting (``_nrt=False``, as in
:mod:`gsik.kernels.kinematics`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik._jit import njit
from gsik.kernels.kinematics import jacobian
from gsik.kernels.pgs import _cholesky_solve
from gsik.kernels.rows import dot, dot1
from gsik.kernels.step import copy_into, copy_rows

#: Powell's damping: a step whose curvature ``s^T y`` is below this fraction of ``s^T B s`` updates ``B`` with ``y``
#: blended towards ``B s`` until it is exactly that fraction (Nocedal & Wright's 0.2).
POWELL_FRACTION = 0.2
#: The multipliers' normal matrix ``J J^T`` gets this fraction of its mean diagonal on its diagonal: a rank-deficient
#: ``J`` (a stretched arm) still has a least-squares solution, and a full one's moves by that fraction only.
MULTIPLIER_DAMPING = 1e-9
# Indices of Curvature.state: steps learnt since B was last P; B is in the posture's level (a settle runs, 1.0 / 0.0);
# the targets were met at q0 (1.0 / 0.0).
S_LEARNT, S_ON, S_MET = range(3)


class Curvature(NamedTuple):
    """A controller's quasi-Newton Lagrangian Hessian and its work arrays (:func:`make_curvature`).

    Attributes:
        P: (n, n) the posture's own normal matrix (``PostureRows.normal``, kept: the steps' ``normal`` holds ``B``
            while a solve settles). B: (n, n) the Hessian learnt (``P`` before any step).
        q0: (n,) [rad] the pose ``J0`` is at. J0, J1: (6m, n) the targets' Jacobian at ``q0`` and after a step.
        G: (M, M) the multipliers' normal matrix, lam: (M,) the multipliers (M: the packed target rows).
        g, s, y, Bs: (n,) the posture's gradient, the step [rad], the gradient's change, ``B s``.
        state: (3,) the ``S_*`` figures.
    """

    P: np.ndarray
    B: np.ndarray
    q0: np.ndarray
    J0: np.ndarray
    J1: np.ndarray
    G: np.ndarray
    lam: np.ndarray
    g: np.ndarray
    s: np.ndarray
    y: np.ndarray
    Bs: np.ndarray
    state: np.ndarray


def make_curvature(normal: np.ndarray, task_rows: int) -> Curvature:
    """A :class:`Curvature` for a posture of normal matrix ``normal`` (n, n) below ``task_rows`` (6m) target error
    rows (at most that many packed); ``B`` starts at ``P``."""
    n = normal.shape[0]
    P = np.array(normal, dtype=float)
    return Curvature(P, P.copy(), np.zeros(n), np.zeros((task_rows, n)), np.zeros((task_rows, n)),
                     np.zeros((task_rows, task_rows)), np.zeros(task_rows), np.zeros(n), np.zeros(n), np.zeros(n),
                     np.zeros(n), np.zeros(3))


@njit(cache=True, _nrt=False)
def begin(cur, normal, carry, met, task_model, q, R, p):
    """A settle's start at ``q`` (n,) [rad] (world frames ``R``, ``p``; ``met``: every target within its tolerances
    there): ``B`` swapped into the posture's level (``normal`` (n, n), which holds ``P`` until :func:`end`), from the
    last settle's (``carry``) or from ``P``; where the targets are met, their Jacobian at ``q`` into ``cur.J0`` (a
    step from an unmet pose teaches nothing: :func:`learn`)."""
    if not carry:
        copy_rows(cur.B, cur.P)
        cur.state[S_LEARNT] = 0.0
    copy_rows(normal, cur.B)
    cur.state[S_ON] = 1.0
    cur.state[S_MET] = 1.0 if met else 0.0
    if met:
        jacobian(task_model, R, p, cur.J0)
    copy_into(cur.q0, q)


@njit(cache=True, _nrt=False)
def end(cur, normal):
    """A settle's end: ``B`` (learnt into ``normal``) kept, the posture's own ``P`` back in ``normal``. Once: a
    second call changes nothing."""
    if cur.state[S_ON] == 0.0:
        return
    copy_rows(cur.B, normal)
    copy_rows(normal, cur.P)
    cur.state[S_ON] = 0.0


@njit(cache=True, _nrt=False)
def learn(cur, task_model, packed_row, reference, q, R, p, B, met):
    """Update ``B`` (n, n) (the posture's ``normal`` while a settle runs), in place, by the step from ``cur.q0`` to
    ``q`` (n,) [rad] (world frames ``R``, ``p``), then go on from ``q``. ``packed_row`` (M,): the target rows' error
    rows (a controller with balance, whose rows are filled per step, never learns); ``reference`` (n,): the
    posture's angles [rad]. No step (``q`` is ``q0``): nothing changes. Only a step that starts and ends with
    every target within its tolerances (``met`` at ``q``, ``cur.state[S_MET]`` at ``q0``) updates ``B``: the
    multipliers model targets that are met (an unreachable hand's residual is no constraint's force; with one, a
    cold solve's settle stays Gauss-Newton's). Returns True if ``B`` was updated."""
    n = q.shape[0]
    s, moved = cur.s, False
    for d in range(n):
        s[d] = q[d] - cur.q0[d]
        moved = moved or s[d] != 0.0
    if not moved:
        return False
    updated = False
    if met:  # J0 is read only from a met pose: an unmet one's Jacobian is not made
        jacobian(task_model, R, p, cur.J1)
        if cur.state[S_MET] > 0.0:  # both ends of the step on the targets
            _multipliers(cur, packed_row, reference, q)
            updated = _bfgs(cur, packed_row, B)
        copy_rows(cur.J0, cur.J1)
    cur.state[S_MET] = 1.0 if met else 0.0
    copy_into(cur.q0, q)
    if updated:
        cur.state[S_LEARNT] += 1.0
    return updated


@njit(cache=True, _nrt=False)
def _multipliers(cur, packed_row, reference, q):
    """``cur.lam`` (M,): the least-squares multipliers of the target rows at ``q``, ``J1^T lam = -P (q - ref)``
    projected onto the rows' span (``(J1 J1^T + damping I) lam = -J1 g``, :data:`MULTIPLIER_DAMPING`); 0 where that
    matrix is not numerically positive definite."""
    n, M = q.shape[0], packed_row.shape[0]
    P, g, J, G, lam, d_ = cur.P, cur.g, cur.J1, cur.G, cur.lam, cur.y
    for d in range(n):
        d_[d] = q[d] - reference[d]
    for d in range(n):
        g[d] = dot1(P, d, d_, 0, n)
    trace = 0.0
    for i in range(M):
        ri = packed_row[i]
        lam[i] = -dot1(J, ri, g, 0, n)
        for j in range(i + 1):
            G[i, j] = dot(J, ri, J, packed_row[j], 0, n)
        trace += G[i, i]
    damping = MULTIPLIER_DAMPING * trace / max(M, 1) + 1e-300
    for i in range(M):
        G[i, i] += damping
    if not _cholesky_solve(G, lam, M):
        lam[:] = 0.0


@njit(cache=True, _nrt=False)
def _bfgs(cur, packed_row, B):
    """``B`` (n, n) updated by BFGS with Powell's damping on ``s = cur.s`` and ``y = P s + (J1 - J0)^T lam``
    (symmetric: the lower triangle computed, mirrored); False (``B`` left) when ``s^T B s`` is not positive or the
    update is not finite."""
    n = B.shape[0]
    s, y, Bs = cur.s, cur.y, cur.Bs
    for d in range(n):
        y[d] = dot1(cur.P, d, s, 0, n)
    for i in range(packed_row.shape[0]):
        r, li = packed_row[i], cur.lam[i]
        if li != 0.0:
            for d in range(n):
                y[d] += (cur.J1[r, d] - cur.J0[r, d]) * li
    sBs = sy = 0.0
    for d in range(n):
        Bs[d] = dot1(B, d, s, 0, n)
        sBs += s[d] * Bs[d]
        sy += s[d] * y[d]
    if not (sBs > 0.0 and sBs < np.inf):
        return False
    theta = 1.0 if sy >= POWELL_FRACTION * sBs else (1.0 - POWELL_FRACTION) * sBs / (sBs - sy)
    sr = 0.0
    for d in range(n):
        y[d] = theta * y[d] + (1.0 - theta) * Bs[d]  # Powell's r, in y's place
        sr += s[d] * y[d]
    if not (sr > 0.0 and sr < np.inf):
        return False
    a, b = 1.0 / sr, 1.0 / sBs
    for i in range(n):
        yi, bi = a * y[i], b * Bs[i]
        for j in range(i + 1):
            v = B[i, j] + yi * y[j] - bi * Bs[j]
            B[i, j] = v
            B[j, i] = v
    return True
