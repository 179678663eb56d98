"""Artist control: prioritised steps over targets on any frame, balance and a preferred posture.

:class:`Controller` is what :class:`gsik.Solver` uses when its targets are
not all on one priority level, aim frames that are not effector sites, or a
posture or balance is on. One step linearises every task at the current
angles and solves the levels in strict order (:func:`gsik.priority.prioritized_step`):

1. the targets of priority 0,
2. balance (when on): the centre of mass over the support polygon,
3. the targets of priority 1, 2, ... in turn,
4. the preferred posture (when on).

A step is kept only if it leaves every level no worse, in order (:func:`gsik.acceptance.compare`). Otherwise it is
halved, then refused and the damping raised (Levenberg-Marquardt, as the fast path does); a full step made worse only by
the posture's move gives way to the target levels' step alone first. A level within its tolerances takes full
Gauss-Newton steps (the base damping): it is a constraint to stay on, and a damping raised for a lower level must not
stop it closing in. A step that changes nothing, or is refused at the largest damping, or ends a run of steps that only
creep (:mod:`gsik.stall`), holds the pose (as a refused step of the fast path does), and holding is remembered, so a
held target settles at its best reach instead of jittering, and a held step costs nothing.

A step without balance is one compiled call (:mod:`gsik.kernels.fallback` over :mod:`gsik.kernels.accept` and
:mod:`gsik.kernels.control`, its fixed inputs held by one :mod:`gsik.kernels.step_inputs` object); this module keeps
the same branches in Python, balance's path and the compiled call's reference. Its inputs live in
:mod:`gsik.control_inputs`, its retargeting and reports in :mod:`gsik.control_targets`.
"""

from __future__ import annotations

import numpy as np

from gsik.acceptance import BETTER, SAME, WORSE, LevelState, anchored, compare
from gsik.balance import center_of_mass, com_jacobian, nearest_point_inside, shrink, signed_distance, support_polygon
from gsik.control_inputs import (CONSTRAINT_TRACKING_ERROR, GROUND_TOLERANCE, TRACKING_ERROR, Balance,  # noqa: F401
                                 ControlStats, FrameTask, Posture, frame_tasks, lag_factors, structure, support)
from gsik.control_inputs import _ordered, held_pose, row_weights, structure_of  # noqa: F401  (structure_of re-exported)
from gsik.control_settle import ControlSettle
from gsik.control_targets import ControlReport, ControlTargets, _same  # noqa: F401  (ControlReport re-exported)
from gsik.kernels import compiled_entry
from gsik.kernels import accept as ak
from gsik.kernels import control as ck
from gsik.kernels import fallback
from gsik.kernels.fallback import DAMPING_RAISE, HALVINGS, MAX_DAMPING
from gsik.kernels import kinematics as kernels
from gsik.kernels import priority as priority_kernel
from gsik.kernels import step_inputs
from gsik.kinematics import kinematic_model, topology
from gsik.priority import BOX_RELATIVE_TOLERANCE, BOX_TOLERANCE, RANK_TOLERANCE, posture_factor
from gsik.rotations import transform

_new_tuple = tuple.__new__  # a NamedTuple with every field given, without its __new__'s Python call

