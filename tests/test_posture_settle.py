"""A prioritised solve's posture settle test (``posture_tolerance``, :class:`gsik.stall.PostureSettle`)."""

import numpy as np
import pytest

import gsik
import gsik.attempts
from gsik.prior import bundled_prior, use_prior
from gsik.stall import PostureSettle

STEP = np.array([4e-4, -9e-4, 1e-4])  # a step [rad] within 1e-3 on every DOF


def _settle(converged: bool = True, gain: float = 1.0) -> PostureSettle:
    return PostureSettle(1e-3, converged, np.array([gain]))


@pytest.mark.parametrize("start, end", [(False, True), (True, False), (False, False)])
def test_a_small_step_settles_nothing_while_a_target_is_off_at_either_end(start, end):
    assert not _settle(start).settled(STEP, STEP, end)


def test_a_step_within_the_tolerance_on_every_dof_settles_the_posture():
    assert _settle().settled(STEP, STEP, True)
    assert _settle().settled(STEP, 0.0 * STEP, True)  # refused: what it would have done is within the tolerance
    assert not _settle().settled(STEP * 1.2, STEP * 1.2, True)  # 1.08e-3 on one DOF


def test_a_step_made_with_a_share_of_the_posture_step_estimates_all_of_it():
    assert not _settle(gain=0.5).settled(STEP, STEP, True)  # the posture's own step: 1.8e-3 on one DOF
    assert _settle(gain=0.5).settled(STEP / 2, STEP / 2, True)


def test_the_start_of_a_step_is_where_the_last_one_ended():
    settle = _settle()
    assert not settle.settled(STEP, STEP, False)  # ended with a target off ...
    assert not settle.settled(STEP, STEP, True)  # ... so the next one started with it off
    assert settle.settled(STEP, STEP, True)


def test_a_warm_attempt_reads_the_step_made_with_a_learnt_share_as_the_remaining_change():
    assert not _settle(gain=0.5).settled(STEP, STEP, True)  # cold: the step over the share, 1.8e-3
    assert PostureSettle(1e-3, True, np.array([0.5]), 0.0).settled(STEP, STEP, True)
    assert not PostureSettle(1e-3, True, np.array([0.5]), 0.0).settled(STEP * 1.2, STEP * 1.2, True)


def _warm_steps(*steps, carried: float | None = 0.0, converged=None) -> list[bool]:
    """Each step's settled(), every step taken whole; ``converged``: the targets' state after each (default all)."""
    settle = PostureSettle(1e-3, False, np.array([1.0]), carried)
    return [settle.settled(s, s, c) for s, c in zip(steps, converged or [True] * len(steps))]


BIG = np.array([4e-2, 1e-2, -2e-2])  # [rad]
NEXT = np.array([4e-3, -3e-3, 1e-3])  # a tenth of BIG's largest DOF: the next one estimated at 4e-4


def test_a_warm_attempt_whose_whole_steps_contract_settles_without_the_verifying_step():
    assert _warm_steps(BIG, NEXT) == [False, True]  # started with a target off: the ratio still estimates the next
    assert _warm_steps(BIG, NEXT, carried=None) == [False, False]  # cold: a step within the tolerance is needed
    assert _warm_steps(BIG, NEXT, converged=[True, False]) == [False, False]  # a target off after it


def test_a_contraction_too_slow_or_estimated_above_the_tolerance_goes_on():
    assert _warm_steps(BIG, BIG * 0.6) == [False, False]  # above CONTRACTION: not a linear close-in yet
    assert _warm_steps(BIG, NEXT * 3.0) == [False, False]  # 0.3 x 1.2e-2: 3.6e-3 still to come
    assert _warm_steps(BIG, NEXT, carried=0.8) == [False, False]  # the last attempt ended on a slow mode


def test_a_halved_or_refused_step_estimates_nothing_and_the_next_reads_its_ratio_to_the_last_whole_one():
    settle = PostureSettle(1e-3, True, np.array([1.0]), 0.0)
    assert not settle.settled(BIG, BIG, True)
    assert not settle.settled(NEXT * 2.0, NEXT * 0.4, True)  # halved twice: 8e-3 full, no ratio to BIG
    assert settle.contraction == pytest.approx(0.0)
    assert not settle.settled(NEXT * 2.0, np.zeros(3), True)  # refused
    assert not settle.settled(NEXT * 2.0, NEXT * 0.01, True)  # the targets' levels alone
    assert settle.contraction == pytest.approx(0.0)
    assert settle.settled(NEXT, NEXT, True)  # taken whole: a tenth of BIG, the last whole one
    assert settle.contraction == pytest.approx(0.1)


MOVE = np.array([3e-2, -1e-2, 2e-2])  # a posture move [rad], far above the tolerance


