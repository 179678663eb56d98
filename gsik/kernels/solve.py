"""One attempt of a full solve: Levenberg-Marquardt over bounded steps, positions first.

Why positions first: from the rest pose, a descent on all rows at once ends,
in 60% of random full-body 6-DOF reaches, at a point where the joint limits
hold it (a first-order stationary point of the bounded problem, typically with
a third of the DOFs on a limit): no step, however damped, lowers the error.
Step limit, damping schedule, gain-ratio acceptance, the exact Jacobian of
the rotation error and limit-avoiding damping all leave it there (measured:
36-41% either way). Without joint limits the same descent converges 95% of the
time, to poses far outside them. What steers it into the right basin is the
order: meet the effector positions first (the orientation rows off, so the
limbs are free to turn), then everything; and when that stalls, again from
where it stalled while that keeps lowering the error. See benchmarks/bench_reach.py.
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit
from gsik.kernels import (BUDGET_EXHAUSTED, CONVERGED, N_STATS, O_COST, O_FINITE, O_ITERATIONS, O_STATUS,
                          O_STEP_NORM, O_SWEEPS, STALLED, KernelSettings, TargetArrays, make_scratch)
from gsik.kernels.kinematics import linear_system
from gsik.kernels.pgs import bounded_solve_in, projected_gauss_seidel
from gsik.kernels.step import (_add_clamped, _bounds, _evaluate, _finish_errors, _finite, copy_into, copy_rows,
                               norm_of, take_frames)

#: Share of an attempt's linearisations the positions-only phase may use.
POSITION_PHASE_SHARE = 0.3
#: The positions-only phase ends once every position is within this [m] (or the tolerance, if coarser).
POSITION_PHASE_TOLERANCE = 0.03
#: Positions go first only when some orientation is this far from its target [rad]: near a solution (tracking,
#: small drags) the full problem is already well linearised, and the extra phase would double the work.
STAGE_ANGLE = 0.5
#: A phase has settled when its last SETTLE_WINDOW linearisations together lowered the error by less than
#: SETTLE_WINDOW_GAIN (relative): a best reach creeps by a little more than settle_tolerance per step for
#: hundreds of steps, gaining nothing visible (held hand 3 m away: 0.5% in 140 linearisations).
SETTLE_WINDOW = 10
SETTLE_WINDOW_GAIN = 1e-3
#: A new positions-then-everything round is made only if the last one lowered the error by more than this fraction.
ROUND_GAIN = 1e-2


@njit(cache=True, inline="always")
def _trial(model, settings, targets, root, W, q, lam, ws, sc, pgs_stats):
    """Solve ``(A + lam I) x = b`` within the limits, scale ``x`` to the step bound, evaluate ``q + x``.

    The trial's frames and errors go into ``sc.*_new``; returns ``(cost, sweeps)``.
    """
    n = q.shape[0]
    x = sc.x_solve
    copy_rows(sc.A_damped, sc.A)
    for i in range(n):
        sc.A_damped[i, i] += lam
    if settings.warm_start:  # from the last step taken, as a frame step starts from the last frame's
        for i in range(n):
            x[i] = min(max(sc.x_prev[i], sc.lo[i]), sc.hi[i])
    else:
        x[:] = 0.0
    if settings.subspace_minimization:
        bounded_solve_in(sc.A_damped, sc.b, x, sc.lo, sc.hi, settings.sweeps, pgs_stats, sc.free_index, sc.free_mask,
                         sc.free_M, sc.free_r)
    else:
        projected_gauss_seidel(sc.A_damped, sc.b, x, sc.lo, sc.hi, settings.sweeps, settings.residual_tolerance,
                               settings.update_tolerance, sc.x_prev, settings.stall_tolerance, pgs_stats)
    # The step bound scales the whole step (clamping each angle would turn it towards the box's corners).
    biggest = 0.0
    for i in range(n):
        biggest = max(biggest, abs(x[i]))
    if settings.max_step > 0.0 and biggest > settings.max_step:
        for i in range(n):
            x[i] *= settings.max_step / biggest
    _add_clamped(q, x, model.lower, model.upper, sc.q_new)
    cost = _evaluate(model, targets, root, W, sc.q_new, sc.R_new, sc.p_new, sc.e, sc.err_new, sc.M)
    return cost, int(pgs_stats[O_SWEEPS])


@njit(cache=True, inline="always")
def _take(q, ws, sc):
    """The trial becomes the state."""
    copy_into(q, sc.q_new)
    take_frames(ws.R, ws.p, sc.R_new, sc.p_new)
    copy_rows(ws.err, sc.err_new)
    copy_into(sc.x_prev, sc.x_solve)


@njit(cache=True, _nrt=False)
def _iteration(model, settings, targets, root, W, q, lam, cost, ws, sc, pgs_stats):
    """One linearisation's step. Returns ``(cost, lam, taken, settled, sweeps)``.

    Adaptive damping: ``lam`` grows until a step lowers the error, which is
    then taken (Levenberg-Marquardt). Otherwise the paper's plain step with
    fixed damping, always taken. Compiled without reference counting, as :func:`gsik.kernels.step.step_with`.
    """
    if not settings.adaptive_damping:
        c, sweeps = _trial(model, settings, targets, root, W, q, settings.damping, ws, sc, pgs_stats)
        _take(q, ws, sc)
        settled = settings.settle_tolerance > 0.0 and abs(cost - c) <= settings.settle_tolerance * cost
        return c, lam, True, settled, sweeps
    sweeps = 0
    while lam < 1e8:
        c, s = _trial(model, settings, targets, root, W, q, lam, ws, sc, pgs_stats)
        sweeps += s
        if c < cost:
            _take(q, ws, sc)
            return c, max(lam * 0.3, 1e-9), True, cost - c <= settings.settle_tolerance * cost, sweeps
        if _predicted_gain(sc.A, sc.b, sc.x_solve) <= 1e-3 * settings.settle_tolerance * cost:
            break  # even the linear model promises nothing: a stationary point within the limits, not a bad lam
        lam *= 5.0
    return cost, lam, False, False, sweeps


@njit(cache=True, inline="always")
def _predicted_gain(A, b, x):
    """The fall of the weighted error the linear model predicts for step ``x``: ``b.x - x.A.x / 2``."""
    gain = 0.0
    for i in range(x.shape[0]):
        ax = 0.0
        for j in range(x.shape[0]):
            ax += A[i, j] * x[j]
        gain += x[i] * (b[i] - 0.5 * ax)
    return gain


@njit(cache=True, inline="always")
def _stalls(settings, sc, taken, settled):
    """True if a linearisation's step ends the phase: not taken, settled, or shorter than the stall tolerance."""
    return not taken or settled or norm_of(sc.x_solve) < settings.stall_tolerance


