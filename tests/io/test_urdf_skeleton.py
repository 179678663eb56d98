"""Tests for gsik.io.urdf_skeleton: URDF robots as gsik skeletons."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import gsik
from gsik.errors import UrdfError
from gsik.rotations import matrix_from_axis_angle
from gsik.io.urdf import matrix_from_rpy, parse_urdf, read_urdf
from gsik.io.urdf_skeleton import link_site_names, skeleton_from_urdf

DATA = Path(__file__).resolve().parents[1] / "data"
ROBOTS = ["humanoid.urdf", "two_link_arm.urdf"]


def direct_link_transforms(robot, angles: dict[str, float]) -> dict[str, np.ndarray]:
    """World transform of every link, composing ``origin @ rot(axis, q)`` from the root link (at the origin)."""
    out = {robot.root_link: np.eye(4)}
    for j in robot.joints_in_tree_order():
        origin = np.eye(4)
        origin[:3, :3] = matrix_from_rpy(j.origin_rpy)
        origin[:3, 3] = j.origin_xyz
        motion = np.eye(4)
        if j.type != "fixed":
            motion[:3, :3] = matrix_from_axis_angle(j.axis, angles[j.name])
        out[j.child] = out[j.parent] @ origin @ motion
    return out


@pytest.mark.parametrize("fixture", ROBOTS)
def test_forward_kinematics_matches_direct_composition_of_the_urdf(fixture, rng):
    robot = read_urdf(DATA / fixture)
    sk = skeleton_from_urdf(robot)
    site = link_site_names(robot)
    for _ in range(20):
        q = rng.uniform(sk.lower, sk.upper)
        angles = {name.removesuffix(".q"): value for name, value in zip(sk.dof_names, q)}
        expected = direct_link_transforms(robot, angles)
        T = sk.frame_transforms(q)
        for link, T_link in expected.items():
            np.testing.assert_allclose(T[sk.frame_of(site[link])], T_link, atol=1e-12)


def test_joints_are_named_after_urdf_joints_and_sites_after_links():
    robot = read_urdf(DATA / "humanoid.urdf")
    sk = skeleton_from_urdf(robot)
    assert sk.joint_names[0] == "pelvis_root"
    assert set(sk.joint_names[1:]) == {j.name for j in robot.joints}
    assert set(sk.site_names) == set(robot.links)
    movable = {j.name for j in robot.joints if j.type in ("revolute", "continuous")}
    assert set(sk.dof_names) == {f"{n}.q" for n in movable}
    assert sk.joint_dofs[sk.joint_names.index("camera_mount")] == ()
    assert sk.root == "pelvis"
    assert set(sk.effector_sites) == {"head_camera", "l_hand", "r_lower_arm", "l_foot", "r_shin"}


def test_limits_follow_the_urdf_and_continuous_joints_turn_through_pi():
    robot = read_urdf(DATA / "humanoid.urdf")
    sk = skeleton_from_urdf(robot)
    d = sk.dof_index("l_elbow.q")
    assert (sk.lower[d], sk.upper[d]) == (0.0, 2.5)
    d = sk.dof_index("neck.q")
    assert (sk.lower[d], sk.upper[d]) == (-2 * math.pi, 2 * math.pi)
    np.testing.assert_allclose(sk.frame_axis[sk.dof_frame[d]], [0, 0, 1])  # the file's "0 0 2", normalised
    assert np.all((sk.lower <= sk.rest) & (sk.rest <= sk.upper))
    narrow = skeleton_from_urdf(robot, continuous_limit=math.pi)
    assert narrow.upper[narrow.dof_index("neck.q")] == math.pi
    with pytest.raises(UrdfError, match="continuous_limit must be a positive angle"):
        skeleton_from_urdf(robot, continuous_limit=0.0)


def test_path_and_parsed_robot_give_the_same_skeleton():
    a = skeleton_from_urdf(DATA / "two_link_arm.urdf")
    b = skeleton_from_urdf(str(DATA / "two_link_arm.urdf"))
    c = skeleton_from_urdf(read_urdf(DATA / "two_link_arm.urdf"))
    for other in (b, c):
        assert other.frame_names == a.frame_names
        np.testing.assert_array_equal(other.frame_offset, a.frame_offset)
    assert a.effector_sites == ("tool",) and a.root == "base"
    # Two links of 0.5 m and 0.4 m along x, turned about z.
    T = a.frame_transforms(np.array([math.pi / 2, 0.0]))
    np.testing.assert_allclose(T[a.frame_of("tool"), :3, 3], [0.0, 0.9, 0.1], atol=1e-12)


def test_links_are_effectors_and_roots_by_their_names():
    sk = skeleton_from_urdf(DATA / "humanoid.urdf", effectors=["l_hand", "head", "r_shin"], root="l_foot")
    assert sk.effector_sites == ("l_hand", "head", "r_shin")
    assert sk.root == "l_foot"
    assert skeleton_from_urdf(DATA / "humanoid.urdf", root="waist").root == "waist"  # a joint works too
    with pytest.raises(UrdfError, match="no link 'hand' to use as an effector; links: 'pelvis', 'torso'"):
        skeleton_from_urdf(DATA / "humanoid.urdf", effectors=["hand"])
    with pytest.raises(UrdfError, match="no link 'base' to use as root"):
        skeleton_from_urdf(DATA / "humanoid.urdf", root="base")
    with pytest.raises(UrdfError, match="listed twice"):
        skeleton_from_urdf(DATA / "humanoid.urdf", effectors=["l_hand", "l_hand"])


ARM = """<robot name="arm">
  <link name="base"/><link name="{link}"/><link name="tip"/>
  <joint name="shoulder" type="{kind}">
    <parent link="base"/><child link="{link}"/>
    <origin xyz="0 0 0.2" rpy="0 0.5 0"/><axis xyz="0 1 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <joint name="wrist" type="fixed">
    <parent link="{link}"/><child link="tip"/><origin xyz="0.3 0 0"/>
  </joint>
