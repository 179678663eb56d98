"""Pose scenarios, random poses and robustness (paper IX.B, IX.C)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import gsik
from gsik.io.pose import pose_from_yaml, pose_to_yaml
from gsik.rotations import angle_between
from gsik.anim.scenarios import (
    SCENARIO_NAMES,
    Scenario,
    ScenarioError,
    angles,
    builtin_scenario,
    builtin_scenarios,
    random_scenario,
    random_scenarios,
    scenario_from_angles,
    scenario_pose,
)
from gsik.anim.scenario_run import format_table, run_scenario, run_scenarios
from gsik.skeleton import JointSpec, RotationSpec, SiteSpec, build_skeleton


@pytest.fixture(scope="module")
def biped():
    return gsik.load_skeleton("biped")


@pytest.fixture(scope="module")
def scenarios(biped):
    return {s.name: s for s in builtin_scenarios(biped)}


@pytest.fixture(scope="module")
def reports(scenarios):
    return {r.name: r for r in run_scenarios(list(scenarios.values()))}


# -- building ----------------------------------------------------------------------------


def test_builtin_scenarios_are_the_named_ones(scenarios):
    assert tuple(scenarios) == SCENARIO_NAMES
    for s in scenarios.values():
        assert isinstance(s, Scenario)
        assert s.root == "right_foot"
        assert set(s.effectors) == {"head", "pelvis", "left_hand", "right_hand", "left_foot"}
        assert np.all(np.isfinite(s.positions))
        assert set(s.targets_at(0)) == set(s.effectors)


def test_unknown_scenario_lists_the_valid_names(biped):
    with pytest.raises(ScenarioError, match="'kneel', 'one_leg'"):
        builtin_scenario(biped, "backflip")


def test_builtin_scenarios_need_the_biped():
    sk = build_skeleton(
        "stick",
        [JointSpec("base", None, (0, 0, 0)), JointSpec("arm", "base", (0, 0, 1), (RotationSpec((1, 0, 0), -1, 1),))],
        sites=[SiteSpec("tip", "arm", (0, 0, 1))],
        effectors=["tip"],
    )
    with pytest.raises(ScenarioError, match="written for the biped"):
        builtin_scenario(sk, "kneel")


def test_angles_check_names_and_limits(biped):
    with pytest.raises(ScenarioError, match="no degree of freedom 'elbow'"):
        angles(biped, {"elbow": 1.0})
    with pytest.raises(ScenarioError, match="outside its limits"):
        angles(biped, {"left_knee.x": 0.5})
    q = angles(biped, {"left_knee.x": -1.0})
    assert q[biped.dof_index("left_knee.x")] == -1.0
    assert q[biped.dof_index("right_knee.x")] == biped.rest[biped.dof_index("right_knee.x")]


def test_scenarios_show_what_their_names_say(scenarios):
    p = {name: dict(zip(s.effectors, s.positions[-1])) for name, s in scenarios.items()}
    assert p["kneel"]["pelvis"][2] < 0.6 and p["kneel"]["left_foot"][1] < -0.5  # low, left leg behind
    assert p["one_leg"]["left_foot"][2] > 0.2  # the left foot is off the ground
    assert min(p["reach_up"]["left_hand"][2], p["reach_up"]["right_hand"][2]) > p["reach_up"]["head"][2] + 0.3
    assert p["crouch"]["pelvis"][2] < 0.5 and p["crouch"]["left_foot"][2] == pytest.approx(0.0, abs=1e-3)
    twist = scenarios["twist"]
    head = twist.rotations[-1, twist.effectors.index("head")]
    assert angle_between(head, np.eye(3)) > math.radians(60)


def test_wave_animates_the_right_hand_side_to_side_above_the_shoulder(scenarios):
    wave = scenarios["wave"]
    assert wave.n_frames > 60
    hand = wave.positions[:, wave.effectors.index("right_hand")]
    waving = hand[30:]
    assert waving[:, 2].min() > 1.4
    assert np.ptp(waving[:, 0]) > 0.1
    # The other targets hold still while it waves.
    for e in ("pelvis", "left_hand", "left_foot"):
        assert np.ptp(wave.positions[:, wave.effectors.index(e)], axis=0).max() < 1e-12


def _chain_length(sk, a, b):
    """Sum of the link lengths on the path between frames a and b (an upper bound of their distance)."""
    fa, fb = sk.frame_of(a), sk.frame_of(b)
    common = sk.ancestry[:, fa] & sk.ancestry[:, fb]
    total = 0.0
    for f in (fa, fb):
        while not common[f]:
            total += float(np.linalg.norm(sk.frame_offset[f]))
            f = int(sk.frame_parent[f])
    return total


def test_impossible_targets_are_out_of_reach(scenarios):
    s = scenarios["impossible"]
    assert not s.reachable
    root = s.world_from_root[:3, 3]
    for j, e in enumerate(s.effectors):
        reach = _chain_length(s.skeleton, s.root, e)
        assert np.linalg.norm(s.positions[0, j] - root) > reach + 0.3


def test_scenario_from_angles_reproduces_the_pose(biped):
    q = angles(biped, {"left_elbow.x": 1.0, "waist.z": 0.3})
    s = scenario_from_angles(biped, "test", "a test", q, "left_foot")
    assert s.root == "left_foot"
    T = biped.with_root("left_foot").effector_poses(q, s.world_from_root)
    for j, e in enumerate(s.effectors):
        np.testing.assert_allclose(s.positions[0, j], T[e][:3, 3], atol=1e-12)
    # The root stands where the rest pose puts it.
    np.testing.assert_allclose(s.world_from_root, biped.frame_transforms(biped.rest)[biped.frame_of("left_foot")])


def test_scenario_rejects_bad_arrays(biped):
    s = builtin_scenario(biped, "kneel")
    with pytest.raises(ScenarioError, match="shape"):
        Scenario("bad", "", s.skeleton, s.effectors, s.positions[:, :2], s.rotations, s.world_from_root)
    bad = s.positions.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(ScenarioError, match="finite"):
        Scenario("bad", "", s.skeleton, s.effectors, bad, s.rotations, s.world_from_root)
    with pytest.raises(ScenarioError, match="not an effector"):
        Scenario("bad", "", s.skeleton, ("right_foot",), s.positions[:, :1], s.rotations[:, :1], s.world_from_root)


# -- random poses -----------------------------------------------------------------------------


def test_random_scenarios_are_seeded(biped):
    a, b = random_scenario(biped, 7), random_scenario(biped, 7)
    np.testing.assert_array_equal(a.positions, b.positions)
    assert a.name == "random-7"
    c = random_scenario(biped, 8)
    assert np.abs(c.positions - a.positions).max() > 0.01
    assert [s.name for s in random_scenarios(biped, 3, seed=5)] == ["random-5", "random-6", "random-7"]


def test_random_spread_zero_is_the_rest_pose(biped):
    s = random_scenario(biped, 1, spread=0.0)
    rest = scenario_from_angles(biped, "rest", "", biped.rest)
    np.testing.assert_allclose(s.positions, rest.positions, atol=1e-12)
    with pytest.raises(ScenarioError, match="spread"):
        random_scenario(biped, 1, spread=1.5)


def test_random_poses_settle_and_hold_still(biped):
    reports = run_scenarios(random_scenarios(biped, 6, seed=11), max_frames=300)
    for r in reports:
        assert r.settled and r.finite
        assert r.hold_max_dq <= 1e-9 and r.hold_max_move <= 1e-9
        if r.status is gsik.Status.CONVERGED:
            assert r.max_position_error <= 1e-4 and r.max_orientation_error <= 1e-3
    assert sum(r.status is gsik.Status.CONVERGED for r in reports) >= 5


def test_a_random_pose_can_stall_in_a_local_minimum_that_a_full_solve_escapes(biped):
    """Stepping from the rest pose straight at random-13 stalls 0.4 m off; solve() with restarts converges."""
    s = random_scenario(biped, 13)
    r = run_scenario(s, max_frames=300)
    assert r.settled and r.status is gsik.Status.STALLED and r.max_position_error > 0.1
    assert r.hold_max_dq <= 1e-9
    full = gsik.Solver(s.skeleton, world_from_root=s.world_from_root).solve(s.targets_at(0))
    assert full.status is gsik.Status.CONVERGED


# -- running ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", [n for n in SCENARIO_NAMES if n != "impossible"])
def test_reachable_scenarios_settle_on_their_targets_and_hold_still(reports, name):
    r = reports[name]
    assert r.settled and r.status is gsik.Status.CONVERGED
    assert r.max_position_error <= 1e-4 and r.max_orientation_error <= 1e-3  # the solver's tolerances
    assert r.reach_frames is not None and r.reach_frames <= r.settle_frames
    assert r.hold_frames == 70  # the quiet run (10) and the hold (60)
    assert r.hold_max_dq <= 1e-9 and r.hold_max_move <= 1e-9  # no oscillation, no creep
    assert r.finite


def test_wave_is_tracked_while_it_moves(reports):
    assert 0 < reports["wave"].tracking_error < 0.02


def test_impossible_scenario_reaches_a_stable_best_reach(reports, scenarios):
    r = reports["impossible"]
    assert r.settled and r.status is gsik.Status.STALLED
    assert r.hold_frames >= 60
    assert r.hold_max_dq <= 1e-9 and r.hold_max_move <= 1e-9
    assert r.finite
    # A best reach: about as close as a full solve with restarts gets.
    s = scenarios["impossible"]
    best = gsik.Solver(s.skeleton, world_from_root=s.world_from_root).solve(s.targets_at(0))
    np.testing.assert_allclose(r.position_errors, best.position_errors, atol=0.01)


def test_stability_measure_fires_on_the_plain_method(scenarios):
    """Fixed damping without the safeguard (the paper's plain method) jitters on impossible targets."""
    r = run_scenario(scenarios["impossible"], adaptive_damping=False, max_frames=100, hold_frames=30)
    assert not r.settled
    assert r.hold_max_dq > 0.01 and r.hold_max_move > 0.01


def test_solver_follows_again_after_an_impossible_reach(scenarios, biped):
    s = scenarios["impossible"]
    solver = gsik.Solver(s.skeleton, world_from_root=s.world_from_root)
    solver.set_targets(s.targets_at(0))
    for _ in range(100):
        solver.step()
    back = scenario_from_angles(biped, "rest", "", biped.rest, "right_foot")
    solver.set_targets(back.targets_at(0))
    for _ in range(300):
        result = solver.step()
    assert result.max_position_error < 1e-3


def test_report_motion_holds_every_frame(reports, scenarios):
    r = reports["kneel"]
    m = r.motion
    assert m.n_frames == 1 + r.settle_frames + r.hold_frames  # rest, then every stepped frame
    np.testing.assert_array_equal(m.q[0], scenarios["kneel"].skeleton.rest)
    assert set(m.roots) == {"right_foot"}
    assert r.ms_per_frame > 0


def test_run_scenario_checks_frame_counts(scenarios):
    with pytest.raises(ScenarioError, match="max_frames"):
        run_scenario(scenarios["kneel"], max_frames=0)
    with pytest.raises(gsik.SolverError):
        run_scenario(scenarios["kneel"], sweeps=0)


def test_run_scenario_reports_progress(scenarios):
    seen = []
    run_scenario(scenarios["reach_up"], progress=lambda done, total: seen.append((done, total)))
    assert seen[-1][0] == seen[-1][1] == len(seen)


def test_table_has_a_row_per_scenario(reports):
    text = format_table(list(reports.values()))
    lines = text.splitlines()
    assert lines[0].split()[:3] == ["scenario", "root", "status"]
    assert len(lines) == 2 + len(reports)
    for name, line in zip(SCENARIO_NAMES, lines[2:]):
        assert line.startswith(name)
    assert "stalled" in lines[2 + SCENARIO_NAMES.index("impossible")]


def test_scenario_pose_round_trips_through_the_pose_format(scenarios, reports, biped):
    s = scenarios["one_leg"]
    pose = scenario_pose(s, reports["one_leg"].motion.q[-1])
    read = pose_from_yaml(pose_to_yaml(pose), biped)
    assert read.warnings == ()
    assert read.pose.root == "right_foot"
    assert set(read.pose.targets) == set(s.effectors)
    np.testing.assert_allclose(read.pose.targets["left_foot"].position, s.positions[-1, s.effectors.index("left_foot")])
    np.testing.assert_allclose(read.pose.q(biped), reports["one_leg"].motion.q[-1])
