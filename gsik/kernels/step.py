"""The solver's kernels: one frame step and a full solve, over the named contracts.

``model`` is a :class:`~gsik.kernels.KinematicModel`, ``settings`` a
:class:`~gsik.kernels.KernelSettings`, ``targets`` a
:class:`~gsik.kernels.TargetArrays`, ``ws`` a :class:`~gsik.kernels.Workspace` (state kept between
calls), ``sc`` a :class:`~gsik.kernels.Scratch` (made by each call: allocating it costs less than passing it in).
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit
from gsik.kernels import (BUDGET_EXHAUSTED, CONVERGED, N_STATS, O_COST, O_ITERATIONS, O_RESIDUAL, O_STATUS,
                          O_STEP_NORM, O_SWEEPS, STALLED, make_scratch)
from gsik.kernels.kinematics import effector_errors, frames_into, linear_system
from gsik.kernels.pgs import bounded_solve, projected_gauss_seidel

# With adaptive damping, lam may fall to this fraction of delta while steps succeed: near a
# solution the steps come closer to Gauss-Newton and the last millimetre takes tens of frames, not hundreds
# (measured on gsik.anim.scenarios; 0.01 settles faster still but tracks a fast wave worse).
ADAPTIVE_FLOOR = 0.1


@njit(cache=True)
def _finish_errors(row_w, err, pos_tol, ori_tol):
    """Zero the errors of unused rows (no target, position only); True if all are within tolerance."""
    ok = True
    for k in range(err.shape[1]):
        if row_w[k, 0] <= 0.0:
            err[0, k] = 0.0
        elif err[0, k] > pos_tol:
            ok = False
        if row_w[k, 3] <= 0.0:
            err[1, k] = 0.0
        elif err[1, k] > ori_tol:
            ok = False
    return ok


@njit(cache=True)
def _add_clamped(q, x, lower, upper, out):
    """``out = clip(q + x, lower, upper)``: the bounds on x keep q + x inside up to one rounding."""
    for i in range(q.shape[0]):
        out[i] = min(max(q[i] + x[i], lower[i]), upper[i])


@njit(cache=True)
def _bounds(q, lower, upper, max_step, lo, hi):
    for i in range(q.shape[0]):
        lo[i] = lower[i] - q[i]
        hi[i] = upper[i] - q[i]
        if max_step > 0.0:
            lo[i] = max(lo[i], -max_step)
            hi[i] = min(hi[i], max_step)
        # Rounding can leave q a hair outside its limits; never ask PGS for an empty box.
        if lo[i] > 0.0:
            lo[i] = 0.0
        if hi[i] < 0.0:
            hi[i] = 0.0


@njit(cache=True, inline="always")
def _evaluate(model, targets, root, W, q, R, p, e, err, M):
    """Frames ``R``, ``p`` at ``q``, the error vector ``e`` and errors ``err``; returns the weighted cost."""
    frames_into(model.frame_parent, model.frame_offset, model.frame_rotation, model.frame_axis, model.frame_dof,
                q, root, W, R, p)
    return effector_errors(R, p, model.effector_frame, targets.position, targets.rotation, targets.row_weight,
                           e, err, M)


@njit(cache=True, inline="always")
def _idle(ws, sc, cost):
    """Every target already met: an idle frame costs one error evaluation."""
    ws.err[:, :] = sc.err_new
    ws.x[:] = 0.0
    st = ws.stats
    st[O_SWEEPS] = 0
    st[O_ITERATIONS] = 0
    st[O_RESIDUAL] = 0.0
    st[O_COST] = cost
    st[O_STEP_NORM] = 0.0
    st[O_STATUS] = CONVERGED


@njit(cache=True, inline="always")
def _step_solve(model, settings, q, lam, ws, sc):
    """Solve ``(A + lam I) x = b`` within the limits and the step bound, warm-started from ``ws.x``."""
    n = q.shape[0]
    A, x, lo, hi = sc.A, ws.x, sc.lo, sc.hi
    for i in range(n):
        A[i, i] += lam
    _bounds(q, model.lower, model.upper, settings.max_step, lo, hi)
    sc.x_prev[:] = x
    if settings.warm_start:
        for i in range(n):
            x[i] = min(max(x[i], lo[i]), hi[i])
    else:
        x[:] = 0.0
    if settings.subspace_minimization:
        bounded_solve(A, sc.b, x, lo, hi, settings.sweeps, ws.stats)
    else:
        projected_gauss_seidel(A, sc.b, x, lo, hi, settings.sweeps, settings.residual_tolerance,
                               settings.update_tolerance, sc.x_prev, settings.stall_tolerance, ws.stats)


@njit(cache=True, inline="always")
def _safeguard(model, settings, targets, root, W, q, lam, cost0, cost, ws, sc):
    """Levenberg-style: a step that raises the error is halved, then refused, and the damping grows;
    so a held target can only settle, never oscillate. Returns ``(cost, accepted)``."""
    x = ws.x
    tries = 0
    while cost > cost0 and tries < 3:
        for i in range(x.shape[0]):
            x[i] *= 0.5
        _add_clamped(q, x, model.lower, model.upper, sc.q_new)
        cost = _evaluate(model, targets, root, W, sc.q_new, sc.R_new, sc.p_new, sc.e, sc.err_new, sc.M)
        tries += 1
    if cost > cost0:
        x[:] = 0.0
        ws.lam[0] = min(lam * 10.0, 1e6)
        return cost0, False
    if cost0 - cost <= settings.settle_tolerance * cost0:
        # So little left to gain that the pose is held: a best reach settles instead of creeping.
        x[:] = 0.0
        return cost0, False
    ws.lam[0] = max(lam * (0.5 if tries == 0 else 4.0), settings.damping * ADAPTIVE_FLOOR)
    return cost, True


@njit(cache=True)
def step(model, settings, targets, root, W, q, ws):
    """One frame: linearise at ``q``, solve the damped normal equations by PGS, update ``q``.

    ``ws.R``, ``ws.p`` must hold the world frames at the incoming ``q``; on
    return they hold the frames at the new ``q`` and ``ws.err`` (2, m) its
    errors. ``ws.x`` (n_dofs,) carries the previous frame's step in (the warm
    start) and this frame's step out; ``ws.lam`` the adaptive damping.
    """
    sc = make_scratch(ws.R.shape[0], q.shape[0], ws.err.shape[1], False)
    cost0 = effector_errors(ws.R, ws.p, model.effector_frame, targets.position, targets.rotation,
                            targets.row_weight, sc.e, ws.err, sc.M)
    sc.err_new[:, :] = ws.err
    if _finish_errors(targets.row_weight, sc.err_new, settings.position_tolerance, settings.orientation_tolerance):
        _idle(ws, sc, cost0)
        return
    linear_system(model, ws.R, ws.p, sc.e, targets.row_weight, sc.A, sc.b, sc.v)
    lam = ws.lam[0] if settings.adaptive_damping else settings.damping
    _step_solve(model, settings, q, lam, ws, sc)
    _add_clamped(q, ws.x, model.lower, model.upper, sc.q_new)
    cost = _evaluate(model, targets, root, W, sc.q_new, sc.R_new, sc.p_new, sc.e, sc.err_new, sc.M)
    accepted = True
    if settings.adaptive_damping:
        cost, accepted = _safeguard(model, settings, targets, root, W, q, lam, cost0, cost, ws, sc)
    if accepted:
        q[:] = sc.q_new
        ws.R[:, :, :] = sc.R_new
        ws.p[:, :] = sc.p_new
        ws.err[:, :] = sc.err_new
    _step_stats(settings, targets, ws, cost, accepted)


@njit(cache=True, inline="always")
def _step_stats(settings, targets, ws, cost, accepted):
    """Cost, step size and status of a step into ``ws.stats``."""
    step_norm = 0.0
    for i in range(ws.x.shape[0]):
        step_norm += ws.x[i] * ws.x[i]
    step_norm = math.sqrt(step_norm)
    st = ws.stats
    st[O_COST] = cost
    st[O_STEP_NORM] = step_norm
    st[O_ITERATIONS] = st[O_SWEEPS]
    if _finish_errors(targets.row_weight, ws.err, settings.position_tolerance, settings.orientation_tolerance):
        st[O_STATUS] = CONVERGED
    elif not accepted or step_norm <= max(settings.stall_tolerance, 1e-12) * 1e3:
        st[O_STATUS] = STALLED
    else:
        st[O_STATUS] = BUDGET_EXHAUSTED


@njit(cache=True, inline="always")
def _damped_try(model, settings, targets, root, W, q, lam, cost, pgs_stats, ws, sc):
    """Raise ``lam`` until a bounded step lowers the cost; take it. Returns ``(cost, lam, accepted, settled, sweeps)``."""
    n = q.shape[0]
    x = sc.x_solve
    sweeps = 0
    while lam < 1e8:
        sc.A_damped[:, :] = sc.A
        for i in range(n):
            sc.A_damped[i, i] += lam
        x[:] = 0.0
        bounded_solve(sc.A_damped, sc.b, x, sc.lo, sc.hi, settings.sweeps, pgs_stats)
        sweeps += int(pgs_stats[O_SWEEPS])
        _add_clamped(q, x, model.lower, model.upper, sc.q_new)
        c = _evaluate(model, targets, root, W, sc.q_new, sc.R_new, sc.p_new, sc.e, sc.err_new, sc.M)
        if c < cost:
            settled = cost - c <= settings.settle_tolerance * cost
            q[:] = sc.q_new
            ws.R[:, :, :] = sc.R_new
            ws.p[:, :] = sc.p_new
            ws.err[:, :] = sc.err_new
            return c, max(lam * 0.3, 1e-9), True, settled, sweeps
        lam *= 5.0
    return cost, lam, False, False, sweeps


@njit(cache=True)
def solve(model, settings, targets, root, W, q, max_iterations, ws):
    """Levenberg-Marquardt over bounded steps until the targets are met or progress stops.

    Each iteration linearises, solves ``(J^T W J + lam I) x = J^T W e`` within
    the limits (:func:`~gsik.kernels.pgs.bounded_solve`), and keeps the step
    only if the weighted error falls; else ``lam`` grows and it tries again.
    Sets ``ws.stats[O_STATUS]`` (converged; stalled: no step lowers the error
    or the pose stopped changing, a best reach; budget exhausted),
    ``O_ITERATIONS``, ``O_SWEEPS``, ``O_COST`` and ``O_STEP_NORM``.
    ``settings.sweeps`` are the sweeps per linearisation.
    """
    row_w = targets.row_weight
    pos_tol = settings.position_tolerance
    ori_tol = settings.orientation_tolerance
    sc = make_scratch(ws.R.shape[0], q.shape[0], ws.err.shape[1], True)
    x = sc.x_solve
    x[:] = 0.0
    pgs_stats = np.zeros(N_STATS)
    lam = max(settings.damping, 1e-3)
    cost = _evaluate(model, targets, root, W, q, ws.R, ws.p, sc.e, ws.err, sc.M)
    total_sweeps = 0
    status = BUDGET_EXHAUSTED
    it = 0
    for it in range(max_iterations + 1):
        sc.err_new[:, :] = ws.err
        if _finish_errors(row_w, sc.err_new, pos_tol, ori_tol):
            status = CONVERGED
            break
        if it == max_iterations:
            break
        linear_system(model, ws.R, ws.p, sc.e, row_w, sc.A, sc.b, sc.v)
        _bounds(q, model.lower, model.upper, settings.max_step, sc.lo, sc.hi)
        cost, lam, accepted, settled, sweeps = _damped_try(model, settings, targets, root, W, q, lam, cost,
                                                           pgs_stats, ws, sc)
        total_sweeps += sweeps
        if not accepted or settled or math.sqrt(np.sum(x * x)) < settings.stall_tolerance:
            status = STALLED
            break
    # e and err must describe the final q (a refused trial overwrote them).
    cost = _evaluate(model, targets, root, W, q, ws.R, ws.p, sc.e, ws.err, sc.M)
    _finish_errors(row_w, ws.err, pos_tol, ori_tol)
    if status == STALLED and _finish_errors(row_w, sc.err_new, pos_tol, ori_tol):
        status = CONVERGED
    st = ws.stats
    st[O_STATUS] = status
    st[O_ITERATIONS] = it
    st[O_SWEEPS] = total_sweeps
    st[O_COST] = cost
    st[O_STEP_NORM] = math.sqrt(np.sum(x * x))