</robot>"""


def test_prismatic_joints_are_rejected_by_name():
    robot = parse_urdf(ARM.format(link="upper", kind="prismatic"))
    with pytest.raises(UrdfError, match="prismatic joint 'shoulder' is not supported"):
        skeleton_from_urdf(robot)


def test_a_link_named_like_a_joint_gets_a_link_suffix():
    robot = parse_urdf(ARM.format(link="shoulder", kind="revolute"))
    sk = skeleton_from_urdf(robot)
    assert "shoulder" in sk.joint_names and "shoulder_link" in sk.site_names
    assert skeleton_from_urdf(robot, effectors=["shoulder"]).effector_sites == ("shoulder_link",)


def test_oblique_axes_and_rpy_origins_pose_as_the_urdf_says(rng):
    robot = parse_urdf(ARM.format(link="upper", kind="revolute"))
    sk = skeleton_from_urdf(robot)
    for angle in rng.uniform(-1, 1, 5):
        expected = direct_link_transforms(robot, {"shoulder": angle})["tip"]
        np.testing.assert_allclose(sk.frame_transforms(np.array([angle]))[sk.frame_of("tip")], expected, atol=1e-12)


def test_the_solver_poses_a_urdf_humanoid(rng):
    sk = skeleton_from_urdf(DATA / "humanoid.urdf", effectors=["l_hand", "l_foot"], root="pelvis")
    q_goal = np.clip(sk.rest + rng.uniform(-0.3, 0.3, sk.n_dofs), sk.lower, sk.upper)
    T = sk.frame_transforms(q_goal)
    solver = gsik.Solver(sk)
    result = solver.solve({n: gsik.Target(T[sk.frame_of(n), :3, 3]) for n in ("l_hand", "l_foot")})
    assert result.converged
    assert result.max_position_error < 1e-4