#: Newton steps of the target levels that may bring a posture move back onto them.
RESTORING_STEPS = 3
#: ... in a solve()'s attempt that settles its posture (:meth:`Controller.settle_steps`). On bench_drag's warm solve()
#: drags the first restoring step decided all but 3 of ~1900 and the third none; at 1, with the settle refusals,
#: 12.3 / 7.7 / 14.6 prioritised solves a warm solve() -> 6.9 / 5.6 / 11.4 (hands at 0 / pins / studio) at the same
#: quality (README, "Warm solve() with a posture"). step() keeps 3, so the retargeter and bundled priors do not move.
SETTLE_RESTORING_STEPS = 1
#: While steps succeed the adaptive damping falls to this fraction of ``settings.damping`` (the fast path's floor is
#: 0.1): near a fold of a target's reach (a straight spine raising the head, a straight leg) the smallest singular
#: value of a level seen in what the levels above leave it is ~3e-3, and a step closes only ``s^2 / (s^2 + lam)`` of
#: what is left in that direction: at the fast path's floor (1e-4) 7% a frame (a 15 degree head turn crept for 300
#: frames); at this one, Gauss-Newton (8 frames).
DAMPING_FLOOR = 1e-3
#: A full step taken lowers the adaptive damping by this factor: from the largest to the floor in 20 steps.
DAMPING_FALL = 0.25
#: A met level's tightening counts only if it lowers the level's cost by more than errors of this fraction of
#: the tolerances would cost: pins close in to far under their tolerance, then hold.
TIGHTEN_FRACTION = 0.01
#: Balance sits between the targets of priority 0 and those of priority 1 (arms pulled at 1 cannot tip the body).
BALANCE_PRIORITY = 0.5
#: The centre of mass is held this far [m] inside the support polygon's edge ...
BALANCE_MARGIN = 0.01
#: ... and pulled back once it comes within this band [m] of that line, so it never chatters across it;
BALANCE_BAND = 0.005
#: ... a drift this far [m] past that line (second order, from lower levels' moves) still counts as balanced.
BALANCE_TOLERANCE = 0.001


