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
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.acceptance import BETTER, SAME, WORSE, LevelState, anchored, compare
from gsik.kernels import kinematics as kernels
from gsik.errors import SolverError
from gsik.balance import MassModel, center_of_mass, com_jacobian, nearest_point_inside, shrink, signed_distance, \
    support_polygon
from gsik.kinematics import kinematic_model, topology
from gsik.priority import Level, posture_factor, prioritized_step
from gsik.rotations import transform
from gsik.stall import StallDetector, unmet_levels

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


class FrameTask(NamedTuple):
    """A target on one frame, packed.

    Attributes:
        name: The joint or site name.
        frame: Its frame index.
        position: (3,) world target position [m].
        rotation: (3, 3) world target orientation.
        row_weight: (6,) weights of the 3 position and 3 orientation rows (0: unused).
        priority: Level; 0 is the most important.
    """

    name: str
    frame: int
    position: np.ndarray
    rotation: np.ndarray
    row_weight: np.ndarray
    priority: int


class Balance(NamedTuple):
    """What balance needs: the mass model and the feet that may carry the body.

    Attributes:
        mass: The :class:`~gsik.balance.MassModel`.
        feet: (k,) frame index of each foot that may support the body.
        soles: k sole polygons (c, 2) [m] in each foot frame's x-y plane.
    """

    mass: MassModel
    feet: tuple[int, ...]
    soles: tuple[np.ndarray, ...]


class Posture(NamedTuple):
    """The preferred pose ``reference`` (n_dofs,) [rad] and its precision: weights (n_dofs,) or (n_dofs, n_dofs)."""

    reference: np.ndarray
    precision: np.ndarray


class ControlStats(NamedTuple):
    """What a controller step did.

    Attributes:
        accepted: The step was kept.
        held: The pose is at rest: no level would change by more than the settle tolerance, or even the
            largest damping's step is refused (the studio's frame loop may idle).
        converged: Every target is within the position and orientation tolerances.
        cost: Weighted squared error ``0.5 e^T W e`` of the targets, all levels.
        step_norm: Size of the change of ``q`` [rad].
    """

    accepted: bool
    held: bool
    converged: bool
    cost: float
    step_norm: float


