"""The frame step kernel (a full solve's attempt is in :mod:`gsik.kernels.solve`), over the named contracts.

``model`` is a :class:`~gsik.kernels.KinematicModel`, ``settings`` a
:class:`~gsik.kernels.KernelSettings`, ``targets`` a
:class:`~gsik.kernels.TargetArrays`, ``ws`` a :class:`~gsik.kernels.Workspace` (state kept between
calls), ``sc`` a :class:`~gsik.kernels.Scratch` (made by each call: allocating it costs less than passing it in).

:func:`step_with` and the kernels it calls are compiled without numba's reference counting (``_nrt=False``): on a
chain the atomic counts of every array it handles were about half of its compiled time. They allocate nothing and
copy arrays by loops (numba's whole-array copy needs the counting).
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels import (BUDGET_EXHAUSTED, CONVERGED, O_COST, O_FINITE, O_ITERATIONS, O_RESIDUAL, O_STATUS,
                          O_STEP_NORM, O_SWEEPS, STALLED, make_scratch)
from gsik.kernels.kinematics import effector_errors, frames_into, linear_system
from gsik.kernels.pgs import bounded_solve_in, projected_gauss_seidel, strictly_inside

# With adaptive damping, lam may fall to this fraction of delta while steps succeed: near a
# solution the steps come closer to Gauss-Newton and the last millimetre takes tens of frames, not hundreds
# (measured on gsik.anim.scenarios; 0.01 settles faster still but tracks a fast wave worse).
ADAPTIVE_FLOOR = 0.1
#: Up to this many DOFs (a limb), a frame step's bounded solve stops its first sweeps early when no bound is touched
#: (:func:`gsik.kernels.pgs.bounded_solve_in`'s ``until_inside``): a wrong guess costs a few sweeps and a small
#: Cholesky again. On a whole body (the 30-DOF biped) a wrong guess costs ~8 µs (Table 1 with the defaults: steps
#: from rest), so there it is tried only when the warm start is the last step's and lies strictly inside the bounds
#: (:func:`_guess`): a drag's steps, where the guess holds.
EARLY_STOP_DOFS = 8


@njit(cache=True, _nrt=False)
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


@njit(cache=True, inline="always")
def _finite(q, err, row_w):
    """True if the angles ``q`` and the errors ``err`` (2, m) of the rows ``row_w`` uses are all finite (their
    squares sum to a finite number, as the Python side once checked)."""
    total = 0.0
    for i in range(q.shape[0]):
        total += q[i] * q[i]
    for k in range(err.shape[1]):
        if row_w[k, 0] > 0.0:
            total += err[0, k] * err[0, k]
        if row_w[k, 3] > 0.0:
            total += err[1, k] * err[1, k]
    return math.isfinite(total)


@njit(cache=True, inline="always")
def norm_of(x):
    """``sqrt(sum(x ** 2))`` of ``x`` (n,), summed in order: the number ``math.sqrt(np.sum(x * x))`` gives, without
    its temporary array."""
    total = 0.0
    for i in range(x.shape[0]):
        total += x[i] * x[i]
    return math.sqrt(total)


@njit(cache=True, inline="always")
def take_frames(R, p, R_new, p_new):
    """``R[:] = R_new``, ``p[:] = p_new`` (frames (nf, 3, 3) and (nf, 3)) as loops: numba's three-dimensional slice
    assignment costs 0.2 µs more on a chain's nine frames."""
    for i in range(R.shape[0]):
        for a in range(3):
            p[i, a] = p_new[i, a]
            for b in range(3):
                R[i, a, b] = R_new[i, a, b]


