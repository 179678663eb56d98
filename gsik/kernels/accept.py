"""The prioritised step's acceptance compiled: the level rule, the anchors, the stall window, the whole common step.

:class:`gsik.control.Controller` keeps a step only if the trial's levels are no worse in priority order
(:func:`gsik.acceptance.compare`, the Python reference of :func:`compare_levels`), anchors what it accepted
(:func:`gsik.acceptance.anchored`, of :func:`anchor_into`) and calls a run of steps that only creep a stall
(:class:`gsik.stall.StallDetector`, of :func:`creeps`). Here those run over arrays kept in place:

- :class:`LevelCache`: the levels' state at the last accepted pose (what ``LevelState`` holds), with the pose it
  holds for, and a start state's buffers for a pose that came from outside.
- :class:`StallWindow`: the last steps' unmet levels and error norms, a ring.

:func:`control_step` is the common path in one call: the start state (cached, or evaluated), the step and its trial
(:func:`gsik.kernels.control.step_trial`), the rule, and when the trial is better the commit (pose, anchors, cache,
damping, :func:`commit`). A worse or unchanged trial it leaves in the work buffers, for the refused step's
fallback (:func:`gsik.kernels.fallback.control_step`: halvings, the target levels alone, the met levels' correction).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik._jit import njit
from gsik.acceptance import BETTER, SAME, WORSE, LevelState
from gsik.kernels import priority
from gsik.kernels.control import O_CONVERGED, O_LAGGING, O_SHARE, O_STATUS, O_TARGET_COST, box, level_state, \
    linearise, step_trial, trial
from gsik.kernels.step import copy_into, copy_rows, take_frames
from gsik.stall import STALL_PROGRESS, STALL_SHRINK, STALL_WINDOW

#: Verdict codes of :func:`compare_levels`: :data:`gsik.acceptance.BETTER`, ``SAME``, ``WORSE`` in that order.
V_BETTER, V_SAME, V_WORSE = range(3)
VERDICTS = (BETTER, SAME, WORSE)
# Indices of LevelCache.flags: the cache holds a state; that state's convergence, targets' cost, lagging (1.0 / 0.0).
F_VALID, F_CONVERGED, F_TARGET_COST, F_LAGGING = range(4)
# Indices of LevelCache.out (control_step's report): the start state was cached; the verdict code and deciding level
# of the last trial judged; the trial was committed; the step kernel's status; an evaluated start state's convergence,
# targets' cost and lagging (1.0 / 0.0); after a commit, the stall window's verdict (1.0 creeps, 0.0 not, -1.0 not
# asked: the step's norm is within rounding of the stall tolerance, NumPy's norm decides); restoring steps were made
# (1.0: the work buffers no longer hold the first trial).
R_FRESH, R_VERDICT, R_DECIDED, R_COMMITTED, R_STATUS, R_CONVERGED0, R_TARGET_COST0, R_LAGGING0, R_CREEPS, \
    R_RESTORED = range(10)
#: A committed step's norm summed in loop order is within this fraction of NumPy's (BLAS's order).
NORM_ROUNDING = 1e-12


class LevelCache(NamedTuple):
    """The levels at the last accepted pose, and a start state's buffers (:func:`make_cache`).

    Attributes:
        q: (n,) the accepted angles [rad]. W: (4, 4) the root's world transform they were accepted at.
        costs, anchors: (L + 1,) the levels' costs and anchors there. met: (L + 1,) bool the met levels.
        e: (6m,) the targets' error rows there. flags: (4,) the ``F_*`` figures.
        costs0: (L + 1,), met0: (L + 1,) bool, e0: (6m,): the state of a start pose that is not the cached one.
        moved: (n,) the committed step's change of the angles [rad]. out: (10,) :func:`control_step`'s ``R_*``.
        dq0: (n,) the step's first (full) step [rad], kept: restoring steps and the fallback
        (:mod:`gsik.kernels.fallback`) overwrite the work buffers'.
        settle: (1,) the posture's settle tolerance [rad] of a solve()'s steps (``settings.posture_tolerance``
        while :class:`gsik.stall.PostureSettle` runs, else 0): a worse full step that would settle the posture is
        refused without retries (:func:`gsik.kernels.fallback.settles`).
    """

    q: np.ndarray
    W: np.ndarray
    costs: np.ndarray
    met: np.ndarray
    anchors: np.ndarray
    e: np.ndarray
    flags: np.ndarray
    costs0: np.ndarray
    met0: np.ndarray
    e0: np.ndarray
    moved: np.ndarray
    out: np.ndarray
    dq0: np.ndarray
    settle: np.ndarray


def make_cache(n_dofs: int, n_tasks: int, n_levels: int) -> LevelCache:
    """An empty :class:`LevelCache` for ``n_levels`` (L) target and balance levels (the posture's is one more)."""
    k = n_levels + 1
    return LevelCache(np.zeros(n_dofs), np.zeros((4, 4)), np.zeros(k), np.zeros(k, dtype=np.bool_), np.zeros(k),
                      np.zeros(6 * n_tasks), np.zeros(4), np.zeros(k), np.zeros(k, dtype=np.bool_),
                      np.zeros(6 * n_tasks), np.zeros(n_dofs), np.zeros(10), np.zeros(n_dofs), np.zeros(1))


def cached_state(cache: LevelCache) -> LevelState:
    """The :class:`~gsik.acceptance.LevelState` of the last accepted pose (copies of the cache)."""
    flags = cache.flags.tolist()
    return LevelState(cache.costs.copy(), cache.met.copy(), cache.anchors.copy(), flags[F_CONVERGED] > 0.0,
                      flags[F_TARGET_COST], cache.e.copy(), flags[F_LAGGING] > 0.0)


def start_state(cache: LevelCache, out: list) -> LevelState:
    """The start pose's :class:`~gsik.acceptance.LevelState` that :func:`control_step` evaluated (``out``: its
    ``R_*`` figures), anchored at its own costs."""
    costs = cache.costs0.copy()
    return LevelState(costs, cache.met0.copy(), costs, out[R_CONVERGED0] > 0.0, out[R_TARGET_COST0],
                      cache.e0.copy(), out[R_LAGGING0] > 0.0)


def store(cache: LevelCache, q: np.ndarray, W: np.ndarray, state: LevelState) -> None:
    """Cache ``state`` as the levels at the accepted pose ``q`` (n,) at ``W`` (4, 4)."""
    cache.q[:], cache.W[:], cache.costs[:], cache.met[:] = q, W, state.costs, state.met
    cache.anchors[:], cache.e[:] = state.anchors, state.error
    cache.flags[:] = 1.0, float(state.converged), state.target_cost, float(state.lagging)


class StallWindow(NamedTuple):
    """:class:`gsik.stall.StallDetector`'s history as arrays (:func:`make_window`).

    Attributes:
        enough: (K,) the gain of each level's error norm that is progress (STALL_PROGRESS of its tolerance norm).
        unmet: (STALL_WINDOW + 1, K) bool, norms: (STALL_WINDOW + 1, K): a ring of the last steps.
        ring: (2,) int64 the steps held and the slot of the oldest.
    """

    enough: np.ndarray
    unmet: np.ndarray
    norms: np.ndarray
    ring: np.ndarray


def make_window(tolerance_norms: np.ndarray) -> StallWindow:
    """An empty :class:`StallWindow` for levels of these tolerance norms (K,) (0: only its own size counts)."""
    k = len(tolerance_norms)
    return StallWindow(STALL_PROGRESS * np.asarray(tolerance_norms, dtype=float),
                       np.zeros((STALL_WINDOW + 1, k), dtype=np.bool_), np.zeros((STALL_WINDOW + 1, k)),
                       np.zeros(2, dtype=np.int64))


@njit(cache=True, _nrt=False)
def norm(v):
    """``sqrt(sum(v ** 2))`` [rad] of a step ``v`` (n,), summed in order: every controlled step's norm, whether the
    compiled call committed it (:func:`commit`) or the controller's Python branches did, is this one sum."""
    s = 0.0
    for d in range(v.shape[0]):
        s += v[d] * v[d]
    return math.sqrt(s)


@njit(cache=True, _nrt=False)
def compare_levels(c0, anchors, met0, c1, met1, floors, settle, upto):
    """``(V_BETTER | V_SAME | V_WORSE, deciding level)`` of a trial (costs ``c1``, met ``met1``) against its start
    (``c0``, ``anchors``, ``met0``), levels ``[0, upto)`` (:func:`gsik.acceptance.compare`'s rule, bit for bit)."""
    tightened = False
    loosened = False
    for k in range(upto):
        a, b = c0[k], c1[k]
        if met0[k] and met1[k]:
            tightened = tightened or b < a - floors[k]
            loosened = loosened or b > a + floors[k]
            continue
        if met0[k] != met1[k]:
            return (V_BETTER if met1[k] else V_WORSE), k
        if b > anchors[k] * (1.0 + settle) + 1e-300:
            return V_WORSE, k
        if b < a * (1.0 - settle):
            return V_BETTER, k
    return (V_BETTER if tightened and not loosened else V_SAME), upto


@njit(cache=True, _nrt=False)
def anchor_into(before, costs, decided, out):
    """``out`` (L + 1,) = ``minimum(before, costs)``, and ``costs`` from level ``decided`` on
    (:func:`gsik.acceptance.anchored`; a NaN either side stays NaN, as NumPy's minimum)."""
    for k in range(costs.shape[0]):
        a, c = before[k], costs[k]
        if k >= decided:
            out[k] = c
        elif math.isnan(a) or math.isnan(c):
            out[k] = math.nan
        else:
            out[k] = a if a < c else c


@njit(cache=True, _nrt=False)
def reset(window):
    """Forget the steps so far."""
    window.ring[0] = 0
    window.ring[1] = 0


@njit(cache=True, _nrt=False)
def creeps(window, met, posture_on, costs):
    """:meth:`gsik.stall.StallDetector.creeps` on ``window``, with the unmet levels from ``met`` (K,) (the posture's,
    last, unmet while on: :func:`gsik.stall.unmet_levels`) and the levels' ``costs`` (K,) after this step."""
    K = costs.shape[0]
    slots = window.unmet.shape[0]
    any_unmet = posture_on
    for k in range(K - 1):
        any_unmet = any_unmet or not met[k]
    count, head = window.ring[0], window.ring[1]
    if count > 0 and any_unmet:
        last = (head + count - 1) % slots
        for k in range(K):
            u = posture_on if k == K - 1 else not met[k]
            if window.unmet[last, k] != u:
                count, head = 0, 0
                break
    if not any_unmet:
        window.ring[0], window.ring[1] = 0, 0
        return False
    if count < slots:
        slot = (head + count) % slots
        count += 1
    else:
        slot = head
        head = (head + 1) % slots
    for k in range(K):
        window.unmet[slot, k] = posture_on if k == K - 1 else not met[k]
        c = costs[k]
        window.norms[slot, k] = math.sqrt(c) if c >= 0.0 else math.nan
    window.ring[0], window.ring[1] = count, head
    if count <= slots - 1:
        return False
    for k in range(K):
        if not window.unmet[slot, k]:
            continue
        before = window.norms[head, k]
        enough = window.enough[k]
        shrink = STALL_SHRINK * before
        if shrink > enough:  # Python's max(enough, shrink): the first unless the second is larger
            enough = shrink
        if not before - window.norms[slot, k] < enough:
            return False
    return True


@njit(cache=True, _nrt=False)
def is_fresh(cache, q, W):
    """True if the cache holds a state for exactly ``q`` (n,) and ``W`` (4, 4) (bit for bit, as ``tobytes``)."""
    if cache.flags[F_VALID] == 0.0:
        return False
    if not _same_bits(cache.q, q):
        return False
    a, b = cache.W.view(np.int64), W.view(np.int64)
    for i in range(4):
        for j in range(4):
            if a[i, j] != b[i, j]:
                return False
    return True


@njit(cache=True, _nrt=False)
def _same_bits(a, b):
    """True if ``a`` and ``b`` (n,) hold the same bits."""
    a, b = a.view(np.int64), b.view(np.int64)
    for d in range(a.shape[0]):
        if a[d] != b[d]:
            return False
    return True


@njit(cache=True, _nrt=False)
def control_step(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, lam, damping, base, near,
                 tols, floors, rule, restoring, stall_tolerance, cache, window, wk):
    """One prioritised step without balance from ``q`` (n,) [rad] (frames ``R``, ``p``; ``lam`` (1,) the adaptive
    damping, ``damping`` this step's): the start state (``cache``'s when :func:`is_fresh`, else evaluated into its
    ``*0`` buffers and the stall ``window`` reset), the step and its trial (:func:`step_trial`), the rule
    (:func:`compare_levels`; ``rule``: (settle fraction, damping fall, damping floor)), and while a trial is worse up
    to ``restoring`` restoring steps of the target levels from it (``gsik.control.Controller._judge``'s, for a
    posture's move that broke a met level); a better trial is committed:
    ``q``, ``R``, ``p`` moved to it (``cache.moved`` the change), anchored into ``cache``, ``lam[0]`` lowered, and
    unless the change's norm is at most ``stall_tolerance`` [rad] the stall ``window`` asked (:func:`creeps`;
    :func:`commit`). ``cache.out``: the ``R_*`` figures; ``cache.dq0`` the full step. A trial no better is left in
    ``wk`` (:func:`gsik.kernels.fallback.control_step` goes on from it)."""
    settle, fall, floor = rule
    fresh = is_fresh(cache, q, W)
    out = cache.out
    if fresh:
        c0, met0, anchors0, e0 = cache.costs, cache.met, cache.anchors, cache.e
    else:
        converged, target, lagging = level_state(tasks, posture, q, R, p, cache.e0, wk.err, wk.M, cache.costs0,
                                                 cache.met0)
        out[R_CONVERGED0], out[R_TARGET_COST0], out[R_LAGGING0] = converged, target, lagging
        c0, met0, anchors0, e0 = cache.costs0, cache.met0, cache.costs0, cache.e0
        reset(window)
    out[R_FRESH] = 1.0 if fresh else 0.0
    out[R_COMMITTED] = 0.0
    step_trial(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e0, c0, damping, base, near,
               tols, wk)
    out[R_STATUS] = wk.out[O_STATUS]
    if wk.out[O_STATUS] != priority.OK:
        return
    copy_into(cache.dq0, wk.dq)  # the first step, kept for halving it and for first_step()
    verdict, decided = compare_levels(c0, anchors0, met0, wk.costs, wk.met, floors, settle, floors.shape[0])
    out[R_RESTORED] = 0.0
    if verdict == V_WORSE and restoring > 0:
        out[R_RESTORED] = 1.0
        verdict, decided = restore(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, near, tols,
                                    restoring, c0, anchors0, met0, floors, settle, wk)
        if verdict < 0:
            out[R_STATUS] = -verdict - 1
            return
    out[R_VERDICT], out[R_DECIDED] = verdict, decided
    if verdict == V_BETTER:
        commit(q, R, p, W, lam, damping * fall, base * floor, anchors0, decided, posture, stall_tolerance, True,
               cache, window, wk)


@njit(cache=True, _nrt=False)
def commit(q, R, p, W, lam, lowered, low, anchors0, decided, posture, stall_tolerance, whole, cache, window, wk):
    """Commit the trial in ``wk``: ``q``, ``R``, ``p`` moved to it (``cache.moved`` the change), anchored from
    ``anchors0`` at level ``decided`` into ``cache``, ``lam[0]`` set to ``max(lowered, low)`` (Python's order), and
    unless the change's norm is at most ``stall_tolerance`` [rad] the stall ``window`` asked (:func:`creeps_after`,
    ``whole``: the trial is the full step's, restored or not; ``cache.out``'s ``R_COMMITTED`` and ``R_CREEPS``)."""
    out = cache.out
    anchor_into(anchors0, wk.costs, decided, cache.anchors)  # in place when anchors0 is cache.anchors
    for d in range(q.shape[0]):
        cache.moved[d] = wk.q[d] - q[d]
        q[d] = wk.q[d]
        cache.q[d] = wk.q[d]
    take_frames(R, p, wk.R, wk.p)
    copy_rows(cache.W, W)
    copy_into(cache.costs, wk.costs)
    copy_into(cache.met, wk.met)
    copy_into(cache.e, wk.e)
    cache.flags[F_VALID] = 1.0
    cache.flags[F_CONVERGED] = wk.out[O_CONVERGED]
    cache.flags[F_TARGET_COST] = wk.out[O_TARGET_COST]
    cache.flags[F_LAGGING] = wk.out[O_LAGGING]
    lam[0] = low if low > lowered else lowered  # Python's max(lowered, low)
    out[R_COMMITTED] = 1.0
    out[R_CREEPS] = -1.0
    moved = norm(cache.moved)
    if moved < stall_tolerance * (1.0 - NORM_ROUNDING):
        out[R_CREEPS] = 0.0  # held by its norm alone: the window is not asked
    elif moved > stall_tolerance * (1.0 + NORM_ROUNDING) or (whole and share_bounded(posture, wk)):
        # above it in any summation order (or a bounded posture move, never a creep): the window decides
        out[R_CREEPS] = 1.0 if creeps_after(whole, posture, wk, window, cache.met, cache.costs) else 0.0


@njit(cache=True, _nrt=False)
def creeps_after(whole, posture, wk, window, met, costs):
    """:func:`creeps` after a step, the posture on when ``posture`` has rows. A full step taken (``whole``: not
    halved, nor the target levels' alone) whose posture share was bounded (:func:`share_bounded`) is the posture
    closing in, never a creep: the window starts again after it."""
    if whole and share_bounded(posture, wk):
        reset(window)
        return False
    return creeps(window, met, posture.factor.shape[0] > 0, costs)


@njit(cache=True, _nrt=False)
def share_bounded(posture, wk):
    """True if the last full step's posture share was scaled onto its bound (``wk.out[O_SHARE]`` above
    ``posture.share[0]``; :func:`gsik.kernels.posture_level.prioritized_step_posture`): the posture has further to go
    than one step takes, so the step has not settled."""
    return wk.out[O_SHARE] > posture.share[0]


@njit(cache=True, _nrt=False)
def restore(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, near, tols, restoring, c0, anchors0,
             met0, floors, settle, wk):
    """Up to ``restoring`` steps of the target levels (the first ``L`` packed levels, ``near`` (L,)) linearised at
    the trial in ``wk``, each from there within the box counted from ``q``, until a trial is no worse than the start
    (``c0``, ``anchors0``, ``met0``). Returns :func:`compare_levels`'s ``(verdict, level)`` of the last trial, or
    ``(-1 - status, 0)`` when the step kernel's status is not OK."""
    rank_tol, box_tol, box_rel_tol = tols
    L = near.shape[0]
    verdict, decided = V_WORSE, 0
    for _ in range(restoring):
        linearise(task_model, tasks, posture, wk.q, wk.R, wk.p, wk.e, wk)
        box(q, wk.q, lower, upper, max_step, wk.lo, wk.hi)
        status = priority.prioritized_step_in(wk.priority, wk.rows, wk.errors, wk.weights, tasks.starts[:L + 1],
                                              wk.dampings[:L], wk.lo, wk.hi, rank_tol, box_tol, box_rel_tol, wk.dq)
        if status != priority.OK:
            return -1 - status, 0
        trial(fk, tasks, posture, root, W, lower, upper, wk.q, wk.dq, 1.0, wk)
        verdict, decided = compare_levels(c0, anchors0, met0, wk.costs, wk.met, floors, settle, floors.shape[0])
        if verdict != V_WORSE:
            break
    return verdict, decided
