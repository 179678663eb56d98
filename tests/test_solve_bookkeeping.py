"""A prioritised solve's bookkeeping (gsik/attempts.py) reads what its steps already evaluated instead of evaluating
it again: the same results, bit for bit, as the solve that evaluates everything afresh (:class:`_Afresh`)."""

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from solver_helpers import studio_drag_targets

import gsik
from gsik.kernels import solve as solve_kernels
from gsik.prior import bundled_prior, use_prior
from gsik.result import Status


class _Afresh(gsik.Solver):
    """The solve as it was before: the targets' convergence at an attempt's start and end evaluated by the
    controller, the result's errors evaluated again, the controller retargeted from the Target objects, the frames
    evaluated at every attempt's start."""

    def _make_controller(self, rows: bool = False):
        return super()._make_controller(rows=False)

    def _control_positions_first(self, c, iterations):
        if not (self._stages_positions() and iterations) or \
                c.errors(self._ws.R, self._ws.p)[1].max(initial=0.0) <= solve_kernels.STAGE_ANGLE:
            return 0, None
        return super()._control_positions_first(c, iterations)

    def _control_solve(self, q0, iterations):
        self._refresh_frames()  # every attempt's frames evaluated at its start, a warm one's too
        return super()._control_solve(q0, iterations)

    def _control_status(self, c, st):
        if c.converged(self._ws.R, self._ws.p):
            return Status.CONVERGED
        return Status.STALLED if st is not None and st.held else Status.BUDGET_EXHAUSTED

    def _control_result(self, status, iterations, residual, step_norm, attempts, report=None):
        return super()._control_result(status, iterations, residual, step_norm, attempts)  # errors evaluated again


def _pair(posture: str, hand_priority: int, **config) -> tuple[gsik.Solver, gsik.Solver, dict]:
    """``(solver, afresh solver, rest effector poses)`` at one drag's start, ``posture`` "start" or "prior"."""
    made = []
    for cls in (gsik.Solver, _Afresh):
        solver = cls(gsik.load_skeleton("biped"))
        poses = solver.effector_poses()
        solver.solve(_targets(poses, 0, 0))
        if posture == "start":
            solver.set_posture(solver.q)
        else:
            use_prior(solver, bundled_prior("biped"))
        solver.configure(**config)
        made.append(solver)
    return made[0], made[1], poses


def _targets(poses: dict, frame: int, hand_priority: int, offset=np.zeros(3)) -> dict:
    targets = studio_drag_targets(poses, frame)
    for hand in ("left_hand", "right_hand"):
        t = targets[hand]
        targets[hand] = gsik.Target(t.position + offset, position_only=True, priority=hand_priority)
    return targets


def _same(a, b) -> None:
    """Two results alike bit for bit."""
    head = ("status", "iterations", "sweeps", "attempts", "effector_names")
    assert [getattr(a, f) for f in head] == [getattr(b, f) for f in head]
    for x, y in ((a.q, b.q), (a.position_errors, b.position_errors), (a.orientation_errors, b.orientation_errors)):
        assert x.tobytes() == y.tobytes()
    assert a.residual == b.residual or (math.isnan(a.residual) and math.isnan(b.residual))
    assert a.step_norm == b.step_norm


def _drag(posture: str, hand_priority: int, frames: int, offset=np.zeros(3), **config) -> list[Status]:
    solver, afresh, poses = _pair(posture, hand_priority, **config)
    statuses = []
    for frame in range(frames):
        targets = _targets(poses, frame, hand_priority, offset)
        a, b = solver.solve(targets), afresh.solve(targets)
        _same(a, b)
        statuses.append(a.status)
    return statuses


def test_a_warm_drag_of_solves_with_the_pins_is_the_same_as_evaluated_afresh():
    assert Status.CONVERGED in _drag("start", 1, 12)


def test_a_warm_drag_of_solves_with_the_hands_at_priority_0_is_the_same_as_evaluated_afresh():
    assert Status.CONVERGED in _drag("start", 0, 8)  # reach on the single level, then settle the posture


def test_the_studio_prior_drag_is_the_same_as_evaluated_afresh():
    assert Status.CONVERGED in _drag("prior", 1, 8)


def test_targets_out_of_reach_restart_and_return_to_the_best_attempt_as_evaluated_afresh():
    # Hands 2 m off: no attempt converges; the restarts end by going back to the best pose without a step.
    statuses = _drag("start", 1, 2, offset=np.array([0.0, 2.0, 0.0]), restarts=2)
    assert Status.CONVERGED not in statuses


def test_an_orientation_far_off_stages_the_positions_first_as_evaluated_afresh():
    solver, afresh, poses = _pair("start", 1)
    targets = _targets(poses, 3, 1)
    turn = gsik.rotations.matrix_from_rotvec(np.array([0.0, 0.0, 0.6]))  # 0.6 rad: above the staging angle
    targets["pelvis"] = gsik.Target(targets["pelvis"].position, turn @ targets["pelvis"].rotation)
    assert 0.6 > solve_kernels.STAGE_ANGLE
    _same(solver.solve(targets), afresh.solve(targets))


def test_a_warm_drag_moved_whole_between_solves_is_the_same_as_evaluated_afresh():
    # A warm attempt starts from the frames the solver holds: moving the character and its targets alike
    # (set_world_from_root) with the angles kept leaves the next solve warm, and its frames must be the moved ones.
    solver, afresh, poses = _pair("start", 1)
    move, shift, statuses = np.array([0.004, 0.0, -0.003]), np.zeros(3), []
    for frame in range(6):
        if frame in (2, 4):
            shift += move
            W = solver.world_from_root
            W[:3, 3] += move
            for s in (solver, afresh):
                s.set_world_from_root(W)
        targets = {n: gsik.Target(t.position + shift, t.orientation, position_only=t.position_only,
                                  priority=t.priority) for n, t in _targets(poses, frame, 1).items()}
        warm = solver._warm_start(solver._q)
        a, b = solver.solve(targets), afresh.solve(targets)
        _same(a, b)
        statuses.append((warm, a.status))
    assert all(s == (frame > 0, Status.CONVERGED) for frame, s in enumerate(statuses))


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.floats(-0.08, 0.08), min_size=3, max_size=3), st.integers(0, 1), st.integers(0, 39))
def test_random_warm_solves_are_the_same_as_evaluated_afresh(offset, hand_priority, frame):
    solver, afresh, poses = _pair("start", hand_priority)
    for k in range(3):
        targets = _targets(poses, frame + k, hand_priority, np.array(offset))
        _same(solver.solve(targets), afresh.solve(targets))


def test_a_solve_again_from_a_converged_pose_is_the_same_as_evaluated_afresh():
    # Its targets start within their tolerances: the settle test's start state, read from the staging check's errors.
    solver, afresh, poses = _pair("start", 1, posture_tolerance=0.05)
    targets = _targets(poses, 5, 1)
    for _ in range(3):
        a, b = solver.solve(targets), afresh.solve(targets)
        _same(a, b)
    assert a.status is Status.CONVERGED
    solver.set_q(a.q + 1e-4)
    afresh.set_q(a.q + 1e-4)
    _same(solver.solve(targets), afresh.solve(targets))