@njit(cache=True, inline="always")
def _window_settled(settings, window_start, cost):
    """True if the last :data:`SETTLE_WINDOW` linearisations lowered the error from ``window_start`` to ``cost``
    by :data:`SETTLE_WINDOW_GAIN` (relative) or less."""
    return settings.settle_tolerance > 0.0 and window_start - cost <= SETTLE_WINDOW_GAIN * window_start


@njit(cache=True)
def _phase(model, settings, targets, root, W, q, budget, ws, sc, counts, evaluated):
    """Iterate on ``targets`` from ``q`` for at most ``budget`` linearisations; returns ``(status, cost)``.

    ``counts`` (2,) gains the linearisations and sweeps done. ``evaluated``: NaN, or the cost at ``q`` whose
    frames and errors ``ws`` already holds for these targets (the phase's first evaluation is then that one).
    """
    row_w = targets.row_weight
    pgs_stats = np.zeros(N_STATS)
    lam = max(settings.damping, 1e-3) if settings.adaptive_damping else settings.damping
    sc.x_prev[:] = 0.0
    sc.x_solve[:] = 0.0
    cost = evaluated
    if math.isnan(cost):
        cost = _evaluate(model, targets, root, W, q, ws.R, ws.p, sc.e, ws.err, sc.M)
    window_start = cost
    for it in range(budget + 1):
        sc.err_new[:, :] = ws.err
        if _finish_errors(row_w, sc.err_new, settings.position_tolerance, settings.orientation_tolerance):
            return CONVERGED, cost
        if it == budget:
            break
        linear_system(model, ws.R, ws.p, sc.e, row_w, sc.A, sc.b, sc.v)
        _bounds(q, model.lower, model.upper, 0.0, sc.lo, sc.hi)
        cost, lam, taken, settled, sweeps = _iteration(model, settings, targets, root, W, q, lam, cost, ws, sc,
                                                       pgs_stats)
        counts[0] += 1
        counts[1] += sweeps
        if _stalls(settings, sc, taken, settled):
            return STALLED, cost
        if (it + 1) % SETTLE_WINDOW == 0:
            if _window_settled(settings, window_start, cost):
                return STALLED, cost
            window_start = cost
    return BUDGET_EXHAUSTED, cost


@njit(cache=True)
def _positions_only(targets):
    row_w = targets.row_weight.copy()
    row_w[:, 3:] = 0.0
    return TargetArrays(targets.position, targets.rotation, row_w)


