"""How :meth:`gsik.solver.Solver.solve` spends its attempts: restarts, continuation, the settled best reach,
and which attempt is best. A mixin of :class:`~gsik.solver.Solver`, which owns the state it works on."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from gsik import control, kernels
from gsik.kernels import O_COST, O_FINITE, O_ITERATIONS, O_RESIDUAL, O_STATUS, O_STEP_NORM, O_SWEEPS
from gsik.kernels import solve as solve_kernels
from gsik.result import _STATUSES, SolveResult, Status
from gsik.rotations import matrix_from_rotvec, rotvec_from_matrix
from gsik.stall import PostureSettle
from gsik.targets import Target

#: Attempts ending with weighted errors this close (relative) found the same best reach ...
SETTLED_AGREEMENT = 1e-3
#: ... and this many further attempts finding it again settle it, when no pose can meet the targets
#: (:meth:`AttemptPolicy._out_of_reach`): no attempt can converge, so the attempts only look for a lower best
#: reach. Measured on 40 such target sets (a hand or the head 2.5-4 m from the pelvis): 1 makes 5.8 attempts
#: instead of 19.6, the best reach's weighted error within 1% of the full search's in 35 of 40 (at most 9%
#: above); 2 makes 9.4 attempts, within 1% in 39 (2.3% above). Targets that may be reachable never settle by
#: agreement: eight random restarts ending in one local minimum 16 mm off did not mean that the ninth would
#: (bench_reach's pose 438 converges at the 13th attempt).
SETTLED_REPEATS = 1
#: Row weights' mask of a positions-only phase: the orientation rows off.
_POSITION_ROWS = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])


class AttemptPolicy:
    """:meth:`solve` and its attempts, for :class:`~gsik.solver.Solver`."""

    #: ``(controller, angles' bytes, posture gain, contraction)``: where the last prioritised attempt with a posture
    #: ended, the share of the posture's step it had learnt and its steps' last contraction
    #: (:class:`~gsik.stall.PostureSettle`).
    _posture_gain: tuple = (None, b"", 1.0, 0.0)
    #: The last prioritised attempt ended with a step (the pose is the one it left), not a return to a pose.
    _stepped: bool = False
    #: The attempt under way is a warm solve's first (:meth:`_warm_start`): its posture settle test is the warm one.
    _warm_attempt: bool = False

    def solve(self, targets: Mapping[str, Target | None] | None = None, q0=None) -> SolveResult:
        """Solve to convergence (or best reach) from ``q0`` (default: the current angles).

        Levenberg-Marquardt over PGS steps (:func:`gsik.kernels.step.solve`). If
        that does not converge, up to ``settings.restarts`` more attempts:
        first a continuation (the targets approached in stages from the
        current effector poses), then random restarts inside the limits.
        The best attempt (lowest weighted error) is kept and becomes the
        solver's state. With priorities, posture or balance each attempt runs
        prioritised steps until the pose holds (:mod:`gsik.control`),
        attempts are compared level by level, and the first further attempt
        starts from the posture; a converged attempt whose posture is not met
        is compared with one from the posture too, as the targets may be met
        on another branch nearer to it. With a posture below one level of
        targets (no priorities, balance or targets off the effectors) each
        attempt meets the targets on the single-level path first and then
        settles the posture; when the posture is the start, no attempt
        repeats the first from it (the first further one is a continuation).
        Each attempt (:func:`gsik.kernels.solve.solve`, or prioritised steps)
        meets the positions first when an orientation is far off
        (``positions_first``). Without priorities, posture or balance, and
        when no pose can meet the targets, the attempts stop early once the
        best reach is settled (:data:`SETTLED_REPEATS` attempts end where the
        best one did, within :data:`SETTLED_AGREEMENT`). A solve that starts from the best reach a
        previous solve settled on, with the same targets (priorities
        included), posture, balance and settings, returns it at once. The
        result counts the linearisations (``iterations``) and sweeps of all
        attempts.
        """
        if targets is not None:
            self.set_targets(targets)
        if q0 is not None:
            self.set_q(q0)
        if self._moved:
            self._make_moved_targets()  # before a continuation stages other values in the packed rows
        if self._is_controlled and not self._balance:
            self._make_controller(rows=True)  # the rows hold the targets' values now: gathered, as a step's
        self._stepped = False
        if self._settled is not None and self._settled[0] == self._reach_key():
            return self._solve_result(self._settled[1], 1, _status(self._settled[1]))  # nothing can do better: no work
        first = None
        if not self._is_controlled:
            first = self._plain_first_attempt()
            if type(first) is SolveResult:
                return first
        stats, attempts = self._attempts(first)
        self._ws.x.fill(0.0)
        self._ws.lam[0] = self._settings.damping
        status = _status(stats)
        self._remember_settled(stats, status)
        # What the next solve may start from warm: this one's pose under this posture, if it converged.
        self._warm = (self._q.tobytes(), self._posture) if status is Status.CONVERGED else None
        return self._solve_result(stats, attempts, status)

    def _refuse_non_finite(self, before: np.ndarray | None, stats: np.ndarray) -> None:
        """Undo a step or attempt that left a non-finite angle or error (``stats[O_FINITE]`` 0; status
        :attr:`Status.REFUSED`): back to the angles ``before`` (None: the kernel left them), so the solver is
        never poisoned and the pose stays the last finite one."""
        if before is not None:
            self._q[:] = before
        self._ws.x[:] = 0.0
        self._ws.lam[0] = self._settings.damping
        self._refresh_frames()
        frames = self._topo.effector_frame
        tp, tR, row_w = self._packed
        err = self._ws.err  # the restored pose's errors, where a target asks for them (inf if it overflows)
        with np.errstate(over="ignore", invalid="ignore"):
            err[0] = np.where(row_w[:, 0] > 0, np.linalg.norm(tp - self._ws.p[frames], axis=1), 0.0)
            cos = (np.einsum("kij,kij->k", tR, self._ws.R[frames]) - 1.0) * 0.5
            err[1] = np.where(row_w[:, 3] > 0, np.arccos(np.clip(cos, -1.0, 1.0)), 0.0)
        stats[O_STATUS] = Status.REFUSED
        stats[O_COST] = stats[O_RESIDUAL] = np.inf
        stats[O_STEP_NORM] = 0.0

    def _solve_result(self, stats: np.ndarray, attempts: int, status: Status) -> SolveResult:
        """The result of a solve whose best attempt's statistics are ``stats`` (its ``status``: :func:`_status`)."""
        if self._is_controlled:  # _stepped: the pose is where the last attempt's last step left it (its errors hold)
            values = stats.tolist()  # Python floats: cheaper to read than NumPy scalars
            return self._control_result(status, int(values[O_ITERATIONS]), values[O_COST], values[O_STEP_NORM],
                                        attempts, self._control_report(self._stepped))
        return self._result(stats, O_COST, attempts)

    def _plain_first_attempt(self) -> SolveResult | tuple[np.ndarray, np.ndarray]:
        """A single-level solve's first attempt from the current angles, in one compiled call that returns its
        statistics (:func:`gsik.kernels.plain.solve_plain`). Converged: the solve's result, the state left as
        :meth:`solve` leaves it. Else ``(its start (n_dofs,) [rad], a copy of its statistics)`` for
        :meth:`_attempts` to go on from (a refused attempt already undone, as :meth:`_kernel_solve` does)."""
        start = self._q.copy()
        run = self._plain or self._plain_inputs()
        finite, status, iterations, sweeps, cost, step_norm = run[1](run[2], self._settings.max_iterations, True)
        if finite and status == kernels.CONVERGED:
            self._settled = None
            self._warm = (self._q.tobytes(), self._posture)
            return self._new_result(status, iterations, sweeps, cost, step_norm, 1)
        stats = self._ws.stats
        if not finite:
            self._refuse_non_finite(np.clip(start, self._skeleton.lower, self._skeleton.upper), stats)
        return start, stats.copy()

    def _attempts(self, first: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, int]:
        """``(statistics of the best attempt, attempts made)``: the first attempt from the current angles (or
        ``first``, ``(its start, its statistics)``, already made), then the further ones the settings and its
        outcome call for; the best one is left as the state."""
        restarts = self._settings.restarts > 0
        self._work_done = [0, 0]
        if first is None:
            start = self._q.copy()
            warm = self._warm_attempt = self._warm_start(start)
            try:
                stats = self._solve_from(start)
            finally:
                self._warm_attempt = False
        else:
            start, stats = first[0], self._count(first[1])
            warm = False  # a single-level first attempt: no posture, none from it to compare with
        attempts = 1
        if _status(stats) is not Status.CONVERGED and restarts:
            stats, attempts = self._restart(start, stats)
        elif restarts and self._posture is not None and not warm \
                and self._attempt_rank(stats)[-1] > 0.0 and not self._starts_at_posture(start):
            stats, attempts = self._posture_attempt(stats)
        stats[O_ITERATIONS], stats[O_SWEEPS] = self._work_done
        return stats, attempts

    def _warm_start(self, start: np.ndarray) -> bool:
        """True if ``start`` (n_dofs,) [rad] is the pose the last solve converged to, under the same posture: it
        chose that pose's branch over the posture's then, and a converged attempt from it needs no second one from
        the posture (a drag's solve per frame: one attempt, not two)."""
        warm = self._warm
        return warm is not None and warm[1] is self._posture and warm[0] == start.tobytes()

    def _remember_settled(self, stats: np.ndarray, status: Status) -> None:
        """Keep a best reach (a stalled solve, ``status`` that of ``stats``) so that the same solve again from it does
        no work."""
        self._settled = None
        if status is Status.STALLED:
            settled = stats.copy()
            settled[O_ITERATIONS] = settled[O_SWEEPS] = 0
            self._settled = (self._reach_key(), settled)

    def _reach_key(self) -> tuple:
        """What a solve's outcome depends on: settings, root and its pose, targets (with their priorities),
        posture, balance, start angles."""
        posture = None if self._posture is None else (self._posture.reference.tobytes(),
                                                      self._posture.precision.tobytes())
        return (self._settings, self._topo.root_frame, self._W.tobytes(), tuple(self._targets.items()), posture,
                self._balance, self._q.tobytes())

    def _restart(self, start: np.ndarray, stats: np.ndarray) -> tuple[np.ndarray, int]:
        """Further attempts after a failed first one; leaves the best attempt as the state."""
        best = (self._attempt_rank(stats), self._q.copy(), stats)
        rng = np.random.default_rng(self._settings.seed)
        attempts = 1
        repeats = 0
        # Agreement settles only targets no pose meets; others may still converge: every restart is made.
        settle_after = SETTLED_REPEATS if self._out_of_reach() else self._settings.restarts + 1
        while _status(stats) is not Status.CONVERGED and attempts <= self._settings.restarts:
            stats = self._further_attempt(attempts, start, rng, best[1])
            attempts += 1
            repeats += self._repeats_best(stats, best[2])
            rank = self._attempt_rank(stats)
            if _status(stats) is Status.CONVERGED or rank < best[0]:
                best = (rank, self._q.copy(), stats)
            if repeats >= settle_after:
                break  # attempts from other starts keep finding the same best reach: the best there is to find
        if best[2] is not stats:
            # An earlier attempt was best: make it the state again (frames and errors included).
            self._solve_from(best[1], iterations=0)
        return best[2], attempts

    def _out_of_reach(self) -> bool:
        """True if no pose meets the targets: two targeted frames (or one and the pinned root) are farther apart
        than the bones between them reach (:attr:`~gsik.Skeleton.chain_length`), by more than twice the
        position tolerance."""
        sk = self._skeleton
        aimed = [(sk.frame_of(n), t.position) for n, t in self._targets.items() if t.weight > 0.0]
        frames = np.array([self._topo.root_frame] + [f for f, _ in aimed])
        points = np.array([self._W[:3, 3]] + [p for _, p in aimed])
        apart = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=2)
        return bool(np.any(apart - sk.chain_length[np.ix_(frames, frames)] > 2.0 * self._settings.position_tolerance))

    def _further_attempt(self, attempts: int, start: np.ndarray, rng: np.random.Generator,
                         best_q: np.ndarray) -> np.ndarray:
        """Attempt ``attempts + 1``: from the posture or by continuation first, then from the best pose so far
        ``best_q`` (n_dofs,) [rad] with the DOFs it holds on a limit mirrored, then random restarts."""
        if attempts == 1 and self._posture is not None and not self._starts_at_posture(start):
            return self._solve_from(self._posture.reference)  # the pose the artist prefers: a natural start
        if attempts == 1:
            return self._solve_by_continuation(start)
        sk = self._skeleton
        held = (best_q <= sk.lower) | (best_q >= sk.upper)
        if attempts == 2 and held.any():
            # Descent can end a few mm off with a joint held on its limits, the target's pose lying on the far
            # side of their range (measured: the one pose of bench_reach's 1000 no restart reached ends 3.7 mm
            # off with the right shoulder's x and z on a limit each, the target's near the other ends). Start
            # again with those DOFs mirrored in their range, the rest where they meet their targets.
            return self._solve_from(np.where(held, sk.lower + sk.upper - best_q, best_q))
        # Random restarts: ever bolder blends of the start with a random pose within the limits.
        alpha = min(1.0, 0.25 * attempts)
        return self._solve_from(start + alpha * (rng.uniform(sk.lower, sk.upper) - start))

    def _starts_at_posture(self, start: np.ndarray) -> bool:
        """True if an attempt from the posture would repeat the first one, from ``start`` (n_dofs,) [rad]: the
        posture is ``start`` and the attempts reach first (:meth:`_reaches_first`), which is deterministic."""
        return self._reaches_first() and np.array_equal(self._posture.reference, start)

    def _repeats_best(self, stats: np.ndarray, best: np.ndarray) -> bool:
        """True if an unconverged attempt ended where the best one did (``best`` before this attempt), within
        :data:`SETTLED_AGREEMENT`; never with priorities, posture or balance."""
        agrees = (not self._is_controlled
                  and abs(stats[O_COST] - best[O_COST]) <= SETTLED_AGREEMENT * best[O_COST])
        return agrees and _status(stats) is not Status.CONVERGED

    def _posture_attempt(self, stats: np.ndarray) -> tuple[np.ndarray, int]:
        """A second attempt from the posture after a converged first one; the better one stays the state."""
        first = (self._attempt_rank(stats), self._q.copy(), stats)
        second = self._solve_from(self._posture.reference)
        if _status(second) is Status.CONVERGED and self._attempt_rank(second) < first[0]:
            return second, 2
        self._solve_from(first[1], iterations=0)
        return first[2], 2

    def _attempt_rank(self, stats: np.ndarray) -> tuple:
        """How good the attempt that just ended is (lower is better): its weighted error, or with
        priorities its levels' errors in order, so no attempt is preferred for a lower level's sake."""
        if self._is_controlled:
            return self._make_controller().rank(self._q, self._ws.R, self._ws.p)
        return (float(stats[O_COST]),)

    def _solve_from(self, q0: np.ndarray, iterations: int | None = None) -> np.ndarray:
        """One attempt from ``q0``; returns a copy of its statistics and adds its work to ``_work_done``."""
        iterations = self._settings.max_iterations if iterations is None else iterations
        if not self._is_controlled:
            stats = self._kernel_solve(q0, iterations)
        elif iterations and self._reaches_first() and not self._warm_attempt:
            stats = self._reach_then_settle(q0, iterations)  # a warm attempt's targets are a frame away: settled
        else:
            stats = self._control_solve(q0, iterations)
        return self._count(stats)

    def _count(self, stats: np.ndarray) -> np.ndarray:
        """Add an attempt's (or a stage's) work to ``_work_done``; returns ``stats``."""
        done, counts = self._work_done, stats.tolist()  # Python floats: cheaper to read than NumPy scalars
        done[0] += int(counts[O_ITERATIONS])
        done[1] += int(counts[O_SWEEPS])
        return stats

    def _kernel_solve(self, q0: np.ndarray, iterations: int) -> np.ndarray:
        """The single-level attempt (:func:`gsik.kernels.solve.solve`) from ``q0``; a copy of its statistics."""
        if q0 is self._q:
            q0 = q0.copy()  # kept: a refused attempt goes back to it
        self._q[:] = q0  # the kernel clamps it into the limits (cheaper there than np.clip here)
        run = self._plain or self._plain_inputs()
        run[1](run[2], iterations, False)
        stats = self._ws.stats
        if not stats[O_FINITE]:
            self._refuse_non_finite(np.clip(q0, self._skeleton.lower, self._skeleton.upper), stats)
        return stats.copy()

    def _solve_settings(self) -> kernels.KernelSettings:
        """The settings a solve's attempt reads (:func:`gsik.kernels.solve.solve`)."""
        return self._settings.kernel_settings(for_solve=True)._replace(positions_first=self._stages_positions())

    def _stages_positions(self) -> bool:
        """True if a solve's attempts meet the positions first: ``positions_first`` is on and the skeleton has
        more than one effector (a single chain goes for every row at once: fewer linearisations, see
        :class:`~gsik.settings.SolverSettings`)."""
        return self._settings.positions_first and len(self._topo.effector_names) > 1

    def _reaches_first(self) -> bool:
        """True if a prioritised attempt may meet its targets on the single-level path first: a posture is the
        only thing that makes it prioritised (one level of targets, all on effectors, no balance)."""
        return self._posture is not None and not self._balance and not self._layout_controlled  # packed with them

    def _reach_then_settle(self, q0: np.ndarray, iterations: int) -> np.ndarray:
        """An attempt with a posture below one level of targets: meet the targets on the single-level path
        from ``q0``, then settle the posture from there with prioritised steps (the lowest level, it moves
        only within what keeps the targets). Descending on targets and posture together from the rest pose
        missed the targets (1 mm) in 28% of bench_prior's rest-posture solves where the single level missed
        1 in 290. If the single level does not converge, the attempt is the prioritised one from ``q0``.
        Statistics of both phases' work summed. Not a warm solve's first attempt (:meth:`_solve_from`): from where
        the last solve converged the targets are a frame away, and the prioritised steps meet them and settle the
        posture together (bench_drag's hands at 0: median 4 -> 2 linearisations, posture cost as low)."""
        reach = self._kernel_solve(q0, iterations)
        if _status(reach) is Status.CONVERGED:
            stats = self._control_solve(self._q.copy(), iterations)
        else:
            stats = self._control_solve(q0, iterations)
        stats[O_ITERATIONS] += reach[O_ITERATIONS]
        stats[O_SWEEPS] += reach[O_SWEEPS]
        return stats

    def _solve_by_continuation(self, q0: np.ndarray, stages: int = 4) -> np.ndarray:
        """Approach the targets in ``stages`` from where the effectors are at ``q0``."""
        tp, tR = self._packed.position, self._packed.rotation
        final_p, final_R = tp.copy(), tR.copy()
        self._q[:] = q0
        self._refresh_frames()
        start_p = self._ws.p[self._topo.effector_frame].copy()
        start_R = self._ws.R[self._topo.effector_frame].copy()
        try:
            for k in range(1, stages):
                a = k / stages
                for i in range(len(final_p)):
                    tp[i] = (1 - a) * start_p[i] + a * final_p[i]
                    tR[i] = matrix_from_rotvec(a * rotvec_from_matrix(final_R[i] @ start_R[i].T)) @ start_R[i]
                if self._reaches_first():  # the controller aims at the final targets: stage on the single level
                    self._count(self._kernel_solve(self._q.copy(), self._settings.max_iterations))
                else:
                    self._solve_from(self._q.copy())
        finally:
            tp[:], tR[:] = final_p, final_R
        return self._solve_from(self._q.copy())

    def _control_solve(self, q0: np.ndarray, iterations: int) -> np.ndarray:
        """One attempt of prioritised steps from ``q0`` until the pose holds; statistics as the kernel's solve."""
        c = self._make_controller()
        moved = q0.tobytes() != self._q.tobytes()
        if moved:  # the current angles are within the limits: clipped as they are
            self._q[:] = np.clip(q0, self._skeleton.lower, self._skeleton.upper)
        if moved or not self._warm_attempt:  # a warm attempt starts where the last solve left angles and frames
            self._refresh_frames()
        first, converged = self._control_positions_first(c, iterations)
        st, it = self._control_steps(c, iterations - first, converged)
        self._stepped = st is not None  # nothing moves the pose after this attempt's last step (see _solve_result)
        it += first
        stats = np.zeros(kernels.N_STATS)
        stats[O_STATUS] = self._control_status(c, st).value  # an int: NumPy probes an enum's array protocols
        stats[O_ITERATIONS] = it if iterations else 0
        stats[O_COST] = c.target_cost(self._ws.R, self._ws.p)
        stats[O_STEP_NORM] = 0.0 if st is None else st.step_norm
        return stats

    def _control_positions_first(self, c, iterations: int) -> tuple[int, bool | None]:
        """With ``positions_first`` and an orientation target off by more than
        :data:`~gsik.kernels.solve.STAGE_ANGLE`, prioritised steps on the positions alone (every level's
        orientation rows off), as a plain attempt's first phase, for at most
        :data:`~gsik.kernels.solve.POSITION_PHASE_SHARE` of ``iterations``. Returns ``(steps made, every target
        within its tolerances at the start pose, or None if not read)``: without that phase the errors read here
        are the ones :meth:`~gsik.control.Controller.converged` reads, so the posture's settle test reuses them."""
        if not (self._stages_positions() and iterations):
            return 0, None
        staged, within = c.target_state(self._ws.R, self._ws.p, solve_kernels.STAGE_ANGLE)  # one compiled call
        if staged:  # every orientation error within STAGE_ANGLE (a NaN is not)
            return 0, within  # Controller.converged's test, on these errors
        tasks = control.frame_tasks(self._skeleton, self._targets, self._settings.orientation_weight)
        c.retarget([t._replace(row_weight=t.row_weight * _POSITION_ROWS) for t in tasks])
        try:
            return self._control_steps(c, math.ceil(solve_kernels.POSITION_PHASE_SHARE * iterations))[1], None
        finally:
            c.retarget(tasks)

    def _control_steps(self, c, iterations: int, converged: bool | None = None) -> tuple:
        """``(last step's ControlStats or None, steps made)``: at most ``iterations`` prioritised steps;
        ``converged``: every target is within its tolerances at the start pose (None: not known yet)."""
        lam = np.array([self._settings.damping])
        settles = self._posture is not None or self._balance  # keep going after convergence until they hold
        posture = self._posture_settle(c, converged)
        st = None
        it = 0
        q, W, R, p, step = self._q, self._W, self._ws.R, self._ws.p, c.step  # read once, not per step
        if posture is not None:
            c.settle_steps(self._settings.posture_tolerance)  # a worse step that settles it is not retried
        settled, first_step = (None, None) if posture is None else (posture.settled, c.first_step)
        try:
            # A warm solve goes on with the targets' curvature the last one learnt (gsik.kernels.curvature).
            done = None if posture is None else c.steps_until_settled(q, W, R, p, lam, iterations, posture,
                                                                      self._warm_attempt)
            if done is not None:  # the loop below in one compiled call
                st, it = done
                return st, it
            if posture is not None:
                c.curvature_begin(q, R, p, self._warm_attempt, posture.converged)
            for it in range(1, iterations + 1):
                before = q.copy() if settled is not None else None
                st = step(q, W, R, p, lam)
                if settled is not None:
                    c.curvature_learn(q, R, p, st.converged)
                if st.held or (st.converged and not settles):
                    break
                if settled is not None and settled(first_step(), q - before, st.converged):
                    st = st._replace(held=True)
                    break
        finally:
            if posture is not None:  # the gain learnt stays for an attempt from here; a step takes it whole
                self._posture_gain = (c, self._q.tobytes(), float(c.posture_gain[0]), posture.contraction)
                c.posture_gain[0] = 1.0
                c.settle_steps(0.0)
                c.curvature_end()
        return st, it

    def _posture_settle(self, c, converged: bool | None = None) -> PostureSettle | None:
        """The posture's step share and settle test for an attempt's steps (:class:`~gsik.stall.PostureSettle`;
        the share and the steps' contraction the last attempt with this controller learnt if this one starts where
        it ended, as a drag's warm solve does: the curvature it measured is that of this pose; in a warm solve's
        first attempt the settle test is the warm one), or ``None`` without a posture, with balance (its
        level's state is not the targets'), or at ``posture_tolerance`` 0. ``converged``: the targets' state at the
        start pose if known (:meth:`_control_positions_first` read it)."""
        if self._posture is None or self._balance or self._settings.posture_tolerance <= 0.0:
            return None
        learnt = self._posture_gain
        here = learnt[0] is c and learnt[1] == self._q.tobytes()
        c.posture_gain[0] = learnt[2] if here else 1.0
        if converged is None:
            converged = c.converged(self._ws.R, self._ws.p)
        return PostureSettle(self._settings.posture_tolerance, converged, c.posture_gain,
                             learnt[3] if here and self._warm_attempt else None)

    def _control_status(self, c, st) -> Status:
        """How a prioritised attempt ended, given its last step ``st`` (None if it made none). The last step's
        ``converged`` is the targets' state at the pose it left (taken or refused), by the tolerances
        :meth:`~gsik.control.Controller.converged` tests; without a step, or with a non-finite cost (a NaN error
        the kernel and that test would read differently), they are tested here."""
        known = st is not None and math.isfinite(st.cost)
        if st.converged if known else c.converged(self._ws.R, self._ws.p):
            return Status.CONVERGED
        return Status.STALLED if st is not None and st.held else Status.BUDGET_EXHAUSTED


def _status(stats: np.ndarray) -> Status:
    """The :class:`Status` a kernel wrote into ``stats``. Compare this, not the float in ``stats``, with a ``Status``:
    NumPy probes an enum operand for its array protocols, about 5 µs of every warm solve() call."""
    return _STATUSES[int(stats[O_STATUS])]

