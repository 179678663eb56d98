"""The bundled humanoid: the biped with wrists, a two-joint spine and clavicles; a turned hand target turns the hand."""

import numpy as np
import pytest

import gsik
from gsik.rotations import angle_between, matrix_from_axis_angle

MIRRORED_AXES = {"y", "z"}  # mirroring left to right (x -> -x) negates rotations about y and z, keeps those about x


@pytest.fixture(scope="module")
def humanoid():
    return gsik.load_skeleton("humanoid")


def test_the_bundled_skeletons_are_the_biped_and_the_humanoid():
    assert gsik.bundled_skeletons() == ("biped", "humanoid")
    assert gsik.load_skeleton("biped").n_dofs == 30  # the paper's biped stays as it was
    with pytest.raises(gsik.SkeletonError, match="bundled: 'biped', 'humanoid'"):
        gsik.load_skeleton("robot")


def test_the_humanoid_has_wrists_a_two_joint_spine_and_clavicles(humanoid):
    sk = humanoid
    dofs = dict(zip(sk.joint_names, sk.joint_dofs))
    assert sk.n_dofs == 43
    assert {j: len(dofs[j]) for j in ("waist", "chest", "left_clavicle", "left_wrist", "right_wrist")} == {
        "waist": 3, "chest": 3, "left_clavicle": 2, "left_wrist": 3, "right_wrist": 3}
    parent = {n: sk.joint_names[p] if p >= 0 else None for n, p in zip(sk.joint_names, sk.joint_parent)}
    assert parent["chest"] == "waist" and parent["neck"] == "chest" and parent["left_clavicle"] == "chest"
    assert parent["left_shoulder"] == "left_clavicle" and parent["left_wrist"] == "left_elbow"
    assert sk.effector_sites == gsik.load_skeleton("biped").effector_sites and sk.root == "right_foot"


def test_the_humanoid_stands_where_the_biped_does_with_its_mass_and_soles(humanoid):
    biped = gsik.load_skeleton("biped")
    mine, theirs = humanoid.effector_poses(humanoid.rest), biped.effector_poses(biped.rest)
    for name in theirs:  # a pose's targets mean the same on both
        np.testing.assert_allclose(mine[name], theirs[name], atol=1e-12)
    assert humanoid.total_mass == pytest.approx(73.0, abs=1e-6)
    assert set(humanoid.soles) == {"left_foot", "right_foot"}
    assert humanoid.segment_mass[list(humanoid.segment_names).index("left_hand")] == pytest.approx(0.445)
    solver = gsik.Solver(humanoid)
    com = solver.center_of_mass()
    assert abs(com[0]) < 1e-9 and 0.9 < com[2] < 1.1  # on the mid-plane, at hip height


def test_the_humanoid_s_limits_are_human_and_mirror_left_to_right(humanoid):
    sk = humanoid
    deg = {n: np.degrees([lo, hi]) for n, lo, hi in zip(sk.dof_names, sk.lower, sk.upper)}
    assert deg["left_wrist.z"] == pytest.approx([-80.2, 80.2], abs=0.1)  # pronation, supination
    assert deg["left_wrist.y"] == pytest.approx([-69.9, 57.3], abs=0.1)  # flexion (towards the thigh), extension
    assert deg["left_wrist.x"] == pytest.approx([-34.4, 20.1], abs=0.1)  # ulnar, radial deviation
    for name in sk.dof_names:
        if not name.startswith("left_"):
            continue
        other = "right_" + name[len("left_"):]
        lo, hi = deg[other]
        expected = (-hi, -lo) if name[-1] in MIRRORED_AXES else (lo, hi)
        assert deg[name] == pytest.approx(expected), name


def _turn_a_hand(skeleton: gsik.Skeleton, degrees: float):
    """Solve with every effector held where it stands and the left hand's target turned about the facing axis.

    Returns (result, solver, world rotations before (n_frames, 3, 3), effector poses before, the hand's target
    rotation (3, 3))."""
    solver = gsik.Solver(skeleton)
    before = solver.effector_poses()
    R0 = solver.world_rotations()
    targets = {n: gsik.Target.from_transform(T) for n, T in before.items()}
    turned = matrix_from_axis_angle(np.array([0.0, 1.0, 0.0]), np.radians(degrees)) @ before["left_hand"][:3, :3]
    targets["left_hand"] = targets["left_hand"].replace(orientation=turned)
    return solver.solve(targets), solver, R0, before, turned


def test_a_hand_target_turned_45_degrees_turns_the_humanoid_s_wrist_not_its_body(humanoid):
    result, solver, R0, before, turned = _turn_a_hand(humanoid, 45.0)
    assert result.converged
    after = solver.effector_poses()
    assert angle_between(after["left_hand"][:3, :3], turned) < np.radians(0.1)
    assert np.linalg.norm(after["left_hand"][:3, 3] - before["left_hand"][:3, 3]) < 1e-3
    assert np.linalg.norm(after["pelvis"][:3, 3] - before["pelvis"][:3, 3]) < 1e-3
    R = solver.world_rotations()
    for frame in ("hips", "waist.z", "chest.z"):  # the pelvis and the chest barely turn
        f = humanoid.frame_of(frame)
        assert angle_between(R[f], R0[f]) < np.radians(3.0), frame
    wrist = [humanoid.dof_index(f"left_wrist.{a}") for a in "zyx"]
    assert np.degrees(np.abs(solver.q[wrist] - humanoid.rest[wrist]).sum()) > 30.0  # the wrist did it


def test_the_biped_without_wrists_turns_its_body_for_the_same_hand_target():
    biped = gsik.load_skeleton("biped")
    result, solver, R0, _, turned = _turn_a_hand(biped, 45.0)
    f = biped.frame_of("waist.z")
    assert angle_between(solver.world_rotations()[f], R0[f]) > np.radians(20.0)  # what the humanoid is for


def test_the_built_in_scenarios_fit_the_humanoid_its_spine_sharing_the_biped_s_waist(humanoid):
    from gsik.anim.scenarios import SCENARIO_NAMES, builtin_scenario

    biped = gsik.load_skeleton("biped")
    assert len({builtin_scenario(humanoid, n).name for n in SCENARIO_NAMES}) == len(SCENARIO_NAMES)
    twist, biped_twist = builtin_scenario(humanoid, "twist"), builtin_scenario(biped, "twist")
    # The same targets on both: the humanoid's waist and chest turn together as far as the biped's waist.
    np.testing.assert_allclose(twist.positions, biped_twist.positions, atol=1e-9)
    np.testing.assert_allclose(twist.rotations, biped_twist.rotations, atol=1e-9)