@njit(cache=True)
def _rough(settings):
    """``settings`` for the positions phase: PGS sweeps alone solve each linear system (no subspace
    minimisation), and the phase has met the positions once each is within :data:`POSITION_PHASE_TOLERANCE`.

    The phase only has to steer the limbs into the right basin; the full phase meets the tolerances. Its
    systems (a row per position, fewer rows than DOFs) are singular but for the damping: solved exactly they
    cost twice a full phase's time per linearisation and reached less (measured on bench_reach's poses, one
    attempt: 61% in 0.88 ms median; 64% in 0.57 ms with the sweeps alone; 64% in 23 rather than 28
    linearisations with the 3 cm tolerance too).
    """
    return KernelSettings(settings.damping, settings.sweeps, settings.residual_tolerance, settings.update_tolerance,
                          settings.stall_tolerance, settings.max_step, settings.adaptive_damping, settings.warm_start,
                          max(settings.position_tolerance, POSITION_PHASE_TOLERANCE), settings.orientation_tolerance,
                          settings.settle_tolerance, False, settings.positions_first)


@njit(cache=True)
def _rounds(model, settings, targets, root, W, q, max_iterations, ws, sc, counts, staged, cost0):
    """Rounds of a positions-only phase (when ``staged``) then a full one, while a round stalls and lowers the
    error by more than :data:`ROUND_GAIN`; ``q`` ends at the best pose unless converged. ``cost0``: the cost at
    the start ``q``, whose frames and errors ``ws`` holds. Returns ``(status, the last phase's cost)``: when
    converged, ``ws`` holds the frames and errors at ``q`` and that cost is theirs."""
    best_q = q.copy()
    best = np.inf
    status = BUDGET_EXHAUSTED
    while True:
        if staged:
            share = max(1, int(math.ceil(POSITION_PHASE_SHARE * max_iterations)))
            _phase(model, _rough(settings), _positions_only(targets), root, W, q,
                   min(share, max_iterations - counts[0]), ws, sc, counts, np.nan)
        # The first full phase without a positions phase starts where solve evaluated: no second evaluation.
        first = np.nan if staged or best < np.inf else cost0
        status, cost = _phase(model, settings, targets, root, W, q, max_iterations - counts[0], ws, sc, counts,
                              first)
        improved = cost < best * (1.0 - ROUND_GAIN)
        if cost < best:
            best = cost
            best_q[:] = q
        if status != STALLED or not staged or not improved or counts[0] >= max_iterations:
            break
    if status != CONVERGED:
        q[:] = best_q
    return status, cost


@njit(cache=True)
def solve(model, settings, targets, root, W, q, max_iterations, ws):
    """One attempt from ``q`` (first clamped into the limits): until the targets are met, progress stops or
    ``max_iterations`` linearisations.

    Each linearisation solves ``(J^T W J + lam I) x = J^T W e`` within the
    limits (:func:`~gsik.kernels.pgs.bounded_solve_in`, or PGS sweeps alone
    without subspace minimisation), the step scaled to ``settings.max_step``.
    With ``settings.positions_first`` and an orientation target off by more
    than :data:`STAGE_ANGLE`, rounds of a
    positions-only phase (PGS sweeps alone, to 3 cm: :func:`_rough`) then a full one, while a round lowers the error
    (see the module's docstring); the best pose is kept. Sets
    ``ws.stats[O_STATUS]`` (converged; stalled: a best reach; budget
    exhausted), ``O_ITERATIONS`` (linearisations), ``O_SWEEPS``, ``O_COST``,
    ``O_STEP_NORM``, ``O_FINITE``. ``settings.sweeps`` are the sweeps per linearisation. The buffers are made
    once per attempt (:func:`~gsik.kernels.make_scratch`).
    """
    for i in range(q.shape[0]):  # the start, clamped into the limits
        q[i] = min(max(q[i], model.lower[i]), model.upper[i])
    sc = make_scratch(ws.R.shape[0], q.shape[0], ws.err.shape[1], True)
    counts = np.zeros(2, dtype=np.int64)
    cost = _evaluate(model, targets, root, W, q, ws.R, ws.p, sc.e, ws.err, sc.M)
    staged = settings.positions_first and np.any((targets.row_weight[:, 3] > 0.0) & (ws.err[1] > STAGE_ANGLE))
    status, cost = _rounds(model, settings, targets, root, W, q, max_iterations, ws, sc, counts, staged, cost)
    if status != CONVERGED:  # q went back to the best pose: its frames and errors (converged: ws holds them)
        cost = _evaluate(model, targets, root, W, q, ws.R, ws.p, sc.e, ws.err, sc.M)
    if _finish_errors(targets.row_weight, ws.err, settings.position_tolerance, settings.orientation_tolerance):
        status = CONVERGED
    st = ws.stats
    st[O_STATUS] = status
    st[O_ITERATIONS] = counts[0]
    st[O_SWEEPS] = counts[1]
    st[O_COST] = cost
    st[O_STEP_NORM] = norm_of(sc.x_solve)
    st[O_FINITE] = _finite(q, ws.err, targets.row_weight)
