"""The solver's behaviour: limits, root switching, warm start, best reach, bad input."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gsik
from gsik import Status, Target
from gsik.benchmark import smooth_trajectory

from solver_helpers import random_q, targets_at


@pytest.fixture
def solver(biped):
    return gsik.Solver(biped)


def rest_targets(solver):
    return {n: Target.from_transform(T) for n, T in solver.effector_poses().items()}


def test_rest_pose_with_targets_at_rest_is_converged(solver):
    r = solver.step(rest_targets(solver))
    assert r.status is Status.CONVERGED
    assert r.max_position_error < 1e-12 and r.max_orientation_error < 1e-9


def test_step_moves_an_effector_to_a_reachable_target(solver):
    targets = rest_targets(solver)
    goal = np.array([-0.35, 0.30, 1.15])
    targets["left_hand"] = Target(goal)
    before = np.linalg.norm(solver.effector_poses()["left_hand"][:3, 3] - goal)
    for _ in range(60):
        r = solver.step(targets)
    after = np.linalg.norm(solver.effector_poses()["left_hand"][:3, 3] - goal)
    assert after < 1e-3 < before
    assert r.errors()["left_hand"][0] == pytest.approx(after, abs=1e-12)


def test_solve_reaches_a_random_reachable_pose(biped, rng):
    solver = gsik.Solver(biped)
    q_goal = random_q(biped, rng)
    r = solver.solve(targets_at(biped, q_goal, solver.world_from_root))
    assert r.converged
    assert r.max_position_error < solver.settings.position_tolerance
    assert r.max_orientation_error < solver.settings.orientation_tolerance
    np.testing.assert_array_equal(r.q, solver.q)


@given(seed=st.integers(0, 2**32 - 1), sweeps=st.integers(1, 20), max_step=st.sampled_from([0.0, 0.1, 1.0]),
       adaptive=st.booleans())
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_limits_are_never_violated(biped, seed, sweeps, max_step, adaptive):
    rng = np.random.default_rng(seed)
    solver = gsik.Solver(biped, sweeps=sweeps, max_step=max_step, adaptive_damping=adaptive)
    # Targets far and wide, reachable or not, changing every few frames.
    for frame in range(30):
        if frame % 5 == 0:
            targets = {n: Target(rng.uniform(-1.5, 1.5, 3) + [0, 0, 1], gsik.rotations.matrix_from_rotvec(
                rng.normal(size=3))) for n in solver.effector_names}
        r = solver.step(targets)
        assert np.all(r.q >= biped.lower) and np.all(r.q <= biped.upper)
        assert np.all(np.isfinite(r.q))
    r = solver.solve()
    assert np.all(r.q >= biped.lower) and np.all(r.q <= biped.upper)


@pytest.mark.parametrize("new_root", ["left_foot", "pelvis", "head", "left_hand", "left_knee", "hips"])
def test_root_switch_leaves_every_joint_in_place(biped, rng, new_root):
    solver = gsik.Solver(biped, q0=random_q(biped, rng))
    before = solver.frame_transforms()
    q_before = solver.q
    solver.set_root(new_root)
    assert solver.root == new_root
    np.testing.assert_allclose(solver.frame_transforms(), before, atol=1e-9)
    np.testing.assert_array_equal(solver.q, q_before)  # angles keep their meaning
    solver.set_root("right_foot")
    np.testing.assert_allclose(solver.frame_transforms(), before, atol=1e-9)


def test_root_switch_keeps_the_pose_while_solving_from_the_new_root(biped, rng):
    solver = gsik.Solver(biped)
    solver.set_targets(rest_targets(solver))
    solver.set_root("left_foot")
    assert solver.effector_names == ("head", "pelvis", "left_hand", "right_hand", "right_foot")
    # The old root foot is held where it stood; nothing moves while nothing is asked.
    np.testing.assert_allclose(solver.targets["right_foot"].position, solver.effector_poses()["right_foot"][:3, 3])
    before = solver.frame_transforms()
    for _ in range(5):
        assert solver.step().status is Status.CONVERGED
    np.testing.assert_allclose(solver.frame_transforms(), before, atol=1e-9)
    # Now lift the right foot: the left (the root) must not move at all.
    left = before[biped.frame_of("left_foot")]
    targets = solver.targets
    targets["right_foot"] = targets["right_foot"].replace(position=targets["right_foot"].position + [0, 0.1, 0.1])
    for _ in range(30):
        solver.step(targets)
    np.testing.assert_allclose(solver.frame_transforms()[biped.frame_of("left_foot")], left, atol=1e-12)
    assert np.linalg.norm(solver.effector_poses()["right_foot"][:3, 3] - targets["right_foot"].position) < 1e-3


def test_a_reversed_joint_turns_the_other_way_seen_from_the_root(biped):
    # From the right foot, bending the right knee (q more negative) tips the body backwards over it.
    solver = gsik.Solver(biped)
    q = solver.q
    pelvis0 = solver.frame_transforms()[biped.frame_of("pelvis"), :3, 3]
    q[biped.dof_index("right_knee.x")] -= 0.3
    solver.set_q(q)
    pelvis1 = solver.frame_transforms()[biped.frame_of("pelvis"), :3, 3]
    foot = solver.frame_transforms()[biped.frame_of("right_foot")]
    np.testing.assert_allclose(foot[:3, 3], [0.09, 0.0505, 0.0], atol=1e-3)  # the root did not move
    assert pelvis1[2] < pelvis0[2] - 0.005  # the knee bent under the body


def smooth_motion(biped, frames=120, seed=0):
    """A smooth 60 fps joint trajectory inside the limits (the benchmarks' own)."""
    return smooth_trajectory(biped, frames, seed)


def test_warm_start_tracks_better_than_cold_start_for_the_same_sweeps(biped):
    """The paper's warm start: last frame's step seeds this frame's sweeps, so a fixed budget goes further."""
    Q = smooth_motion(biped)
    W = gsik.Solver(biped, q0=Q[0]).world_from_root
    errors = {}
    for warm in (True, False):
        paper = gsik.SolverSettings.paper(sweeps=20, warm_start=warm, update_tolerance=0, residual_tolerance=0)
        solver = gsik.Solver(biped, q0=Q[0], settings=paper)
        errors[warm] = np.median([solver.step(targets_at(biped, q, W)).max_position_error for q in Q[1:]])
    assert errors[True] < 0.5 * errors[False], errors


def test_warm_start_needs_fewer_iterations_than_cold_start(biped):
    """Full solves along a trajectory: from the last frame's answer versus from the rest pose every frame."""
    Q = smooth_motion(biped, frames=30, seed=1)
    W = gsik.Solver(biped, q0=Q[0]).world_from_root
    iterations = {}
    for warm in (True, False):
        solver = gsik.Solver(biped, q0=Q[0], restarts=0)
        results = [solver.solve(targets_at(biped, q, W), q0=None if warm else biped.rest) for q in Q[1:]]
        assert all(r.converged for r in results)
        iterations[warm] = sum(r.iterations for r in results)
    assert iterations[True] < 0.5 * iterations[False], iterations


def test_unreachable_targets_settle_into_a_stable_best_reach(biped):
    solver = gsik.Solver(biped, sweeps=5)
    targets = rest_targets(solver)
    targets["left_hand"] = Target([-3.0, 2.0, 2.5])  # metres out of reach
    targets["head"] = Target([0.0, 0.0, 3.0], np.eye(3))
    changes = []
    for _ in range(400):
        q0 = solver.q
        r = solver.step(targets)
        assert np.all(np.isfinite(r.q)) and np.all(np.isfinite(r.position_errors))
        changes.append(np.abs(r.q - q0).max())
    assert r.status is Status.STALLED
    assert max(changes[-100:]) < 1e-6  # no jitter, no oscillation
    hand = solver.effector_poses()["left_hand"][:3, 3]
    shoulder = solver.frame_transforms()[biped.frame_of("left_shoulder"), :3, 3]
    direction = (np.array([-3.0, 2.0, 2.5]) - shoulder) / np.linalg.norm(np.array([-3.0, 2.0, 2.5]) - shoulder)
    assert (hand - shoulder) @ direction > 0.55  # the arm stretches out towards the target


def test_solve_reports_best_reach_for_unreachable_targets(biped):
    solver = gsik.Solver(biped, restarts=1)
    targets = rest_targets(solver)
    targets["right_hand"] = Target([4.0, 0.0, 1.0])
    r = solver.solve(targets)
    assert r.status is Status.STALLED
    assert np.all(np.isfinite(r.q))


def test_position_only_and_disabled_effectors_are_ignored(solver):
    targets = rest_targets(solver)
    targets["left_hand"] = Target([-0.3, 0.3, 1.1], gsik.rotations.matrix_from_rotvec([0, 0, 3.0]),
                                  position_only=True)
    targets["head"] = None
    for _ in range(80):
        r = solver.step(targets)
    i = r.effector_names.index("left_hand")
    assert r.position_errors[i] < 1e-3
    assert r.orientation_errors[i] == 0.0  # its orientation is not asked for
    assert r.position_errors[r.effector_names.index("head")] == 0.0
    assert "head" not in solver.targets


def test_weights_decide_conflicts(biped):
    """Two effectors pull apart; the heavier one gets closer to its target."""
    errs = {}
    for w in (10.0, 0.1):
        solver = gsik.Solver(biped)
        targets = rest_targets(solver)
        targets["left_hand"] = Target([-2.0, 0.0, 1.3], weight=w)
        targets["right_hand"] = Target([2.0, 0.0, 1.3], weight=1.0)
        r = solver.solve(targets)
        errs[w] = r.errors()["left_hand"][0]
    assert errs[10.0] < errs[0.1]


def test_result_arrays_are_copies(solver):
    r = solver.step(rest_targets(solver))
    r.q[0] = 1.0
    r.position_errors[0] = 5.0
    assert solver.q[0] != 1.0
    assert solver.step().position_errors[0] != 5.0
    q = solver.q
    q[0] = 1.0
    assert solver.q[0] != 1.0


@pytest.mark.parametrize("bad, message", [
    ({"position": [np.nan, 0, 0]}, "position must be finite"),
    ({"position": [np.inf, 0, 0]}, "position must be finite"),
    ({"position": [0, 0]}, r"position must have shape \(3,\)"),
    ({"position": "here"}, "position must be 3 numbers"),
    ({"position": [0, 0, 0], "orientation": np.diag([1.0, 1.0, -1.0])}, "not a rotation matrix"),
    ({"position": [0, 0, 0], "orientation": np.eye(3) * 2}, "not a rotation matrix"),
    ({"position": [0, 0, 0], "orientation": [2, 0, 0, 0]}, "unit norm"),
    ({"position": [0, 0, 0], "orientation": [np.nan, 0, 0, 1]}, "orientation must be finite"),
    ({"position": [0, 0, 0], "orientation": np.eye(2)}, r"shape \(3, 3\) or \(4,\)"),
    ({"position": [0, 0, 0], "weight": -1}, "weight must be finite and >= 0"),
    ({"position": [0, 0, 0], "weight": np.nan}, "weight must be finite and >= 0"),
])
def test_bad_targets_are_rejected_before_they_touch_the_solver(solver, bad, message):
    q0, targets0 = solver.q, solver.targets
    with pytest.raises(gsik.TargetError, match=message):
        solver.step({"left_hand": Target(**bad)})
    np.testing.assert_array_equal(solver.q, q0)
    assert solver.targets == targets0


def test_unknown_effector_and_root_as_target_are_rejected(solver):
    with pytest.raises(gsik.TargetError, match=r"no effector 'left_hnd'; effectors: 'head', 'pelvis'"):
        solver.set_targets({"left_hnd": Target([0, 0, 1])})
    with pytest.raises(gsik.TargetError, match=r"'right_foot' is the IK root"):
        solver.set_targets({"right_foot": Target([0, 0, 1])})
    with pytest.raises(gsik.TargetError, match="must be a gsik.Target"):
        solver.set_targets({"head": [0, 0, 1]})


def test_unknown_root_lists_the_choices(solver):
    with pytest.raises(gsik.SkeletonError, match="no joint or site 'left_shoe'.*sites: 'pelvis'"):
        solver.set_root("left_shoe")
    assert solver.root == "right_foot"


@pytest.mark.parametrize("settings_, message", [
    ({"damping": 0.0}, "damping must be > 0"),
    ({"damping": -1.0}, "damping must be finite and >= 0"),
    ({"sweeps": 0}, "sweeps must be at least 1"),
    ({"sweeps": 2.5}, "sweeps must be a whole number"),
    ({"max_step": np.nan}, "max_step must be finite"),
    ({"warm_start": "yes"}, "warm_start must be True or False"),
    ({"dampening": 0.1}, "unknown solver setting.*'dampening'.*valid: 'damping'"),
])
def test_bad_settings_name_the_setting(biped, settings_, message):
    with pytest.raises(gsik.SolverError, match=message):
        gsik.Solver(biped, **settings_)


def test_initial_angles_are_checked(biped):
    q = biped.rest.copy()
    q[biped.dof_index("left_knee.x")] = 1.0
    with pytest.raises(gsik.SolverError, match=r"left_knee.x = 1 rad is outside its limits \[-2.79, 0\]"):
        gsik.Solver(biped, q0=q)
    with pytest.raises(gsik.SkeletonError, match=r"joint angles must have shape \(30,\)"):
        gsik.Solver(biped, q0=np.zeros(3))
    q[:] = np.nan
    with pytest.raises(gsik.SkeletonError, match="not finite"):
        gsik.Solver(biped, q0=q)


def test_paper_mode_fixed_damping_still_tracks(biped):
    """adaptive_damping=False is the paper's plain method: fixed delta, k sweeps, warm start."""
    solver = gsik.Solver(biped, settings=gsik.SolverSettings.paper(sweeps=5))
    targets = rest_targets(solver)
    targets["right_hand"] = Target(targets["right_hand"].position + [0.05, 0.1, 0.1])
    for _ in range(300):
        r = solver.step(targets)
    assert r.max_position_error < 1e-3
