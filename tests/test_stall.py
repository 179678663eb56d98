"""The prioritised path's stall detector, and settling with the studio's pins and the natural posture (library)."""

import math

import numpy as np

import gsik
from gsik.prior import bundled_prior, use_prior
from gsik.rotations import matrix_from_axis_angle
from gsik.stall import STALL_SHRINK, STALL_WINDOW, StallDetector

TOLERANCE_NORMS = np.array([1e-4, 1e-4])


def _run(detector, norms_per_step, met=(True, False)) -> list[bool]:
    """``creeps`` after each step of target level norms ``norms_per_step``."""
    unmet = ~np.array(met)
    return [detector.creeps(unmet, np.asarray(n) ** 2) for n in norms_per_step]  # costs whose roots are n


def test_steps_that_gain_less_than_the_threshold_creep_after_the_window():
    d = StallDetector(TOLERANCE_NORMS)
    # A level 0.3 tolerances off gaining 0.1% of a tolerance a step.
    flags = _run(d, [[0.0, 3e-4 - 1e-7 * k] for k in range(STALL_WINDOW + 2)])
    assert not any(flags[:STALL_WINDOW]) and all(flags[STALL_WINDOW:])


def test_steps_that_close_in_never_creep():
    d = StallDetector(TOLERANCE_NORMS)
    assert not any(_run(d, [[0.0, 1e-2 * 0.8 ** k] for k in range(3 * STALL_WINDOW)]))


def test_a_large_error_shrinking_by_more_than_its_share_is_progress_but_less_is_a_creep():
    gain = 2 * STALL_SHRINK / STALL_WINDOW  # per step, relative
    d = StallDetector(TOLERANCE_NORMS)
    assert not any(_run(d, [[0.0, 0.01 * (1 - gain) ** k] for k in range(3 * STALL_WINDOW)]))
    d = StallDetector(TOLERANCE_NORMS)
    assert _run(d, [[0.0, 0.01 * (1 - gain / 4) ** k] for k in range(3 * STALL_WINDOW)])[-1]


def test_all_levels_met_or_a_level_met_anew_starts_again():
    d = StallDetector(TOLERANCE_NORMS)
    creeping = [[0.0, 3e-4]] * (STALL_WINDOW + 1)
    assert _run(d, creeping)[-1]
    assert not d.creeps(np.array([False, False]), np.zeros(2))
    assert not any(_run(d, creeping[:STALL_WINDOW]))
    assert not d.creeps(np.array([True, True]), np.array([1e-8, 1e-8]))  # level 0 unmet anew


def test_one_level_still_closing_in_is_no_stall():
    d = StallDetector(TOLERANCE_NORMS)
    flags = _run(d, [[3e-4, 1e-2 * 0.8 ** k] for k in range(2 * STALL_WINDOW)], met=(False, False))
    assert not any(flags)


def _studio(biped):
    """The studio's new document: feet and pelvis pinned, head and hands at 1 (hands position-only), the prior."""
    solver = gsik.Solver(biped, sweeps=8, damping=1e-3)
    pinned = ("left_foot", "pelvis")
    targets = {n: gsik.Target.from_transform(T, position_only=n.endswith("_hand"), priority=0 if n in pinned else 1)
               for n, T in solver.effector_poses().items()}
    use_prior(solver, bundled_prior("biped"))
    return solver, targets


def _turn_head(targets, degrees):
    head = targets["head"]
    R = matrix_from_axis_angle(np.array([0.0, 0.0, 1.0]), math.radians(degrees)) @ head.rotation
    return {**targets, "head": head.replace(orientation=R)}


def _steps_until(solver, status, most):
    for n in range(1, most + 1):
        r = solver.step()
        if r.status is status:
            return n, r
    return -1, r


def test_a_15_degree_head_turn_converges_within_60_steps_with_pins_and_prior(biped):
    solver, targets = _studio(biped)
    solver.set_targets(_turn_head(targets, 15.0))
    n, r = _steps_until(solver, gsik.Status.CONVERGED, 60)
    assert n > 0, f"{r.status.name} at {r.max_position_error * 1000:.3f} mm after 60 steps"
    assert r.errors()["pelvis"][0] < 1e-6 and r.errors()["left_foot"][0] < 1e-6


def test_a_head_turn_beyond_reach_by_a_hair_stalls_within_60_steps_and_then_holds(biped):
    solver, targets = _studio(biped)
    solver.set_targets(_turn_head(targets, 30.0))  # best reach about 0.12 mm off (0.1 mm tolerance)
    n, r = _steps_until(solver, gsik.Status.STALLED, 60)
    assert n > 0, f"{r.status.name} at {r.max_position_error * 1000:.3f} mm after 60 steps"
    assert r.errors()["head"][0] < 0.2e-3
    q = solver.q
    for _ in range(5):
        assert solver.step().status is gsik.Status.STALLED
    np.testing.assert_array_equal(solver.q, q)