@njit(cache=True, inline="always")
def copy_into(dst, src):
    """``dst[:] = src`` for vectors (n,) as a loop (no reference counting: see the module's docstring)."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True, inline="always")
def copy_rows(dst, src):
    """``dst[:, :] = src`` for matrices (r, c) as loops (see :func:`copy_into`)."""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]


@njit(cache=True, _nrt=False)
def _add_clamped(q, x, lower, upper, out):
    """``out = clip(q + x, lower, upper)``: the bounds on x keep q + x inside up to one rounding."""
    for i in range(q.shape[0]):
        out[i] = min(max(q[i] + x[i], lower[i]), upper[i])


@njit(cache=True, _nrt=False)
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
    """Frames ``R``, ``p`` at ``q``, the error vector ``e`` and errors ``err``; returns the weighted cost.

    The step's one forward kinematics (the frames at the incoming ``q`` are the last step's): the frames it leaves
    become the state when the step is taken."""
    frames_into(model.frame_parent, model.frame_offset, model.frame_rotation, model.frame_axis, model.frame_dof,
                q, root, W, R, p)
    return effector_errors(R, p, model.effector_frame, targets.position, targets.rotation, targets.row_weight,
                           e, err, M)


@njit(cache=True, inline="always")
def _idle(ws, sc, cost, finite):
    """Every target already met (or the errors are not finite): an idle frame costs one error evaluation."""
    copy_rows(ws.err, sc.err_new)
    ws.x[:] = 0.0
    st = ws.stats
    st[O_SWEEPS] = 0
    st[O_ITERATIONS] = 0
    st[O_RESIDUAL] = 0.0
    st[O_COST] = cost
    st[O_STEP_NORM] = 0.0
    st[O_STATUS] = CONVERGED
    st[O_FINITE] = finite


@njit(cache=True, inline="always")
def _start(x, x_prev, lo, hi, warm_start):
    """The sweeps' start in ``x``: the previous frame's step ``x_prev`` within ``lo``, ``hi`` (warm), else 0."""
    if warm_start:
        for i in range(x.shape[0]):
            x[i] = min(max(x_prev[i], lo[i]), hi[i])
    else:
        x[:] = 0.0


@njit(cache=True, inline="always")
def _guess(x, lo, hi):
    """True if the warm start ``x`` (n,) moves (a step after a step, not after an idle frame or a new pose) and lies
    strictly inside the bounds ``lo``, ``hi``: the last step touched none, so this one likely touches none either."""
    moves = False
    for i in range(x.shape[0]):
        moves = moves or x[i] != 0.0
    return moves and strictly_inside(x, lo, hi)


@njit(cache=True, inline="always")
def _step_solve(model, settings, q, lam, ws, sc):
    """Solve ``(A + lam I) x = b`` within the limits and the step bound, warm-started from ``ws.x``."""
    n = q.shape[0]
    A, x, lo, hi = sc.A, ws.x, sc.lo, sc.hi
    for i in range(n):
        A[i, i] += lam
    _bounds(q, model.lower, model.upper, settings.max_step, lo, hi)
    copy_into(sc.x_prev, x)
    _start(x, sc.x_prev, lo, hi, settings.warm_start)
    if settings.subspace_minimization:
        guess = n <= EARLY_STOP_DOFS or (settings.warm_start and _guess(x, lo, hi))
        if not bounded_solve_in(A, sc.b, x, lo, hi, settings.sweeps, ws.stats, sc.free_index, sc.free_mask,
                                sc.free_M, sc.free_r, guess):
            # A bound is active: from the same start with all the sweeps (the step's numbers as they always were).
            early = ws.stats[O_SWEEPS]
            _start(x, sc.x_prev, lo, hi, settings.warm_start)
            bounded_solve_in(A, sc.b, x, lo, hi, settings.sweeps, ws.stats, sc.free_index, sc.free_mask, sc.free_M,
                             sc.free_r)
            ws.stats[O_SWEEPS] += early
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
    A step that would leave a non-finite angle or error is not taken and
    ``ws.stats[O_FINITE]`` is 0.0 (else 1.0); returns the same as a bool,
    which a caller from Python reads for less than an array element.
    """
    return step_with(model, settings, targets, root, W, q, ws,
                     make_scratch(ws.R.shape[0], q.shape[0], ws.err.shape[1], False))


@njit(cache=True, _nrt=False)
def step_with(model, settings, targets, root, W, q, ws, sc):
    """:func:`step` with its scratch ``sc`` (a :class:`~gsik.kernels.Scratch`) given: what :func:`step` and
    :func:`gsik.kernels.plain.step_plain` call, without reference counting (see the module's docstring)."""
    cost0 = effector_errors(ws.R, ws.p, model.effector_frame, targets.position, targets.rotation,
                            targets.row_weight, sc.e, ws.err, sc.M)
    copy_rows(sc.err_new, ws.err)
    if _finish_errors(targets.row_weight, sc.err_new, settings.position_tolerance, settings.orientation_tolerance):
        finite = _finite(q, sc.err_new, targets.row_weight)
        _idle(ws, sc, cost0, finite)
        return finite
    linear_system(model, ws.R, ws.p, sc.e, targets.row_weight, sc.A, sc.b, sc.v)
    lam = ws.lam[0] if settings.adaptive_damping else settings.damping
    _step_solve(model, settings, q, lam, ws, sc)
    _add_clamped(q, ws.x, model.lower, model.upper, sc.q_new)
    cost = _evaluate(model, targets, root, W, sc.q_new, sc.R_new, sc.p_new, sc.e, sc.err_new, sc.M)
    accepted = True
    if settings.adaptive_damping:
        cost, accepted = _safeguard(model, settings, targets, root, W, q, lam, cost0, cost, ws, sc)
    # A non-finite step is never taken: the caller refuses it (Status.REFUSED) from stats[O_FINITE].
    finite = not accepted or _finite(sc.q_new, sc.err_new, targets.row_weight)
    if accepted and finite:
        copy_into(q, sc.q_new)
        take_frames(ws.R, ws.p, sc.R_new, sc.p_new)
        copy_rows(ws.err, sc.err_new)
    _step_stats(settings, targets, ws, cost, accepted)
    ws.stats[O_FINITE] = finite
    return finite


@njit(cache=True, inline="always")
def _step_stats(settings, targets, ws, cost, accepted):
    """Cost, step size and status of a step into ``ws.stats``."""
    step_norm = norm_of(ws.x)
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
