"""A refused full step's fallback compiled: the whole prioritised step without balance in one call.

When the full step's trial (:func:`gsik.kernels.accept.control_step`) is no better than the start,
:class:`gsik.control.Controller`'s Python branches (``_damped_trial``, ``_targets_alone``, ``_correction``, the
restoring steps of ``_judge``, ``_adapt_damping``) try, in order:

1. with a posture, the target levels' step alone (the posture's left out), kept if better for them;
2. the full step halved up to 3 times (each trial, with a posture, given up to ``restoring`` restoring steps);
3. the step of the met levels above the first unmet one alone, kept if it tightens them;

and refuse the step otherwise (the damping raised tenfold up to :data:`MAX_DAMPING`); in a solve() attempt that
settles a posture, a worse full step that passes the posture's settle test is refused without them (:func:`settles`,
``gsik.control.Controller.settle_steps``). :func:`control_step` runs the
same over the same buffers, bit for bit (``tests/test_fallback_kernels.py`` compares the two on drags), so a refused
step no longer leaves the compiled code. :func:`step_end` reads what a step's statistics need.
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels import priority
from gsik.kernels.accept import (
    F_CONVERGED,
    F_LAGGING,
    F_TARGET_COST,
    R_COMMITTED,
    R_CONVERGED0,
    R_CREEPS,
    R_DECIDED,
    R_FRESH,
    R_LAGGING0,
    R_STATUS,
    R_TARGET_COST0,
    R_VERDICT,
    V_BETTER,
    V_SAME,
    V_WORSE,
    commit,
    compare_levels,
    creeps,
    norm,
    restore,
)
from gsik.kernels.accept import control_step as full_step
from gsik.kernels.control import box, linearise, trial

#: Largest adaptive damping (the fast path's too): a step refused at it holds the pose.
MAX_DAMPING = 1e6
#: A refused (worse) step raises the adaptive damping by this factor.
DAMPING_RAISE = 10.0
#: Halvings of a worse full step before the met levels' correction.
HALVINGS = 3


# Inlined into its caller (gsik.kernels.step_inputs.control_step): a call passes these NamedTuples of ~70 arrays by
# value, ~0.5 µs a step on bench_drag's drags.
@njit(cache=True, _nrt=False, inline="always")
def control_step(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, lam, damping, base, near,
                 tols, floors, rule, restoring, stall_tolerance, cache, window, wk):
    """One prioritised step without balance from ``q`` (n,) [rad], every branch compiled: the full step
    (:func:`gsik.kernels.accept.control_step`, same arguments), and when its trial is no better the fallback
    (:func:`refused`). ``cache.out``: the ``R_*`` figures; read the outcome with :func:`step_end`."""
    full_step(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, lam, damping, base, near,
              tols, floors, rule, restoring, stall_tolerance, cache, window, wk)
    out = cache.out
    if out[R_STATUS] == priority.OK and out[R_COMMITTED] == 0.0:
        refused(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, lam, damping, base, near,
                tols, floors, rule, restoring, stall_tolerance, cache, window, wk)


@njit(cache=True, _nrt=False)
def step_end(cache):
    """``(status, committed, held or creeps, converged, targets' cost, lagging, step norm [rad])`` of the step
    :func:`control_step` made (floats, 1.0 / 0.0 for flags). Committed: the third is ``R_CREEPS`` (-1: the caller's
    norm decides, :meth:`gsik.control.Controller._committed`) and the state the committed pose's; refused: whether
    the pose is held, and the start pose's state."""
    out, flags = cache.out, cache.flags
    if out[R_COMMITTED] > 0.0:
        return (out[R_STATUS], 1.0, out[R_CREEPS], flags[F_CONVERGED], flags[F_TARGET_COST], flags[F_LAGGING],
                norm(cache.moved))
    return out[R_STATUS], 0.0, out[R_CREEPS], out[R_CONVERGED0], out[R_TARGET_COST0], out[R_LAGGING0], 0.0


@njit(cache=True, _nrt=False)
def _start(cache):
    """``(costs, anchors, met, error rows)`` of the step's start state: the cache's when it was fresh, else the
    ``*0`` buffers :func:`gsik.kernels.accept.control_step` evaluated (anchored at their own costs)."""
    if cache.out[R_FRESH] > 0.0:
        return cache.costs, cache.anchors, cache.met, cache.e
    return cache.costs0, cache.costs0, cache.met0, cache.e0


@njit(cache=True, _nrt=False)
def refused(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, lam, damping, base, near, tols,
            floors, rule, restoring, stall_tolerance, cache, window, wk):
    """The fallback of a full step whose trial (in ``wk``, judged ``cache.out[R_VERDICT]``) is no better: a worse
    one retried (:func:`_retry`) unless it settles the posture (:func:`settles`), a better retry committed
    (``lam[0]`` lowered only for the target levels' step alone), else the step refused (:func:`_refuse`)."""
    settle, fall, floor = rule
    c0, anchors0, met0, e0 = _start(cache)
    out = cache.out
    verdict, decided, tries = int(out[R_VERDICT]), int(out[R_DECIDED]), 0
    if verdict == V_WORSE and not settles(cache, posture):
        verdict, decided, tries = _retry(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p,
                                         near, tols, floors, settle, restoring, c0, anchors0, met0, e0, cache, wk)
        if verdict < 0:
            out[R_STATUS] = -verdict - 1
            return
    out[R_VERDICT], out[R_DECIDED] = verdict, decided
    if verdict == V_BETTER:
        lowered, low = (damping * fall, base * floor) if tries == 0 else (damping, -math.inf)
        commit(q, R, p, W, lam, lowered, low, anchors0, decided, posture, stall_tolerance, False, cache, window, wk)
        return
    _refuse(verdict, lam, damping, posture, c0, met0, cache, window)


@njit(cache=True, _nrt=False)
def settles(cache, posture):
    """True if the full step ``cache.dq0`` settles a solve()'s posture (:class:`gsik.stall.PostureSettle`'s test,
    ``cache.settle[0]`` its tolerance [rad], > 0): every target within its tolerances at the start pose, and no DOF
    of the step above the tolerance times the posture's gain. Refused, such a step ends the attempt there; a retry
    (halved, or the target levels' alone) could move the pose by about that tolerance at most, at the cost of up to
    13 linearisations (``gsik.control.Controller._damped_trial`` asks the same)."""
    tolerance = cache.settle[0]
    if not tolerance > 0.0:
        return False
    converged = cache.flags[F_CONVERGED] if cache.out[R_FRESH] > 0.0 else cache.out[R_CONVERGED0]
    if not converged > 0.0:
        return False
    full = 0.0
    for d in range(cache.dq0.shape[0]):
        a = abs(cache.dq0[d])
        if a > full or math.isnan(a):
            full = a
    return full <= tolerance * posture.gain[0]


@njit(cache=True, _nrt=False)
def _refuse(verdict, lam, damping, posture, c0, met0, cache, window):
    """A refused step: ``lam[0]`` raised after a worse trial; held (``R_CREEPS``) when the trial changed nothing,
    the damping is the largest, or the stall window (asked last, as the Python branches do) says it creeps; the start
    pose's state into ``R_CONVERGED0`` .. ``R_LAGGING0``."""
    out = cache.out
    if verdict == V_WORSE:
        raised = damping * DAMPING_RAISE
        lam[0] = MAX_DAMPING if MAX_DAMPING < raised else raised  # Python's min(raised, MAX_DAMPING)
    held = verdict == V_SAME or damping >= MAX_DAMPING or creeps(window, met0, posture.factor.shape[0] > 0, c0)
    out[R_CREEPS] = 1.0 if held else 0.0
    if out[R_FRESH] > 0.0:
        out[R_CONVERGED0] = cache.flags[F_CONVERGED]
        out[R_TARGET_COST0] = cache.flags[F_TARGET_COST]
        out[R_LAGGING0] = cache.flags[F_LAGGING]


@njit(cache=True, _nrt=False)
def _retry(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, near, tols, floors, settle,
           restoring, c0, anchors0, met0, e0, cache, wk):
    """``(verdict, deciding level, halvings made)`` of the retries of a worse full step ``cache.dq0`` from ``q``
    (frames ``R``, ``p``, error rows ``e0``), the last retry's trial in ``wk``: with a posture the target levels'
    step alone (better for them, or on), the step halved (:data:`HALVINGS` times at most) until its trial (after up
    to ``restoring`` restoring steps) is no worse, the met levels' correction. ``(-1 - status, 0, 0)`` when the step
    kernel's status is not OK."""
    L = near.shape[0]
    if posture.factor.shape[0] > 0:
        status = _levels_step(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e0, L, tols,
                              wk)
        if status != priority.OK:
            return -1 - status, 0, 0
        verdict, decided = compare_levels(c0, anchors0, met0, wk.costs, wk.met, floors, settle, L)
        if verdict == V_BETTER:
            return verdict, decided, 0
    scale = 1.0
    for tries in range(1, HALVINGS + 1):
        scale *= 0.5
        trial(fk, tasks, posture, root, W, lower, upper, q, cache.dq0, scale, wk)
        verdict, decided = compare_levels(c0, anchors0, met0, wk.costs, wk.met, floors, settle, floors.shape[0])
        if verdict == V_WORSE and restoring > 0:
            verdict, decided = restore(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, near,
                                        tols, restoring, c0, anchors0, met0, floors, settle, wk)
            if verdict < 0:
                return verdict, 0, tries
        if verdict != V_WORSE:
            return verdict, decided, tries
    k = _correctable(c0, met0, floors, L)
    if k > 0:
        status = _levels_step(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e0, k, tols,
                              wk)
        if status != priority.OK:
            return -1 - status, 0, HALVINGS
        verdict, decided = compare_levels(c0, anchors0, met0, wk.costs, wk.met, floors, settle, k)
        if verdict == V_BETTER:
            return verdict, decided, HALVINGS
    return V_WORSE, 0, HALVINGS


@njit(cache=True, _nrt=False)
def _correctable(c0, met0, floors, L):
    """The first unmet level ``k`` (of ``L`` target levels) when the met levels above it may tighten (one's cost
    ``c0`` above its ``floors``), else 0 (``gsik.control.Controller._correction``'s test)."""
    k = 0
    while k < met0.shape[0] and met0[k]:
        k += 1
    if k == 0 or k == L or k == met0.shape[0]:
        return 0
    for j in range(k):
        if c0[j] > floors[j]:
            return k
    return 0


@njit(cache=True, _nrt=False)
def _levels_step(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e0, levels, tols, wk):
    """The step of the first ``levels`` packed levels alone, linearised at ``q`` (frames ``R``, ``p``, error rows
    ``e0``) with the full step's dampings, and its trial into ``wk``. Returns the step kernel's status."""
    linearise(task_model, tasks, posture, q, R, p, e0, wk)
    box(q, q, lower, upper, max_step, wk.lo, wk.hi)
    rank_tol, box_tol, box_rel_tol = tols
    status = priority.prioritized_step_in(wk.priority, wk.rows, wk.errors, wk.weights, tasks.starts[:levels + 1],
                                          wk.dampings[:levels], wk.lo, wk.hi, rank_tol, box_tol, box_rel_tol, wk.dq)
    if status == priority.OK:
        trial(fk, tasks, posture, root, W, lower, upper, q, wk.dq, 1.0, wk)
    return status
