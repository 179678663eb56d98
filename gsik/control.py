"""Artist control: prioritised steps over targets on any frame, balance and a preferred posture.

:class:`Controller` is what :class:`gsik.Solver` uses when its targets are
not all on one priority level, aim frames that are not effector sites, or a
posture or balance is on. One step linearises every task at the current
angles and solves the levels in strict order (:func:`gsik.priority.prioritized_step`):

1. the targets of priority 0,
2. balance (when on): the centre of mass over the support polygon,
3. the targets of priority 1, 2, ... in turn,
4. the preferred posture (when on).

A step is kept only if it leaves every level no worse, in order
(:func:`gsik.acceptance.compare`). Otherwise it is halved, then refused and
the damping raised (Levenberg-Marquardt, as the fast path does); a full step
made worse only by the posture's move gives way to the target levels' step
alone first. A level within its tolerances takes full Gauss-Newton steps (the
base damping): it is a constraint to stay on, and a damping raised for a lower
level must not stop it closing in. A step that changes nothing, or is refused
at the largest damping, or ends a run of steps that only creep
(:mod:`gsik.stall`), holds the pose (as a refused step of the fast path does),
and holding is remembered, so a held target settles at its best reach instead
of jittering, and a held step costs nothing.

The common step (no balance, the full step's trial better at once) is one compiled call (:mod:`gsik.kernels.accept`
over :mod:`gsik.kernels.control`); this module keeps the rarer branches. Its inputs live in :mod:`gsik.control_inputs`.
"""

from __future__ import annotations

import math

import numpy as np

from gsik.acceptance import BETTER, SAME, WORSE, LevelState, anchored, compare
from gsik.balance import center_of_mass, com_jacobian, nearest_point_inside, shrink, signed_distance, support_polygon
from gsik.control_inputs import GROUND_TOLERANCE, Balance, ControlStats, FrameTask, Posture, frame_tasks, \
    structure, support  # noqa: F401  (gsik.control's names, as before the split)
from gsik.control_inputs import _ordered, row_weights, structure_of  # noqa: F401  (structure_of re-exported)
from gsik.kernels import compiled_entry
from gsik.kernels import accept as ak
from gsik.kernels import control as ck
from gsik.kernels import kinematics as kernels
from gsik.kernels import priority as priority_kernel
from gsik.kinematics import kinematic_model, topology
from gsik.priority import BOX_RELATIVE_TOLERANCE, BOX_TOLERANCE, RANK_TOLERANCE, posture_factor
from gsik.rotations import transform

#: A target lags while it is off by more than this many times its tolerance (1 mm, 0.01 rad at the defaults): with
#: ``settings.tracking_steps`` above 1 a ``Solver.step()`` then linearises again. Measured on bench_drag's studio
#: default (pins and the bundled prior, hands dragged 6 mm a frame round a circle): one linearisation a frame kept
#: both hands within 1 mm in 243 of 300 frames (the posture's move, flat only to first order, leaves them up to
#: 7 mm off), up to three in 300 (a third of the frames take two).
TRACKING_ERROR = 10.0
#: Newton steps of the target levels that may bring a posture move back onto them.
RESTORING_STEPS = 3
#: Largest adaptive damping (the fast path's too): a step refused at it holds the pose.
MAX_DAMPING = 1e6
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


