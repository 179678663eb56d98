"""A prioritised solve's posture settle test (``posture_tolerance``, :class:`gsik.stall.PostureSettle`)."""

import numpy as np
import pytest

import gsik
from gsik.stall import PostureSettle

STEP = np.array([4e-4, -9e-4, 1e-4])  # a step [rad] within 1e-3 on every DOF


@pytest.mark.parametrize("start, end", [(False, True), (True, False), (False, False)])
def test_a_small_step_settles_nothing_while_a_target_is_off_at_either_end(start, end):
    assert not PostureSettle(1e-3, start).settled(STEP, end)


def test_a_step_within_the_tolerance_on_every_dof_settles_the_posture():
    assert PostureSettle(1e-3, True).settled(STEP, True)
    assert not PostureSettle(1e-3, True).settled(STEP * 1.2, True)  # 1.08e-3 on one DOF


def test_the_start_of_a_step_is_where_the_last_one_ended():
    settle = PostureSettle(1e-3, True)
    assert not settle.settled(STEP, False)  # ended with a target off ...
    assert not settle.settled(STEP, True)  # ... so the next one started with it off
    assert settle.settled(STEP, True)


def _drag(biped, frames: int, **settings) -> tuple[list, gsik.control.Posture]:
    """Warm solves of a short drag: pelvis and left foot held, both hands pulled and moved round a circle at priority
    0, the pulled pose as the posture (bench_drag's "posture, hands at 0"): every frame's result, and the posture."""
    solver = gsik.Solver(biped, **settings)
    rest = solver.effector_poses()

    def targets(frame):
        out = {n: gsik.Target.from_transform(rest[n]) for n in ("pelvis", "left_foot")}
        angle = 2.0 * np.pi * frame / 100
        for hand in ("left_hand", "right_hand"):
            moved = [0.1 * (np.cos(angle) - 1.0), 0.15, 0.1 * np.sin(angle)]
            out[hand] = gsik.Target(rest[hand][:3, 3] + moved, position_only=True)
        return out

    solver.solve(targets(0))
    solver.set_posture(solver.q)
    return [solver.solve(targets(f)) for f in range(1, frames + 1)], solver.posture


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