def _gain_after(*moves, gain: float = 1.0, step_scale: float = 1.0) -> float:
    """The gain after posture moves ``moves``, each its step's full step times ``1 / step_scale``."""
    settle = _settle(gain=gain)
    for m in moves:
        settle.settled(m / step_scale, m, True)
    return float(settle.gain[0])


def test_posture_moves_that_swing_back_halve_the_share_of_the_step_taken():
    assert _gain_after(MOVE, -MOVE) == pytest.approx(0.5)  # mu = -1: the step was twice too long
    assert _gain_after(MOVE, -0.75 * MOVE, gain=0.5) == pytest.approx(0.5 / 1.75)


def test_posture_moves_that_close_in_slowly_take_more_of_the_step_up_to_all_of_it():
    assert _gain_after(MOVE, 0.5 * MOVE, gain=0.25) == pytest.approx(0.5)
    assert _gain_after(MOVE, 0.5 * MOVE, gain=0.8) == 1.0
    assert _gain_after(MOVE, -10.0 * MOVE, gain=0.5) == pytest.approx(0.1)  # at least MIN_POSTURE_GAIN


def test_each_secant_reads_the_length_of_the_move_just_before_it():
    # MOVE then 2 MOVE: mu = 2, no gain from it; then -2 MOVE against 2 MOVE: mu = -1 (against MOVE it would be -4).
    assert _gain_after(MOVE, 2.0 * MOVE, -2.0 * MOVE, gain=0.5) == pytest.approx(0.25)
    settle = _settle(gain=0.5)
    settle.settled(MOVE, MOVE, True)
    settle.settled(2.0 * MOVE, 2.0 * MOVE, True)
    settle.settled(MOVE, MOVE, False)  # a target off: no posture move, none to measure against
    settle.settled(MOVE, MOVE, True)  # started with a target off: not a posture move either
    for m in (3.0 * MOVE, -3.0 * MOVE):  # a new pair, measured against each other only: mu = -1
        settle.settled(m, m, True)
    assert float(settle.gain[0]) == pytest.approx(0.25)


def test_moves_that_turn_or_are_not_the_posture_move_leave_the_share_as_it_is():
    turned = np.array([1e-2, 3e-2, 0.0])  # orthogonal to MOVE: no curvature along one line measured
    assert _gain_after(MOVE, turned, gain=0.5) == 0.5
    assert _gain_after(MOVE, -MOVE, gain=0.5, step_scale=0.4) == 0.5  # each move under half its full step


def _drag(biped, frames: int, priority: int = 0, **settings) -> tuple[list, gsik.control.Posture]:
    """Warm solves of a short drag: pelvis and left foot held, both hands pulled and moved round a circle at
    ``priority``, the pulled pose as the posture (bench_drag's "posture, hands at 0", at 1 its "pins"): every frame's
    result, and the posture."""
    solver = gsik.Solver(biped, **settings)
    rest = solver.effector_poses()

    def targets(frame, priority=0):
        out = {n: gsik.Target.from_transform(rest[n]) for n in ("pelvis", "left_foot")}
        angle = 2.0 * np.pi * frame / 100
        for hand in ("left_hand", "right_hand"):
            moved = [0.1 * (np.cos(angle) - 1.0), 0.15, 0.1 * np.sin(angle)]
            out[hand] = gsik.Target(rest[hand][:3, 3] + moved, position_only=True, priority=priority)
        return out

    solver.solve(targets(0))
    solver.set_posture(solver.q)
    return [solver.solve(targets(f, priority)) for f in range(1, frames + 1)], solver.posture


def _posture_cost(posture, q) -> float:
    """``0.5 (q - reference)^T P (q - reference)`` of a posture with per-DOF weights."""
    d = q - posture.reference
    return 0.5 * d @ (posture.precision * d)


def test_a_settled_posture_ends_warm_solves_sooner_with_the_targets_met_and_the_posture_kept(biped):
    on, posture = _drag(biped, 12)
    off, _ = _drag(biped, 12, posture_tolerance=0.0)
    assert all(r.status is gsik.Status.CONVERGED for r in on + off)
    assert sum(r.iterations for r in on) < sum(r.iterations for r in off)
    for a, b in zip(on, off):  # the posture no worse than 1% of its cost with the test off
        assert _posture_cost(posture, a.q) <= 1.01 * _posture_cost(posture, b.q)


def test_warm_solves_skip_the_verifying_step_with_the_targets_met_and_the_posture_kept(biped, monkeypatch):
    """The pins' drag (hands at 1): the warm settle test (a contraction's estimate) against the cold one in every
    attempt, and against the test off."""
    warm, posture = _drag(biped, 8, priority=1)
    off, _ = _drag(biped, 8, priority=1, posture_tolerance=0.0)
    monkeypatch.setattr(gsik.attempts, "PostureSettle",
                        lambda tolerance, converged, gain, contraction=None: PostureSettle(tolerance, converged, gain))
    cold, _ = _drag(biped, 8, priority=1)
    assert all(r.status is gsik.Status.CONVERGED for r in warm + cold + off)
    assert sum(r.iterations for r in warm) < sum(r.iterations for r in cold) < sum(r.iterations for r in off)
    for a, b in zip(warm, off):
        assert _posture_cost(posture, a.q) <= 1.01 * _posture_cost(posture, b.q)
        np.testing.assert_allclose(a.q, b.q, atol=0.005)  # [rad]