class Controller(ControlTargets, ControlSettle):
    """Prioritised IK steps for one skeleton seen from one root.

    Every level's state and the linearised, packed levels come from compiled code (:mod:`gsik.kernels.control`):
    without balance a step and its trial are one call. Balance's support polygon is evaluated here.

    Args:
        skeleton: The :class:`gsik.Skeleton` (its ``root`` the IK root).
        tasks: The targets, each a :class:`FrameTask`.
        posture: A :class:`Posture`, or ``None``.
        balance: A :class:`Balance`, or ``None``.
        settings: The :class:`gsik.SolverSettings`.
    """

    #: False: every step through the Python branches (the reference the compiled common path is tested against).
    compiled_step = True
    #: False: a worse full step that would settle a solve()'s posture is retried as any other (:meth:`settle_steps`;
    #: what benchmarks/bench_drag.py measures that shortcut's quality against).
    settle_refusals = True
    #: Restoring steps of the steps to come (:meth:`settle_steps`).
    _restoring = RESTORING_STEPS
    #: The last step's full step when the Python branches judged it, ``None`` when the compiled call made the step.
    _first: np.ndarray | None = None

    def __init__(self, skeleton, tasks, posture: Posture | None, balance: Balance | None, settings):
        self._sk = skeleton
        self._settings = settings
        if balance is not None and not balance.feet:
            balance = None  # no foot on the ground: nothing to stand on
        self._posture = posture
        n = skeleton.n_dofs
        # The posture's precision factored once (a learned prior's is a full matrix): each step only multiplies.
        self._posture_rows = ck.posture_rows(None, np.zeros((0, n))) if posture is None else \
            ck.posture_rows(posture.reference, posture_factor(posture.precision))
        self.posture_gain = self._posture_rows.gain  # (1,) the share of the posture's step taken: 1 but in solve()
        self._share_bound = float(self._posture_rows.share[0])  # bound on the posture's share of a step [rad]
        self._lower, self._upper = np.array(skeleton.lower, dtype=float), np.array(skeleton.upper, dtype=float)
        self._tols = (RANK_TOLERANCE, BOX_TOLERANCE, BOX_RELATIVE_TOLERANCE)
        self._balance = balance
        self._root = skeleton.frame_of(skeleton.root)
        self._held = None  # control_inputs.held_pose of the last step that held the pose
        self._rest_damping = self._last_held = False  # start from the base damping; the last step held the pose
        self._layout = None  # what a result reports, for these effectors (ControlTargets._report_layout)
        self._rows = None  # each task's row in the solver's packed targets (ControlTargets.use_rows), or None
        self._errors_left = False  # the work's errors are those at the pose the last step left
        self._tasks = _ordered(tasks)
        self.key = structure(skeleton, tasks, posture, balance, settings)
        names = [t.name for t in self._tasks]
        self.names = tuple(names)
        self._topo = topology(skeleton, skeleton.root, names)
        self._task_model = kinematic_model(skeleton, self._topo)
        self._fk_model = kinematic_model(skeleton)
        priorities = [t.priority for t in self._tasks]
        if balance is not None:
            priorities.append(BALANCE_PRIORITY)
        # Level index of every task row block, and of balance.
        self._levels = sorted(set(priorities))
        self._task_level = np.array([self._levels.index(t.priority) for t in self._tasks], dtype=np.int64)
        self._balance_level = self._levels.index(BALANCE_PRIORITY) if balance is not None else -1
        m = len(self._tasks)
        self._e = np.zeros(6 * m)
        self._err = np.zeros((2, m))
        self._tp, self._tR = np.zeros((m, 3)), np.zeros((m, 3, 3))
        self._row_w = None  # (m, 6) set with what depends on it by retarget
        self._target_weights = self._orientation_weight = None  # what retarget_targets made _row_w of
        self._M = np.zeros((3, 3))
        if balance is not None:
            bodies = [skeleton.frame_names[f] for f in balance.mass.body_frame]
            self._mass_kinematics = kinematic_model(skeleton, topology(skeleton, skeleton.root, bodies))
            self._Jm = np.zeros((6 * len(balance.mass.mass), n))
        self.retarget(tasks)

    def _thresholds(self) -> None:
        """What depends on the row weights only: the kernels' :class:`~gsik.kernels.control.ControlTasks` (each
        level's rows, the error bounds (2, m) of the band and of convergence, inf where a row is unused), and per
        level (L + 1,) the cost of errors at :data:`TIGHTEN_FRACTION` of the tolerances (``_floors``) and at the
        tolerances (``_near``)."""
        s, w = self._settings, self._row_w
        used = np.stack([w[:, 0] > 0.0, w[:, 3] > 0.0])
        tolerance = np.array([[s.position_tolerance], [s.orientation_tolerance]])
        self._tolerance = np.where(used, tolerance, np.inf)
        L = len(self._levels)
        rows = np.repeat(self._task_level, 6)
        flat = w.reshape(-1)
        level_rows = [np.flatnonzero((rows == k) & (flat > 0.0)) if k != self._balance_level
                      else np.array([-1, -1]) for k in range(L)]  # balance: two rows, filled per step
        packed_row = np.concatenate(level_rows + [np.zeros(0, dtype=np.int64)]).astype(np.int64)
        packed_weight = np.concatenate([flat[r] if r.size == 0 or r[0] >= 0 else np.zeros(2) for r in level_rows]
                                       + [np.zeros(0)])
        counts = [len(r) for r in level_rows] + ([self._sk.n_dofs] if self._posture is not None else [])
        starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self._tasks_in = ck.ControlTasks(self._topo.effector_frame.astype(np.int64), self._tp, self._tR,
                                         np.ascontiguousarray(w), self._task_level,
                                         0.5 * self._tolerance, self._tolerance,
                                         lag_factors(self._task_level) * self._tolerance, packed_row, packed_weight,
                                         starts)
        self._work = ck.make_work(self._sk.n_frames, self._sk.n_dofs, len(self._tasks), starts, L)
        self._entries = {}  # compiled entry points, made at first use for these inputs
        self._layout = None  # a result's errors are reported where these row weights use a row
        per_task = 0.5 * TIGHTEN_FRACTION ** 2 * (w[:, 0] * s.position_tolerance ** 2
                                                  + w[:, 3] * s.orientation_tolerance ** 2)
        floors = np.bincount(self._task_level, per_task, minlength=L + 1)
        if self._balance is not None:
            floors[self._balance_level] = 0.5 * (TIGHTEN_FRACTION * BALANCE_TOLERANCE) ** 2
        self._floors = floors
        self._near = floors[:-1] / TIGHTEN_FRACTION ** 2
        self._window = ak.make_window(np.sqrt(np.append(self._near, 0.0)))  # the posture's: its own size only
        self._cache = ak.make_cache(self._sk.n_dofs, len(self._tasks), L)  # the last accepted pose's levels
        self._step_calls = {}  # restoring steps: (compiled entry, StepInputs), made at the first such compiled step
        self._settle_calls = {}  # restoring steps: steps_until_settled's compiled call, made at its first

    def _call(self, kernel, *args):
        """``kernel(*args)`` through its compiled entry point (made once for these argument types)."""
        entry = self._entries.get(kernel)
        if entry is None:
            entry = self._entries[kernel] = compiled_entry(kernel, *args)
        return entry(*args)

    def _level_state(self, q, R, p) -> LevelState:
        """The levels at ``q`` (frames ``R``, ``p``), anchored at their own costs
        (:class:`~gsik.acceptance.LevelState`).

        A target level is met when all its targets are within half the
        tolerances, balance when the centre of mass is inside the support
        polygon's margin (within :data:`BALANCE_TOLERANCE`); the posture never is (it always compares by cost).
        """
        wk = self._work
        converged, target, lagging = self._call(ck.level_state, self._tasks_in, self._posture_rows, q, R, p, wk.e,
                                                wk.err, wk.M, wk.costs, wk.met)
        return self._state(R, p, converged, target, lagging)

    def _state(self, R, p, converged: bool, target_cost: float, lagging: bool) -> LevelState:
        """The :class:`~gsik.acceptance.LevelState` the kernels left in the work buffers (copied), with balance's
        level evaluated at frames ``R``, ``p``."""
        wk = self._work
        costs, met = wk.costs.copy(), wk.met.copy()
        if self._balance is not None:
            goal, com = self._support_goal(R, p)
            outside = max(signed_distance(goal, com[:2]), 0.0)
            costs[self._balance_level] = 0.5 * outside ** 2
            met[self._balance_level] = outside <= BALANCE_TOLERANCE
        return LevelState(costs, met, costs, bool(converged), float(target_cost), wk.e.copy(), bool(lagging))

    def rank(self, q, R, p) -> tuple:
        """The levels' costs in priority order (a met level counts 0): compare poses lexicographically."""
        state = self._level_state(q, R, p)
        return tuple(np.where(state.met, 0.0, state.costs).tolist())

    def _support_goal(self, R, p) -> tuple[np.ndarray, np.ndarray]:
        """The polygon the centre of mass must stay in (support shrunk by the margin) and the centre of mass."""
        b = self._balance
        feet = [transform(R[f], p[f]) for f in b.feet]
        goal = shrink(support_polygon(feet, list(b.soles)), BALANCE_MARGIN)
        return goal, center_of_mass(b.mass, R, p)

    # -- the linearised levels -------------------------------------------------
    def _linearise(self, q, R, p, error: np.ndarray) -> None:
        """The levels linearised at ``q`` (frames ``R``, ``p``, the targets' error rows ``error`` (6 m,) there),
        packed into the work buffers in priority order, the posture last."""
        wk = self._work
        self._call(ck.linearise, self._task_model, self._tasks_in, self._posture_rows, q, R, p, error, wk)
        if self._balance is not None:
            self._balance_rows(R, p)

    def _balance_rows(self, R, p) -> None:
        """Balance's two packed rows: the centre of mass's ground Jacobian and its way back into the support
        polygon, or (inside the band) two rows of weight 0, which the step's kernel leaves out."""
        wk = self._work
        a = self._tasks_in.starts[self._balance_level]
        goal, com = self._support_goal(R, p)
        if signed_distance(goal, com[:2]) <= -BALANCE_BAND:
            wk.rows[a:a + 2], wk.errors[a:a + 2], wk.weights[a:a + 2] = 0.0, 0.0, 0.0
            return
        kernels.jacobian(self._mass_kinematics, R, p, self._Jm)
        wk.rows[a:a + 2] = com_jacobian(self._balance.mass, R, self._Jm)[:2]
        wk.errors[a:a + 2] = nearest_point_inside(goal, com[:2]) - com[:2]
        wk.weights[a:a + 2] = 1.0

    def _solve(self, q, q_from, levels: int) -> np.ndarray:
        """The strict-priority step (n,) of the first ``levels`` packed levels, from ``q_from`` within the box whose
        step limit counts from ``q`` (:func:`gsik.kernels.control.box`)."""
        wk, tols = self._work, self._tols
        self._call(ck.box, q, q_from, self._lower, self._upper, self._settings.max_step, wk.lo, wk.hi)
        if self._call(priority_kernel.prioritized_step_in, wk.priority, wk.rows, wk.errors, wk.weights,
                      self._tasks_in.starts[:levels + 1], wk.dampings[:levels], wk.lo, wk.hi, tols[0], tols[1],
                      tols[2], wk.dq) != priority_kernel.OK:
            raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
        return wk.dq.copy()

    # -- one step --------------------------------------------------------------
    def step(self, q: np.ndarray, W: np.ndarray, R: np.ndarray, p: np.ndarray, lam: np.ndarray) -> ControlStats:
        """One prioritised step from ``q`` (n_dofs,) [rad], in place on ``q``, ``R``, ``p`` and ``lam`` (1,).

        ``R``, ``p`` hold the world frames at ``q`` with the root pinned at ``W`` (4, 4). Without balance the whole
        step, a refused full step's fallback too, is one compiled call (:func:`gsik.kernels.fallback.control_step`);
        the Python branches here are its reference (``compiled_step`` False) and balance's path."""
        s = self._settings
        self._first = None
        if self._rest_damping:
            lam[0], self._rest_damping = s.damping, False
        damping = float(lam[0]) if s.adaptive_damping else s.damping
        self._errors_left = False
        if self._holds(q, W, damping):
            return self._held[3]  # the same step from the same pose: it would hold again
        if self._balance is None and s.adaptive_damping and self.compiled_step:
            entry, inputs = self._step_calls.get(self._restoring) or self._make_step_call(W, q, R, p, lam, damping)
            end = entry(inputs, W, q, R, p, lam, damping)
            if end[0] != priority_kernel.OK:
                raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
            if end[1]:
                self._errors_left = True  # the trial's, at the pose committed
                return self._stats(q, W, lam, self._committed(end))
            return self._stats(q, W, lam, _new_tuple(ControlStats, (False, end[2] > 0.0, end[3] > 0.0, end[4], 0.0,
                                                                    end[5] > 0.0)))
        fresh = self._call(ak.is_fresh, self._cache, q, W)
        state0 = ak.cached_state(self._cache) if fresh else self._level_state(q, R, p)
        if not fresh:
            self._window.ring[:] = 0  # the pose changed from outside
        first = self._first_trial(q, W, R, p, state0, damping)
        self._first = first
        tries, ((verdict, decided), q2, R2, p2, state) = self._damped_trial(q, W, R, p, state0, first)
        accepted = verdict == BETTER or not s.adaptive_damping
        if accepted:
            step_norm = self._call(step_inputs.norm, q2 - q)  # the compiled call's sum, bit for bit
            q[:], R[:], p[:] = q2, R2, p2
            state = anchored(state, state0, decided if verdict == BETTER else 0)
            ak.store(self._cache, q, W, state)
        else:
            step_norm, state = 0.0, state0
        self._adapt_damping(lam, damping, verdict, accepted, tries)
        # Held: nothing would change, the largest damping's step is refused, or the steps only creep (gsik.stall).
        held = s.adaptive_damping and (verdict == SAME or (accepted and step_norm <= s.stall_tolerance)
                                       or (not accepted and damping >= MAX_DAMPING) or self._call(
                                           ak.creeps_after, accepted and self._whole, self._posture_rows, self._work,
                                           self._window, state.met, state.costs))
        return self._stats(q, W, lam, ControlStats(accepted, held, state.converged, state.target_cost, step_norm,
                                                   state.lagging))

    def step_arguments(self) -> tuple:
        """``(head, mid, tail)``: :func:`gsik.kernels.accept.control_step`'s arguments that are fixed for these
        inputs, as ``control_step(*head, W, *mid, q, R, p, lam, damping, *tail)`` takes them."""
        s = self._settings
        return ((self._task_model, self._fk_model, self._tasks_in, self._posture_rows, self._root),
                (self._lower, self._upper, s.max_step),
                (s.damping, self._near, self._tols, self._floors, (float(s.settle_tolerance), DAMPING_FALL,
                                                                   DAMPING_FLOOR),
                 self._restoring if self._posture is not None else 0, float(s.stall_tolerance), self._cache,
                 self._window, self._work))

    def _make_step_call(self, W, q, R, p, lam, damping) -> tuple:
        """``(entry, inputs)``: :func:`gsik.kernels.step_inputs.control_step`'s compiled entry and this controller's
        :class:`~gsik.kernels.step_inputs.StepInputs` (numba unboxes one object, not ~70 arrays a step), kept; without
        numba, :func:`gsik.kernels.fallback.control_step` given every argument."""
        head, mid, tail = self.step_arguments()
        if not step_inputs.AVAILABLE:
            call = (lambda _, W, q, R, p, lam, damping: self._end(fallback.control_step(
                *head, W, *mid, q, R, p, lam, damping, *tail)), None)
        else:
            inputs = step_inputs.make_step_inputs(*head, *mid, *tail)
            call = (compiled_entry(step_inputs.control_step, inputs, W, q, R, p, lam, damping), inputs)
        self._step_calls[self._restoring] = call
        return call

    def _end(self, _=None) -> tuple:
        """What :func:`gsik.kernels.step_inputs.control_step` returns, read from the cache (the call without it)."""
        return fallback.step_end(self._cache)

    def _committed(self, end: tuple) -> ControlStats:
        """The :class:`ControlStats` of a step :func:`~gsik.kernels.accept.control_step` committed (``end``: what
        :func:`gsik.kernels.step_inputs.control_step` returns; :func:`gsik.kernels.frame_step.frame_step` judges
        the same): held when the step's norm (:func:`gsik.kernels.step_inputs.norm`) is at most the stall tolerance
        or the stall window says it creeps (asked here when the kernel left it to that norm)."""
        cache, tolerance = self._cache, self._settings.stall_tolerance
        _, _, crept, converged, target_cost, lagging, step_norm = end
        if crept < 0.0:
            crept = not step_norm <= tolerance and self._call(ak.creeps, self._window, cache.met,
                                                              self._posture is not None, cache.costs)
        return _new_tuple(ControlStats, (True, step_norm <= tolerance or crept > 0.0, converged > 0.0, target_cost,
                                         step_norm, lagging > 0.0))

    def _stats(self, q, W, lam, stats: ControlStats) -> ControlStats:
        """``stats``; a held pose is kept until the targets change (a frame asked for anyway changes nothing)."""
        self._held = held_pose(q, W, lam[0], stats.converged, stats.cost, stats.lagging) if stats.held else None
        self._last_held = stats.held
        return stats

    def _holds(self, q, W, damping) -> bool:
        """True if the last step held the pose ``q`` at ``W`` with this damping: a step now would do the same."""
        held = self._held
        return held is not None and held[2] == damping and _same(q, held[0]) and _same(W, held[1])

    def _damped_trial(self, q, W, R, p, state0: LevelState, dq: np.ndarray) -> tuple[int, tuple]:
        """``(halvings made, trial)``: the prioritised step ``dq`` (n,) from ``q`` (its full trial in the work
        buffers), halved up to :data:`HALVINGS` times while its trial (:meth:`_judge`) is worse (with adaptive
        damping only); if it stays worse, the met levels' correction alone (:meth:`_correction`). Compiled:
        :func:`gsik.kernels.fallback.control_step`."""
        scale, self._whole = 1.0, False  # whole: the full step's trial (restored or not) is the one returned
        for tries in range(HALVINGS + 1):
            if tries:
                self._trial(q, dq, scale, W)
            trial = self._judge(q, W, state0)
            if trial[0][0] != WORSE or not self._settings.adaptive_damping:
                self._whole = tries == 0
                return tries, trial
            if tries == 0 and self._settles(state0, dq):
                return tries, trial
            if tries == 0 and self._posture is not None:
                targets = self._targets_alone(q, W, R, p, state0)
                if targets is not None:
                    return 0, targets
            scale *= 0.5
        return tries, self._correction(q, W, R, p, state0) or trial

    def settle_steps(self, tolerance: float) -> None:
        """The posture's settle tolerance [rad] of the steps to come: ``settings.posture_tolerance`` while a solve()'s
        :class:`gsik.stall.PostureSettle` runs, 0 after. While on, a worse full step that would settle the posture
        (:meth:`_settles`) is refused at once (retries would move it by about the tolerance, for up to 13 steps), a
        posture move that broke a met level gets :data:`SETTLE_RESTORING_STEPS` restoring steps, and the prior's share
        of a step is not bounded (``PostureRows.share``; PostureSettle's gain rules)."""
        on, rows = tolerance > 0.0 and self.settle_refusals, self._posture_rows
        self._cache.settle[0] = tolerance if on else 0.0
        self._restoring = SETTLE_RESTORING_STEPS if on else RESTORING_STEPS
        rows.share[0] = self._share_bound if tolerance <= 0.0 else 0.0

    def _settles(self, state0: LevelState, dq: np.ndarray) -> bool:
        """True if the full step ``dq`` (n,) [rad] from the start state ``state0`` settles the posture
        (:class:`gsik.stall.PostureSettle`'s test at :meth:`settle_steps`'s tolerance; compiled:
        :func:`gsik.kernels.fallback.settles`)."""
        tolerance = float(self._cache.settle[0])
        return tolerance > 0.0 and state0.converged and \
            float(np.abs(dq).max()) <= tolerance * float(self.posture_gain[0])

    def _first_trial(self, q, W, R, p, state0: LevelState, damping: float) -> np.ndarray:
        """The full step (n,) from ``q``, its trial left in the work buffers (one compiled call without balance)."""
        wk, s = self._work, self._settings
        if self._balance is None:
            self._call(ck.step_trial, self._task_model, self._fk_model, self._tasks_in, self._posture_rows,
                       self._root, W, self._lower, self._upper, s.max_step, q, R, p, state0.error, state0.costs,
                       damping, s.damping, self._near, self._tols, wk)
            if wk.out[ck.O_STATUS] != priority_kernel.OK:
                raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
            return wk.dq.copy()
        self._linearise(q, R, p, state0.error)
        ck.dampings_into(state0.costs, self._near, damping, s.damping, self._posture is not None, wk.dampings)
        dq = self._solve(q, q, len(wk.dampings))
        self._trial(q, dq, 1.0, W)
        return dq

    def _trial(self, q, dq, scale: float, W) -> None:
        """The trial ``clip(q + scale dq)``: its frames and level state into the work buffers."""
        self._call(ck.trial, self._fk_model, self._tasks_in, self._posture_rows, self._root, W, self._lower,
                   self._upper, q, dq, scale, self._work)

    def _trial_state(self) -> tuple:
        """``(q, R, p, LevelState)`` of the trial in the work buffers (copies)."""
        wk = self._work
        out = wk.out.tolist()
        state = self._state(wk.R, wk.p, out[ck.O_CONVERGED] > 0.0, out[ck.O_TARGET_COST], out[ck.O_LAGGING] > 0.0)
        return wk.q.copy(), wk.R.copy(), wk.p.copy(), state

    def _targets_alone(self, q, W, R, p, state0: LevelState) -> tuple | None:
        """The trial of the target levels' step alone (the posture's left out), if it is better for them, else
        ``None``. A full step is worse when the posture's move, flat only to first order, costs a target level more
        than the level's own step gains (a target at a fold of its reach: a yawed head on a straight spine); halving
        it and raising the damping would then damp the target levels' own step too, and they would creep."""
        self._linearise(q, R, p, state0.error)  # a restoring step may have linearised elsewhere since
        self._trial(q, self._solve(q, q, len(self._levels)), 1.0, W)
        trial = self._judge(q, W, state0, upto=len(self._levels))
        return trial if trial[0][0] == BETTER else None

    def _correction(self, q, W, R, p, state0: LevelState) -> tuple | None:
        """The trial of the step of the met levels above the first unmet one alone, if it tightens them (a lower
        level may lose what their correction costs it: strict priority), else ``None``. A lower level's move
        leaves them off by its second order; when that move is refused, this still closes them in."""
        k = int(np.argmin(state0.met))  # the leading met levels (the posture, last, never is)
        if k == 0 or k == len(self._levels) or not np.any(state0.costs[:k] > self._floors[:k]):
            return None
        self._linearise(q, R, p, state0.error)
        self._trial(q, self._solve(q, q, k), 1.0, W)
        trial = self._judge(q, W, state0, upto=k)
        return trial if trial[0][0] == BETTER else None

    def first_step(self) -> np.ndarray:
        """(n_dofs,) [rad] the last step's full step (before halving or restoring; not held): a view, read it now."""
        return self._first if self._first is not None else self._cache.dq0

    def _adapt_damping(self, lam: np.ndarray, damping: float, verdict: str, accepted: bool, tries: int) -> None:
        """Levenberg-Marquardt on ``lam`` (1,): lower it after a full step taken, raise it after a worse one."""
        s = self._settings
        if accepted and s.adaptive_damping:
            lam[0] = max(damping * DAMPING_FALL, s.damping * DAMPING_FLOOR) if tries == 0 else damping
        elif not accepted and verdict == WORSE:
            lam[0] = min(damping * DAMPING_RAISE, MAX_DAMPING)

    def _judge(self, q, W, state0: LevelState, upto: int | None = None):
        """``((verdict, deciding level), q, R, p, level state)`` of the trial in the work buffers
        (:func:`~gsik.acceptance.compare`, on the levels above ``upto`` only if given). When a lower level's move
        breaks a met higher level (the null space is only flat to first order), up to :meth:`settle_steps`'s number of
        restoring steps of the target levels from the trial pose bring it back onto them, and that pose is judged
        instead."""
        settle = self._settings.settle_tolerance
        first = self._trial_state()
        verdict = compare(state0, first[3], settle, self._floors, upto)
        if verdict[0] != WORSE or self._posture is None or upto is not None:
            return (verdict,) + first
        q3, R3, p3, state3 = first
        for _ in range(self._restoring):
            self._linearise(q3, R3, p3, state3.error)
            self._trial(q3, self._solve(q, q3, len(self._levels)), 1.0, W)
            q3, R3, p3, state3 = self._trial_state()
            restored = compare(state0, state3, settle, self._floors)
            if restored[0] != WORSE:
                return restored, q3, R3, p3, state3
        return (verdict,) + first
