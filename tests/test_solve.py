"""Solver.solve(): limits, a settled best reach, the work it reports, and every setting reaching it."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gsik
from gsik import Status, Target
from gsik.kernels import O_ITERATIONS, O_SWEEPS
from gsik.rotations import matrix_from_rotvec

from solver_helpers import random_q, targets_at


def unreachable_targets(solver):
    """Every effector where it stands, one hand 3 m away."""
    targets = {n: Target.from_transform(T) for n, T in solver.effector_poses().items()}
    targets["left_hand"] = Target([-3.0, 2.0, 2.5])
    return targets


@given(seed=st.integers(0, 2**32 - 1), adaptive=st.booleans(), subspace=st.booleans(), staged=st.booleans(),
       solve_max_step=st.sampled_from([0.0, 0.1, 1.0]), warm=st.booleans())
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_solve_never_leaves_the_limits_whatever_the_method(biped, seed, adaptive, subspace, staged, solve_max_step,
                                                           warm):
    rng = np.random.default_rng(seed)
    solver = gsik.Solver(biped, adaptive_damping=adaptive, subspace_minimization=subspace, positions_first=staged,
                         solve_max_step=solve_max_step, warm_start=warm, max_iterations=40, restarts=2, seed=seed)
    targets = {n: Target(rng.uniform(-1.5, 1.5, 3) + [0, 0, 1], matrix_from_rotvec(rng.normal(size=3)))
               for n in solver.effector_names}
    r = solver.solve(targets, q0=random_q(biped, rng))
    assert np.all(np.isfinite(r.q)) and np.all(np.isfinite(r.position_errors))
    assert np.all(r.q >= biped.lower) and np.all(r.q <= biped.upper)
    np.testing.assert_array_equal(r.q, solver.q)


def test_held_unreachable_target_settles_then_costs_nothing(biped):
    solver = gsik.Solver(biped)
    targets = unreachable_targets(solver)
    first = solver.solve(targets)
    assert first.status is Status.STALLED
    assert np.all(np.isfinite(first.q)) and np.isfinite(first.residual)
    assert first.iterations > 0 and first.sweeps > 0
    again = solver.solve(targets)  # held: the same targets, from the best reach the first solve left
    assert again.status is Status.STALLED
    assert (again.attempts, again.iterations, again.sweeps) == (1, 0, 0)
    np.testing.assert_array_equal(again.q, first.q)
    np.testing.assert_array_equal(again.position_errors, first.position_errors)
    assert again.residual == first.residual


def test_a_settled_reach_is_forgotten_when_targets_start_or_settings_change(biped):
    solver = gsik.Solver(biped, restarts=1)
    targets = unreachable_targets(solver)
    solver.solve(targets)
    targets["left_hand"] = Target([-3.0, 2.0, 2.4])
    assert solver.solve(targets).iterations > 0  # other targets
    solver.solve(targets)
    assert solver.solve(targets, q0=biped.rest).iterations > 0  # another start
    solver.solve(targets)
    solver.configure(damping=2e-3)
    assert solver.solve(targets).iterations > 0  # other settings


def test_reported_work_is_the_sum_over_all_attempts(biped, monkeypatch):
    solver = gsik.Solver(biped, restarts=3)
    kernel = gsik.solver.plain_kernels.solve_plain  # every single-level attempt's compiled call
    done = []

    def counting(inputs, max_iterations, finish):
        out = kernel(inputs, max_iterations, finish)
        done.append((int(solver._ws.stats[O_ITERATIONS]), int(solver._ws.stats[O_SWEEPS])))
        return out

    monkeypatch.setattr(gsik.solver.plain_kernels, "solve_plain", counting)
    targets = unreachable_targets(solver)
    targets["right_hand"] = Target([3.0, -2.0, 2.5])
    r = solver.solve(targets)
    assert r.attempts > 1 and len(done) >= r.attempts  # a continuation runs several kernel calls
    assert r.iterations == sum(i for i, _ in done) and r.sweeps == sum(s for _, s in done)
    assert r.iterations > done[0][0]  # not only the first attempt's work


def test_paper_solve_is_the_paper_step_repeated(biped, rng):
    paper = gsik.SolverSettings.paper(solve_sweeps=7, sweeps=7, restarts=0, max_iterations=25)
    targets = targets_at(biped, np.clip(biped.rest + rng.normal(0, 0.3, biped.n_dofs), biped.lower, biped.upper),
                         gsik.Solver(biped).world_from_root)
    solved = gsik.Solver(biped, settings=paper).solve(targets)
    stepper = gsik.Solver(biped, settings=paper)
    stepper.set_targets(targets)
    for _ in range(solved.iterations):
        stepped = stepper.step()
    assert solved.iterations > 0
    np.testing.assert_allclose(solved.q, stepped.q, rtol=0, atol=1e-12)


# Each setting a solve reads, with another value: the solve's outcome must change (today's bug: two settings
# were silently ignored, bit-identical results on or off).
SOLVE_SETTINGS = [
    ({}, "adaptive_damping", False), ({}, "subspace_minimization", False), ({}, "positions_first", False),
    ({}, "solve_max_step", 0.05), ({}, "warm_start", False), ({"restarts": 0}, "settle_tolerance", 0.3),
    ({}, "damping", 0.3), ({}, "orientation_weight", 2.0), ({}, "max_iterations", 3),
    ({"subspace_minimization": False}, "solve_sweeps", 1),
    ({"subspace_minimization": False, "solve_sweeps": 30}, "residual_tolerance", 1e-2),
    ({"subspace_minimization": False, "solve_sweeps": 30}, "update_tolerance", 1e-2),
    ({"subspace_minimization": False, "solve_sweeps": 30}, "stall_tolerance", 1e-1),
    ({"max_iterations": 4}, "restarts", 0), ({"max_iterations": 4}, "seed", 7),
]


@pytest.mark.parametrize("base, name, other", SOLVE_SETTINGS, ids=[s[1] for s in SOLVE_SETTINGS])
def test_every_solve_setting_reaches_solve(biped, base, name, other):
    rng = np.random.default_rng(3)
    W = gsik.Solver(biped).world_from_root
    problems = [targets_at(biped, random_q(biped, rng), W) for _ in range(4)]

    def outcomes(**extra):
        solver = gsik.Solver(biped, **base, **extra)
        return [solver.solve(t, q0=biped.rest) for t in problems]

    a, b = outcomes(), outcomes(**{name: other})
    assert any(x.iterations != y.iterations or not np.array_equal(x.q, y.q) for x, y in zip(a, b)), name


def test_step_only_settings_do_not_change_a_solve(biped, rng):
    targets = targets_at(biped, random_q(biped, rng), gsik.Solver(biped).world_from_root)
    a = gsik.Solver(biped).solve(targets)
    b = gsik.Solver(biped, sweeps=3, max_step=0.05).solve(targets)
    np.testing.assert_array_equal(a.q, b.q)


def test_paper_settings_name_the_paper_method_for_a_solve():
    paper = gsik.SolverSettings.paper()
    assert not (paper.adaptive_damping or paper.subspace_minimization or paper.positions_first)
    assert paper.max_step == paper.solve_max_step == paper.settle_tolerance == 0.0


# Poses of bench_reach's set (index: draw of default_rng(1)) no solve with restarts reached before:
# 857: every attempt ended 3.7 mm off with the right shoulder's x and z each on a limit (the target's near the
# other ends; the attempt from the best reach with those DOFs mirrored converges);
# 438: eight attempts in a row ended 16 mm off at one local minimum, and agreement settled it (the 13th converges).
@pytest.mark.parametrize("index", [857, 438])
def test_poses_once_missed_with_restarts_are_reached(biped, index):
    rng = np.random.default_rng(1)
    q_target = [random_q(biped, rng) for _ in range(index + 1)][-1]
    solver = gsik.Solver(biped)
    r = solver.solve(targets_at(biped, q_target, solver.world_from_root), q0=biped.rest)
    assert r.status is Status.CONVERGED
    assert r.max_position_error < 1e-3 and r.max_orientation_error < np.radians(1.0)


def prioritised(targets):
    """The same targets, the hands one level below the rest."""
    return {n: t.replace(priority=1) if n.endswith("hand") else t for n, t in targets.items()}


def test_positions_first_reaches_a_prioritised_solve(biped):
    rng = np.random.default_rng(3)
    W = gsik.Solver(biped).world_from_root
    problems = [prioritised(targets_at(biped, random_q(biped, rng), W)) for _ in range(3)]

    def outcomes(**extra):
        solver = gsik.Solver(biped, restarts=0, max_iterations=60, **extra)
        return [solver.solve(t, q0=biped.rest) for t in problems]

    a, b = outcomes(), outcomes(positions_first=False)
    assert any(x.iterations != y.iterations or not np.array_equal(x.q, y.q) for x, y in zip(a, b))


def test_a_held_prioritised_unreachable_target_settles_then_costs_nothing(biped):
    solver = gsik.Solver(biped)
    targets = prioritised(unreachable_targets(solver))
    first = solver.solve(targets)
    assert first.status is Status.STALLED and first.iterations > 0
    again = solver.solve(targets)
    assert again.status is Status.STALLED
    assert (again.attempts, again.iterations, again.sweeps) == (1, 0, 0)
    np.testing.assert_array_equal(again.q, first.q)
    np.testing.assert_array_equal(again.position_errors, first.position_errors)
    assert again.effector_names == first.effector_names and again.residual == first.residual


def test_a_settled_reach_is_forgotten_when_priorities_posture_or_balance_change(biped):
    solver = gsik.Solver(biped, restarts=1)
    targets = unreachable_targets(solver)
    solver.solve(targets)
    assert solver.solve(prioritised(targets)).iterations > 0  # the same values on two levels: another problem
    solver.solve(targets)
    solver.set_posture()
    assert solver.solve(targets).iterations > 0  # a posture to meet too
    solver.set_posture(weights=0.0)
    solver.solve(targets)
    solver.set_balance(True)
    assert solver.solve(targets).iterations > 0  # balance to hold too


def test_targets_no_pose_meets_settle_on_the_first_attempt_that_finds_the_best_reach_again(biped):
    solver = gsik.Solver(biped)
    r = solver.solve(unreachable_targets(solver))  # the first solve of a new unreachable target
    assert r.status is Status.STALLED
    assert r.attempts <= 1 + gsik.attempts.SETTLED_REPEATS < 9  # before: eight agreeing attempts settled it


def test_reachable_targets_are_never_taken_for_out_of_reach(biped, rng):
    solver = gsik.Solver(biped)
    for _ in range(20):
        solver.set_targets(targets_at(biped, random_q(biped, rng), solver.world_from_root))
        assert not solver._out_of_reach()
    solver.set_targets(unreachable_targets(solver))
    assert solver._out_of_reach()