def test_a_step_ignores_the_posture_tolerance(biped):
    def steps(**settings):
        solver = gsik.Solver(biped, **settings)
        solver.set_posture(biped.rest)
        targets = {"left_hand": gsik.Target(solver.effector_poses()["left_hand"][:3, 3] + [0.05, 0.1, 0.0],
                                            position_only=True, priority=1)}
        return [solver.step(targets).q for _ in range(6)]

    for a, b in zip(steps(), steps(posture_tolerance=0.0)):
        np.testing.assert_array_equal(a, b)


def test_the_paper_method_has_no_posture_settle_test():
    assert gsik.SolverSettings.paper().posture_tolerance == 0.0


def test_a_negative_posture_tolerance_is_refused():
    with pytest.raises(gsik.SolverError, match="posture_tolerance"):
        gsik.SolverSettings(posture_tolerance=-1e-3)


def _studio_drag(biped, frames: int, **settings) -> tuple[list, gsik.Solver, list]:
    """Warm solves of the studio's drag (bench_drag's): pelvis and left foot held at 0, both hands pulled 0.15 m
    and moved round a circle at 1, the bundled prior as the posture; the arms nearly straight, where the posture's
    steps swing. Every frame's result, the solver, and the share of the posture's step each solve ended with."""
    solver = gsik.Solver(biped, **settings)
    rest = solver.effector_poses()

    def targets(frame, priority=1):
        out = {n: gsik.Target.from_transform(rest[n]) for n in ("pelvis", "left_foot")}
        angle = 2.0 * np.pi * frame / 100
        for hand in ("left_hand", "right_hand"):
            moved = [0.1 * (np.cos(angle) - 1.0), 0.15, 0.1 * np.sin(angle)]
            out[hand] = gsik.Target(rest[hand][:3, 3] + moved, position_only=True, priority=priority)
        return out

    solver.solve(targets(0, priority=0))
    use_prior(solver, bundled_prior("biped"))
    results, gains = [], []
    for f in range(1, frames + 1):
        results.append(solver.solve(targets(f)))
        gains.append(solver._posture_gain[2])
    return results, solver, gains


def test_swinging_posture_steps_are_shortened_and_a_step_still_takes_the_whole_posture_step(biped, monkeypatch):
    # Gauss-Newton posture steps swing near straight arms; the targets' curvature learnt takes the swing out
    # (tests/test_settle_curvature.py), so the share is watched without it.
    monkeypatch.setattr(gsik.control.Controller, "learns_curvature", False)
    on, solver, gains = _studio_drag(biped, 30)
    off, _, _ = _studio_drag(biped, 30, posture_tolerance=0.0)
    assert all(r.status is gsik.Status.CONVERGED for r in on + off)
    assert sum(r.iterations for r in on) < sum(r.iterations for r in off)
    assert min(gains) < 0.5  # the swing measured: less than half the posture's step, kept for the next solve ...
    assert solver._make_controller().posture_gain[0] == 1.0  # ... but not for a step()


def test_a_warm_solve_settles_from_where_the_last_converged_without_the_single_level_reach(biped, monkeypatch):
    """With the hands at priority 0 (one level of targets, the posture below) a cold attempt meets the targets on
    the single level first; a warm solve's attempt starts where the last solve converged and settles from there,
    and still meets targets that jumped far in one frame."""
    reached = []
    reach = gsik.attempts.AttemptPolicy._reach_then_settle
    monkeypatch.setattr(gsik.attempts.AttemptPolicy, "_reach_then_settle",
                        lambda self, *a: reached.append(self._warm_attempt) or reach(self, *a))
    solver = gsik.Solver(biped)
    rest = solver.effector_poses()

    def targets(lift):
        out = {n: gsik.Target.from_transform(rest[n]) for n in ("pelvis", "left_foot")}
        for hand in ("left_hand", "right_hand"):
            out[hand] = gsik.Target(rest[hand][:3, 3] + [0.0, lift, 0.05], position_only=True)
        return out

    solver.set_posture(solver.q)
    assert solver.solve(targets(0.0)).status is gsik.Status.CONVERGED
    assert reached == [False]  # cold: reached first
    for lift in (0.01, 0.02, 0.25):  # a frame's move, then a jump
        r = solver.solve(targets(lift))
        assert r.status is gsik.Status.CONVERGED
        assert r.position_errors.max() <= solver.settings.position_tolerance
    assert reached == [False]  # every warm one settled from where the last converged