class Controller:
    """Prioritised IK steps for one skeleton seen from one root.

    Args:
        skeleton: The :class:`gsik.Skeleton` (its ``root`` the IK root).
        tasks: The targets, each a :class:`FrameTask`.
        posture: A :class:`Posture`, or ``None``.
        balance: A :class:`Balance`, or ``None``.
        settings: The :class:`gsik.SolverSettings`.
    """

    def __init__(self, skeleton, tasks, posture: Posture | None, balance: Balance | None, settings):
        self._sk = skeleton
        self._settings = settings
        if balance is not None and not balance.feet:
            balance = None  # no foot on the ground: nothing to stand on
        self._posture = posture
        # The posture's precision factored once (a learned prior's is a full matrix): each step only multiplies.
        self._posture_factor = None if posture is None else posture_factor(posture.precision)
        self._posture_ones = np.ones(skeleton.n_dofs)
        self._balance = balance
        self._root = skeleton.frame_of(skeleton.root)
        self._state_cache = None  # (q, world_from_root, LevelState) of the last accepted pose
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
        self._J = np.zeros((6 * m, skeleton.n_dofs))
        self._e = np.zeros(6 * m)
        self._err = np.zeros((2, m))
        self._row_w = None  # (m, 6) set with what depends on it by retarget
        self._M = np.zeros((3, 3))
        if balance is not None:
            bodies = [skeleton.frame_names[f] for f in balance.mass.body_frame]
            self._mass_kinematics = kinematic_model(skeleton, topology(skeleton, skeleton.root, bodies))
            self._Jm = np.zeros((6 * len(balance.mass.mass), skeleton.n_dofs))
        self.retarget(tasks)

    def retarget(self, tasks) -> None:
        """New target values for the same structure (``structure(...) == self.key``): no rebuild while dragging."""
        ordered = _ordered(tasks)
        tp = np.array([t.position for t in ordered]).reshape(-1, 3)
        tR = np.array([t.rotation for t in ordered]).reshape(-1, 3, 3)
        row_w = np.array([t.row_weight for t in ordered]).reshape(-1, 6)
        if self._row_w is not None and np.array_equal(tp, self._tp) and np.array_equal(tR, self._tR) \
                and np.array_equal(row_w, self._row_w):
            return  # the same targets again (a held drag): what the last steps learnt still holds
        self._tp, self._tR = tp, tR
        if not np.array_equal(row_w, self._row_w):
            self._row_w = row_w
            self._thresholds()
        self._state_cache = self._held = None
        self._stall.reset()
        self._rest_damping = self._last_held  # a held pose's damping was learnt on the old targets: start afresh

    def _thresholds(self) -> None:
        """What depends on the row weights only: each level's rows, the error bounds (2, m) of the band and of
        convergence (inf where a row is unused), and per level (L + 1,) the cost of errors at
        :data:`TIGHTEN_FRACTION` of the tolerances (``_floors``) and at the tolerances (``_near``)."""
        s, w = self._settings, self._row_w
        used = np.stack([w[:, 0] > 0.0, w[:, 3] > 0.0])
        tolerance = np.array([[s.position_tolerance], [s.orientation_tolerance]])
        self._tolerance = np.where(used, tolerance, np.inf)
        self._band = 0.5 * self._tolerance
        L, m = len(self._levels), len(self._tasks)
        rows = np.repeat(self._task_level, 6)
        self._level_rows = [np.flatnonzero((rows == k) & (w.reshape(-1) > 0.0)) for k in range(L)]
        self._level_weights = [w.reshape(-1)[r] for r in self._level_rows]
        # Sums per level as one product each: 0.5 w over each level's error rows (and a last row over all of
        # them: the targets' cost), and its tasks' two error columns.
        self._cost_rows = np.zeros((L + 2, 6 * m))
        self._cost_rows[rows, np.arange(6 * m)] = 0.5 * w.reshape(-1)
        self._cost_rows[-1] = 0.5 * w.reshape(-1)
        self._band_rows = np.zeros((L + 1, 2 * m))
        self._band_rows[np.tile(self._task_level, 2), np.arange(2 * m)] = 1.0
        per_task = 0.5 * TIGHTEN_FRACTION ** 2 * (w[:, 0] * s.position_tolerance ** 2
                                                  + w[:, 3] * s.orientation_tolerance ** 2)
        floors = np.bincount(self._task_level, per_task, minlength=len(self._levels) + 1)
        if self._balance is not None:
            floors[self._balance_level] = 0.5 * (TIGHTEN_FRACTION * BALANCE_TOLERANCE) ** 2
        self._floors = floors
        self._near = floors[:-1] / TIGHTEN_FRACTION ** 2
        self._stall = StallDetector(np.sqrt(np.append(self._near, 0.0)))  # the posture's: its own size only

    # -- evaluation ----------------------------------------------------------
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
        self._task_errors(R, p)
        padded = np.zeros((2, len(self.names) + 1))  # a last column of zeros for the effectors without a target
        padded[:, :-1] = np.where(self._tolerance < np.inf, self._err, 0.0)
        out = padded[:, index]
        return names, out[0], out[1]

    def _task_errors(self, R, p) -> None:
        kernels.effector_errors(R, p, self._topo.effector_frame, self._tp, self._tR, self._row_w, self._e, self._err,
                                self._M)

    def _level_state(self, q, R, p) -> LevelState:
        """The levels at ``q`` (frames ``R``, ``p``), anchored at their own costs (:class:`~gsik.acceptance.LevelState`).

        A target level is met when all its targets are within half the
        tolerances, balance when the centre of mass is inside the support
        polygon's margin (within :data:`BALANCE_TOLERANCE`); the posture never is (it always compares by cost).
        """
        self._task_errors(R, p)
        e, err = self._e.copy(), self._err
        sums = self._cost_rows @ (e * e)
        costs, target_cost = sums[:-1], float(sums[-1])
        met = self._band_rows @ (err > self._band).ravel() == 0.0
        met[-1] = False
        if self._balance is not None:
            goal, com = self._support_goal(R, p)
            outside = max(signed_distance(goal, com[:2]), 0.0)
            costs[self._balance_level] = 0.5 * outside ** 2
            met[self._balance_level] = outside <= BALANCE_TOLERANCE
        if self._posture is not None:
            g = q - self._posture.reference
            P = self._posture.precision
            costs[-1] = 0.5 * float(g @ (P * g if P.ndim == 1 else P @ g))
        converged = not (err > self._tolerance).any()
        return LevelState(costs, met, costs, converged, target_cost, e)

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
    def levels(self, q, R, p, error: np.ndarray | None = None) -> list[Level]:
        """The linearised levels at ``q`` (frames ``R``, ``p``), in priority order, the posture last;
        ``error`` (6 m,) the targets' errors there if known (:attr:`LevelState.error`)."""
        if error is None:
            self._task_errors(R, p)
            error = self._e
        kernels.jacobian(self._task_model, R, p, self._J)
        out = [self._balance_level_rows(R, p) if k == self._balance_level else Level(self._J[rows], error[rows], w)
               for k, (rows, w) in enumerate(zip(self._level_rows, self._level_weights))]
        if self._posture is not None:
            L = self._posture_factor  # factor_level's level, with its arrays made once
            out.append(Level(L, L @ (self._posture.reference - q), self._posture_ones))
        return out

    def _balance_level_rows(self, R, p) -> Level:
        goal, com = self._support_goal(R, p)
        n = self._sk.n_dofs
        if signed_distance(goal, com[:2]) <= -BALANCE_BAND:
            return Level(np.zeros((0, n)), np.zeros(0), np.zeros(0))
        kernels.jacobian(self._mass_kinematics, R, p, self._Jm)
        Jc = com_jacobian(self._balance.mass, R, self._Jm)
        return Level(Jc[:2], nearest_point_inside(goal, com[:2]) - com[:2], np.ones(2))

    # -- one step --------------------------------------------------------------
    def step(self, q: np.ndarray, W: np.ndarray, R: np.ndarray, p: np.ndarray, lam: np.ndarray) -> ControlStats:
        """One prioritised step from ``q`` (n_dofs,) [rad], in place on ``q``, ``R``, ``p`` and ``lam`` (1,).

        ``R``, ``p`` hold the world frames at ``q`` with the root pinned at ``W`` (4, 4).
        """
        s = self._settings
        if self._rest_damping:
            lam[0], self._rest_damping = s.damping, False
        damping = lam[0] if s.adaptive_damping else s.damping
        if self._holds(q, W, damping):
            return self._held[3]  # the same step from the same pose: it would hold again
        cached = self._state_cache
        fresh = cached is not None and np.array_equal(cached[0], q) and np.array_equal(cached[1], W)
        state0 = cached[2] if fresh else anchored(self._level_state(q, R, p))
        tries, ((verdict, decided), q2, R2, p2, state) = self._damped_trial(q, W, R, p, state0, damping)
        accepted = verdict == BETTER or not s.adaptive_damping
        if accepted:
            step_norm = float(np.linalg.norm(q2 - q))
            q[:], R[:], p[:] = q2, R2, p2
            state = anchored(state, state0, decided if verdict == BETTER else 0)
            self._state_cache = (q.copy(), W.copy(), state)
        else:
            step_norm, state = 0.0, state0
        self._adapt_damping(lam, damping, verdict, accepted, tries)
        # Held: nothing would change, or even the largest damping's step is refused (the fast path's stall), or
        # the steps only creep (gsik.stall).
        if not fresh:
            self._stall.reset()  # the pose changed from outside
        held = s.adaptive_damping and (verdict == SAME or (accepted and step_norm <= s.stall_tolerance)
                                       or (not accepted and damping >= MAX_DAMPING)
                                       or self._stall.creeps(unmet_levels(state.met, self._posture is not None), state.costs))
        stats = ControlStats(accepted, held, state.converged, state.target_cost, step_norm)
        # A held pose is kept until the targets change: the same step again would hold again, and a creep that
        # was taken stops (a frame asked for anyway changes nothing).
        self._held = (q.copy(), W.copy(), lam[0], stats._replace(accepted=False, step_norm=0.0)) if held else None
        self._last_held = held
        return stats

    def _holds(self, q, W, damping) -> bool:
        """True if the last step held the pose ``q`` at ``W`` with this damping: a step now would do the same."""
        held = self._held
        return held is not None and held[2] == damping and np.array_equal(held[0], q) and np.array_equal(held[1], W)

    def _damped_trial(self, q, W, R, p, state0: LevelState, damping) -> tuple[int, tuple]:
        """``(halvings made, trial)``: the prioritised step from ``q``, halved up to 3 times while its
        trial (:meth:`_trial`) is worse (with adaptive damping only); if it stays worse, the met levels'
        correction alone (:meth:`_correction`)."""
        dampings = self._dampings(damping, state0.costs)
        levels = self.levels(q, R, p, state0.error)
        box = self._box(q, q)
        dq = prioritized_step(levels, *box, dampings)
        for tries in range(4):
            trial = self._trial(q, q + dq, W, state0, dampings)
            if trial[0][0] != WORSE or not self._settings.adaptive_damping:
                return tries, trial
            if tries == 0 and self._posture is not None:
                targets = self._targets_alone(q, W, levels, box, state0, dampings)
                if targets is not None:
                    return 0, targets
            dq = 0.5 * dq
        return tries, self._correction(q, W, levels, box, state0, dampings) or trial

    def _targets_alone(self, q, W, levels, box, state0: LevelState, dampings) -> tuple | None:
        """The trial of the target levels' step alone (the posture's left out), if it is better for them, else
        ``None``. A full step is worse when the posture's move, flat only to first order, costs a target level more
        than the level's own step gains (a target at a fold of its reach: a yawed head on a straight spine); halving
        it and raising the damping would then damp the target levels' own step too, and they would creep."""
        dq = prioritized_step(levels[:-1], *box, dampings[:-1])
        trial = self._trial(q, q + dq, W, state0, dampings, upto=len(self._levels))
        return trial if trial[0][0] == BETTER else None

    def _correction(self, q, W, levels, box, state0: LevelState, dampings) -> tuple | None:
        """The trial of the step of the met levels above the first unmet one alone, if it tightens them (a lower
        level may lose what their correction costs it: strict priority), else ``None``. A lower level's move
        leaves them off by its second order; when that move is refused, this still closes them in."""
        k = int(np.argmin(state0.met))  # the leading met levels (the posture, last, never is)
        if k == 0 or k == len(self._levels) or not np.any(state0.costs[:k] > self._floors[:k]):
            return None
        dq = prioritized_step(levels[:k], *box, dampings[:k])
        trial = self._trial(q, q + dq, W, state0, dampings, upto=k)
        return trial if trial[0][0] == BETTER else None

    def _adapt_damping(self, lam: np.ndarray, damping: float, verdict: str, accepted: bool, tries: int) -> None:
        """Levenberg-Marquardt on ``lam`` (1,): lower it after a full step taken, raise it after a worse one."""
        s = self._settings
        if accepted and s.adaptive_damping:
            lam[0] = max(damping * DAMPING_FALL, s.damping * DAMPING_FLOOR) if tries == 0 else damping
        elif not accepted and verdict == WORSE:
            lam[0] = min(damping * 10.0, MAX_DAMPING)

    def _dampings(self, lam: float, costs: np.ndarray) -> np.ndarray:
        """Damping per level, given its ``costs`` (L + 1,): the base one for a level within its tolerances (its
        linear model is good there: a small error is closed at once, whatever a lower level's trouble raised
        ``lam`` to), ``lam`` for the others, and for the posture the base one raised as ``lam`` is (so a
        posture move refused for its second-order cost shrinks)."""
        base = self._settings.damping
        d = np.where(costs[:-1] <= self._near, min(base, lam), lam)
        if self._posture is not None:
            d = np.append(d, base * max(1.0, lam / base))
        return d

    def _box(self, q: np.ndarray, q_from: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Bounds ``lo <= dq <= hi`` (n,) of a step from ``q_from``: the limits, and the step limit counted from ``q``."""
        s, sk = self._settings, self._sk
        lo, hi = sk.lower - q_from, sk.upper - q_from
        if s.max_step > 0.0:
            lo = np.maximum(lo, q - q_from - s.max_step)
            hi = np.minimum(hi, q - q_from + s.max_step)
        return np.minimum(lo, 0.0), np.maximum(hi, 0.0)

    def _trial(self, q, q_try, W, state0: LevelState, dampings, upto: int | None = None):
        """``((verdict, deciding level), q, R, p, level state)`` of a trial pose (:func:`~gsik.acceptance.compare`,
        on the levels above ``upto`` only if given). When a lower level's move breaks a met higher level (the
        null space is only flat to first order), up to :data:`RESTORING_STEPS` restoring steps of the target
        levels from the trial pose bring it back onto them, and that pose is judged instead."""
        sk, settle = self._sk, self._settings.settle_tolerance
        R2, p2 = np.empty((sk.n_frames, 3, 3)), np.empty((sk.n_frames, 3))
        q2 = np.clip(q_try, sk.lower, sk.upper)
        self._frames(q2, W, R2, p2)
        state = self._level_state(q2, R2, p2)
        verdict = compare(state0, state, settle, self._floors, upto)
        if verdict[0] != WORSE or self._posture is None or upto is not None:
            return verdict, q2, R2, p2, state
        q3, R3, p3 = q2.copy(), R2.copy(), p2.copy()
        for _ in range(RESTORING_STEPS):
            levels = self.levels(q3, R3, p3)[:-1]
            q3 = np.clip(q3 + prioritized_step(levels, *self._box(q, q3), dampings[:-1]), sk.lower, sk.upper)
            self._frames(q3, W, R3, p3)
            state3 = self._level_state(q3, R3, p3)
            restored = compare(state0, state3, settle, self._floors)
            if restored[0] != WORSE:
                return restored, q3, R3, p3, state3
        return verdict, q2, R2, p2, state

    def target_cost(self, R, p) -> float:
        """Weighted squared error ``0.5 e^T W e`` of every target at frames ``R``, ``p``."""
        self._task_errors(R, p)
        return float(0.5 * (self._row_w * self._e.reshape(-1, 6) ** 2).sum())

    def converged(self, R, p) -> bool:
        """True if every target is within the position and orientation tolerances."""
        pos, ori = self.errors(R, p)
        s = self._settings
        return bool(np.all(pos <= s.position_tolerance) and np.all(ori <= s.orientation_tolerance))

    def _frames(self, q, W, R, p) -> None:
        kernels.forward_kinematics(self._fk_model, q, self._root, W, R, p)


def _ordered(tasks) -> list[FrameTask]:
    """Tasks by priority, then name: one order for building and retargeting."""
    return sorted(tasks, key=lambda t: (t.priority, t.name))


def structure(skeleton, tasks, posture, balance, settings) -> tuple:
    """What a :class:`Controller` is built for, apart from the target values: equal keys can retarget."""
    feet = None if balance is None else balance.feet
    return (skeleton.root, tuple((t.name, t.priority) for t in _ordered(tasks)), id(posture), feet, id(settings))


def frame_tasks(skeleton, targets, orientation_weight: float) -> list[FrameTask]:
    """The :class:`FrameTask` of each ``{name: gsik.Target}``."""
    tasks = []
    for name, t in targets.items():
        wp = t.weight
        wo = wp * orientation_weight if t.uses_orientation else 0.0
        w = np.array((wp, wp, wp, wo, wo, wo), dtype=float)
        tasks.append(FrameTask(name, skeleton.frame_of(name), t.position, t.rotation, w, t.priority))
    return tasks


#: A foot whose target is within this height [m] of the standing foot is on the ground too.
GROUND_TOLERANCE = 0.01


def support(skeleton, targets, p: np.ndarray) -> Balance:
    """The :class:`Balance` of ``skeleton`` seen from its root: the root foot, and every other foot with a
    sole whose target is on the ground (the root foot's height); ``p`` (n_frames, 3) the world positions [m]."""
    if skeleton.total_mass <= 0.0:
        raise SolverError(f"balance needs segment masses; skeleton {skeleton.name!r} gives none "
                          "(see skeletons/README.md: segments' mass)")
    ground = p[skeleton.frame_of(skeleton.root)][2] if skeleton.root in skeleton.soles else 0.0
    feet = [n for n in skeleton.soles if n == skeleton.root
            or (n in targets and abs(targets[n].position[2] - ground) <= GROUND_TOLERANCE)]
    return Balance(skeleton.mass_model, tuple(skeleton.frame_of(n) for n in feet),
                   tuple(skeleton.soles[n] for n in feet))