class Controller:
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
    #: The last step's full step when the Python branches judged it, ``None`` when the compiled call committed it.
    _first: np.ndarray | None = None

    def __init__(self, skeleton, tasks, posture: Posture | None, balance: Balance | None, settings):
        self._sk = skeleton
        self._settings = settings
        if balance is not None and not balance.feet:
            balance = None  # no foot on the ground: nothing to stand on
        self._posture = posture
        n = skeleton.n_dofs
        # The posture's precision factored once (a learned prior's is a full matrix): each step only multiplies.
        self._posture_rows = ck.PostureRows(np.zeros(n), np.zeros((0, n)), np.ones(1)) if posture is None else \
            ck.PostureRows(np.array(posture.reference, dtype=float), np.ascontiguousarray(posture_factor(
                posture.precision)), np.ones(1))
        self.posture_gain = self._posture_rows.gain  # (1,) the share of the posture's step taken: 1 but in solve()
        self._lower, self._upper = np.array(skeleton.lower, dtype=float), np.array(skeleton.upper, dtype=float)
        self._tols = (RANK_TOLERANCE, BOX_TOLERANCE, BOX_RELATIVE_TOLERANCE)
        self._balance = balance
        self._root = skeleton.frame_of(skeleton.root)
        self._held = None  # (q, world_from_root, damping, ControlStats) of the last step that held the pose
        self._rest_damping = self._last_held = False  # start from the base damping; the last step held the pose
        self._layout = None  # (effector names, result names, task index of each) for results
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

    def retarget(self, tasks) -> None:
        """New target values for the same structure (``structure(...) == self.key``): no rebuild while dragging."""
        ordered = _ordered(tasks)
        self._target_weights = None
        self._retarget(np.array([t.position for t in ordered]).reshape(-1, 3),
                       np.array([t.rotation for t in ordered]).reshape(-1, 3, 3),
                       np.array([t.row_weight for t in ordered]).reshape(-1, 6))

    def retarget_targets(self, targets, orientation_weight: float) -> None:
        """:meth:`retarget` from ``{name: gsik.Target}`` (the same names and priorities as the tasks built for)."""
        ts = [targets[n] for n in self.names]
        weights = [(t.weight, t.uses_orientation) for t in ts]
        if weights == self._target_weights and orientation_weight == self._orientation_weight:
            row_w = self._row_w  # the same row weights: no array to build (a drag moves targets, not weights)
        else:
            row_w = np.array([row_weights(t, orientation_weight) for t in ts], dtype=float).reshape(-1, 6)
        self._retarget(  # a Target's position and rotation are float64: their bytes joined, the (m, 3), (m, 3, 3)
            np.frombuffer(b"".join([t.position.tobytes() for t in ts])).reshape(-1, 3),
            np.frombuffer(b"".join([t.rotation.tobytes() for t in ts])).reshape(-1, 3, 3), row_w)
        self._target_weights, self._orientation_weight = weights, orientation_weight

    def _retarget(self, tp: np.ndarray, tR: np.ndarray, row_w: np.ndarray) -> None:
        """Target positions (m, 3) [m], orientations (m, 3, 3) and row weights (m, 6), in task order."""
        same_w = _same(row_w, self._row_w)
        if same_w and _same(tp, self._tp) and _same(tR, self._tR):
            return  # the same targets again (a held drag): what the last steps learnt still holds
        self._tp[:], self._tR[:] = tp, tR  # in place: the kernels' inputs hold them
        if not same_w:
            self._row_w = row_w
            self._thresholds()
        self._cache.flags[ak.F_VALID], self._held = 0.0, None
        self._window.ring[:] = 0
        self._rest_damping = self._last_held  # a held pose's damping was learnt on the old targets: start afresh

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
                                         0.5 * self._tolerance, self._tolerance, TRACKING_ERROR * self._tolerance,
                                         packed_row,
                                         packed_weight, starts)
        self._work = ck.make_work(self._sk.n_frames, self._sk.n_dofs, len(self._tasks), int(starts[-1]), L,
                                  len(counts))
        self._entries = {}  # compiled entry points, made at first use for these inputs
        per_task = 0.5 * TIGHTEN_FRACTION ** 2 * (w[:, 0] * s.position_tolerance ** 2
                                                  + w[:, 3] * s.orientation_tolerance ** 2)
        floors = np.bincount(self._task_level, per_task, minlength=L + 1)
        if self._balance is not None:
            floors[self._balance_level] = 0.5 * (TIGHTEN_FRACTION * BALANCE_TOLERANCE) ** 2
        self._floors = floors
        self._near = floors[:-1] / TIGHTEN_FRACTION ** 2
        self._window = ak.make_window(np.sqrt(np.append(self._near, 0.0)))  # the posture's: its own size only
        self._cache = ak.make_cache(self._sk.n_dofs, len(self._tasks), L)  # the last accepted pose's levels

    def _call(self, kernel, *args):
        """``kernel(*args)`` through its compiled entry point (made once for these argument types)."""
        entry = self._entries.get(kernel)
        if entry is None:
            entry = self._entries[kernel] = compiled_entry(kernel, *args)
        return entry(*args)

    def errors(self, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position [m] and orientation [rad] error (m,) of each task (0 where a row is unused)."""
        self._task_errors(R, p)
        err = self._err.copy()
        err[0, self._row_w[:, 0] <= 0.0] = 0.0
        err[1, self._row_w[:, 3] <= 0.0] = 0.0
        return err[0], err[1]

    def report(self, effector_names: tuple[str, ...], R, p) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
        """``(names, position errors [m], orientation errors [rad])``: every effector (0 without a target),
        then the other targeted frames."""
        if self._layout is None or self._layout[0] != effector_names:
            names = effector_names + tuple(n for n in self.names if n not in effector_names)
            where = {n: k for k, n in enumerate(self.names)}
            self._layout = (effector_names, names, np.array([where.get(n, -1) for n in names], dtype=np.int64))
        _, names, index = self._layout
        out = np.empty((2, len(names)))
        self._call(ck.report_errors, R, p, self._tasks_in, index, self._e, self._err, self._M, out)
        return names, out[0], out[1]

    def _task_errors(self, R, p) -> None:
        self._call(kernels.effector_errors, R, p, self._tasks_in.frame, self._tp, self._tR, self._tasks_in.row_weight,
                   self._e, self._err, self._M)

    def _level_state(self, q, R, p) -> LevelState:
        """The levels at ``q`` (frames ``R``, ``p``), anchored at their own costs (:class:`~gsik.acceptance.LevelState`).

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
        if self._call(priority_kernel.prioritized_step, wk.rows, wk.errors, wk.weights,
                      self._tasks_in.starts[:levels + 1], wk.dampings[:levels], wk.lo, wk.hi, tols[0], tols[1],
                      tols[2], wk.dq) != priority_kernel.OK:
            raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
        return wk.dq.copy()

    # -- one step --------------------------------------------------------------
    def step(self, q: np.ndarray, W: np.ndarray, R: np.ndarray, p: np.ndarray, lam: np.ndarray) -> ControlStats:
        """One prioritised step from ``q`` (n_dofs,) [rad], in place on ``q``, ``R``, ``p`` and ``lam`` (1,).

        ``R``, ``p`` hold the world frames at ``q`` with the root pinned at ``W`` (4, 4). Without balance, the start
        state, the step, its trial and a better trial's commit are one compiled call
        (:func:`gsik.kernels.accept.control_step`)."""
        s = self._settings
        self._first = None
        if self._rest_damping:
            lam[0], self._rest_damping = s.damping, False
        damping = float(lam[0]) if s.adaptive_damping else s.damping
        if self._holds(q, W, damping):
            return self._held[3]  # the same step from the same pose: it would hold again
        if self._balance is None and s.adaptive_damping and self.compiled_step:
            self._call(ak.control_step, self._task_model, self._fk_model, self._tasks_in, self._posture_rows,
                       self._root, W, self._lower, self._upper, s.max_step, q, R, p, lam, damping, s.damping,
                       self._near, self._tols, self._floors, (float(s.settle_tolerance), DAMPING_FALL, DAMPING_FLOOR),
                       RESTORING_STEPS if self._posture is not None else 0, float(s.stall_tolerance), self._cache,
                       self._window, self._work)
            out = self._cache.out.tolist()
            if out[ak.R_STATUS] != priority_kernel.OK:
                raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
            if out[ak.R_COMMITTED]:
                return self._stats(q, W, lam, ak.committed_stats(self._cache, self._window, self._posture is not None,
                                                                 s.stall_tolerance))
            state0 = ak.cached_state(self._cache) if out[ak.R_FRESH] > 0.0 else ak.start_state(self._cache, out)
            first, judged = self._work.dq.copy(), None
            if out[ak.R_RESTORED]:  # the full step's trial and its restoring steps judged no better: only the verdict
                judged = ((ak.VERDICTS[int(out[ak.R_VERDICT])], 0), None, None, None, None)
                first = self._cache.dq0.copy()
        else:
            fresh = self._call(ak.is_fresh, self._cache, q, W)
            state0 = ak.cached_state(self._cache) if fresh else self._level_state(q, R, p)
            if not fresh:
                self._window.ring[:] = 0  # the pose changed from outside
            first, judged = self._first_trial(q, W, R, p, state0, damping), None
        self._first = first
        tries, ((verdict, decided), q2, R2, p2, state) = self._damped_trial(q, W, R, p, state0, first, judged)
        accepted = verdict == BETTER or not s.adaptive_damping
        if accepted:
            dq = q2 - q
            step_norm = math.sqrt(float(dq @ dq))
            q[:], R[:], p[:] = q2, R2, p2
            state = anchored(state, state0, decided if verdict == BETTER else 0)
            ak.store(self._cache, q, W, state)
        else:
            step_norm, state = 0.0, state0
        self._adapt_damping(lam, damping, verdict, accepted, tries)
        # Held: nothing would change, the largest damping's step is refused, or the steps only creep (gsik.stall).
        held = s.adaptive_damping and (verdict == SAME or (accepted and step_norm <= s.stall_tolerance)
                                       or (not accepted and damping >= MAX_DAMPING) or self._call(
                                           ak.creeps, self._window, state.met, self._posture is not None, state.costs))
        return self._stats(q, W, lam, ControlStats(accepted, held, state.converged, state.target_cost, step_norm,
                                                   state.lagging))

    def _stats(self, q, W, lam, stats: ControlStats) -> ControlStats:
        """``stats``; a held pose is kept until the targets change (a frame asked for anyway changes nothing)."""
        self._held = (q.copy(), W.copy(), lam[0], stats._replace(accepted=False, step_norm=0.0)) if stats.held else None
        self._last_held = stats.held
        return stats

    def _holds(self, q, W, damping) -> bool:
        """True if the last step held the pose ``q`` at ``W`` with this damping: a step now would do the same."""
        held = self._held
        return held is not None and held[2] == damping and _same(q, held[0]) and _same(W, held[1])

    def _damped_trial(self, q, W, R, p, state0: LevelState, dq: np.ndarray, judged) -> tuple[int, tuple]:
        """``(halvings made, trial)``: the prioritised step ``dq`` (n,) from ``q`` (its full trial in the work
        buffers, or already ``judged``), halved up to 3 times while its trial (:meth:`_judge`) is worse (with adaptive
        damping only); if it stays worse, the met levels' correction alone (:meth:`_correction`)."""
        scale = 1.0
        for tries in range(4):
            if tries:
                self._trial(q, dq, scale, W)
            trial = judged if tries == 0 and judged is not None else self._judge(q, W, state0)
            if trial[0][0] != WORSE or not self._settings.adaptive_damping:
                return tries, trial
            if tries == 0 and self._posture is not None:
                targets = self._targets_alone(q, W, R, p, state0)
                if targets is not None:
                    return 0, targets
            scale *= 0.5
        return tries, self._correction(q, W, R, p, state0) or trial

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
        return self._first if self._first is not None else (
            self._cache.dq0 if self._cache.out[ak.R_RESTORED] else self._work.dq)

    def _adapt_damping(self, lam: np.ndarray, damping: float, verdict: str, accepted: bool, tries: int) -> None:
        """Levenberg-Marquardt on ``lam`` (1,): lower it after a full step taken, raise it after a worse one."""
        s = self._settings
        if accepted and s.adaptive_damping:
            lam[0] = max(damping * DAMPING_FALL, s.damping * DAMPING_FLOOR) if tries == 0 else damping
        elif not accepted and verdict == WORSE:
            lam[0] = min(damping * 10.0, MAX_DAMPING)

    def _judge(self, q, W, state0: LevelState, upto: int | None = None):
        """``((verdict, deciding level), q, R, p, level state)`` of the trial in the work buffers
        (:func:`~gsik.acceptance.compare`, on the levels above ``upto`` only if given). When a lower level's move
        breaks a met higher level (the null space is only flat to first order), up to :data:`RESTORING_STEPS`
        restoring steps of the target levels from the trial pose bring it back onto them, and that pose is judged
        instead."""
        settle = self._settings.settle_tolerance
        first = self._trial_state()
        verdict = compare(state0, first[3], settle, self._floors, upto)
        if verdict[0] != WORSE or self._posture is None or upto is not None:
            return (verdict,) + first
        q3, R3, p3, state3 = first
        for _ in range(RESTORING_STEPS):
            self._linearise(q3, R3, p3, state3.error)
            self._trial(q3, self._solve(q, q3, len(self._levels)), 1.0, W)
            q3, R3, p3, state3 = self._trial_state()
            restored = compare(state0, state3, settle, self._floors)
            if restored[0] != WORSE:
                return restored, q3, R3, p3, state3
        return (verdict,) + first

    def target_cost(self, R, p) -> float:
        """Weighted squared error ``0.5 e^T W e`` of every target at frames ``R``, ``p``."""
        self._task_errors(R, p)
        return float(0.5 * (self._row_w * self._e.reshape(-1, 6) ** 2).sum())

    def converged(self, R, p) -> bool:
        """True if every target is within the position and orientation tolerances."""
        pos, ori = self.errors(R, p)
        s = self._settings
        return bool(np.all(pos <= s.position_tolerance) and np.all(ori <= s.orientation_tolerance))


def _same(a: np.ndarray, b: np.ndarray | None) -> bool:
    """True if ``b`` holds the very values of ``a`` (bit for bit: a cheaper test than ``np.array_equal``)."""
    return a is b or (b is not None and a.shape == b.shape and a.tobytes() == b.tobytes())
