"""Tests for gsik.io.bvh_skeleton: Euler angles and the BVH export of poses and motions (import: test_bvh_import.py)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from bvh_skeleton_cases import (
    DATA,
    ORDERS,
    max_position_difference,
    one_joint_clip,
    round_trip,
    smooth_motion,
)

import gsik
from gsik.anim.motion import Motion
from gsik.errors import BvhError
from gsik.io.bvh import bvh_forward_kinematics, format_bvh, read_bvh
from gsik.io.bvh_skeleton import (
    EULER_ORDER,
    Z_UP_TO_Y_UP,
    euler_from_matrix,
    import_bvh,
    matrix_from_euler,
    motion_to_bvh,
    pose_to_bvh,
    write_motion_bvh,
)
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.rotations import matrix_from_rotvec

# ---------------------------------------------------------------------------
# Euler angles
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("order", ORDERS)
def test_euler_from_matrix_inverts_matrix_from_euler_for_every_order(order, rng):
    angles = np.c_[rng.uniform(-np.pi, np.pi, 200), rng.uniform(-1.5, 1.5, 200), rng.uniform(-np.pi, np.pi, 200)]
    R = matrix_from_euler(angles, order)
    back = euler_from_matrix(R, order)
    np.testing.assert_allclose(back, angles, atol=1e-9)
    np.testing.assert_allclose(matrix_from_euler(back, order), R, atol=1e-12)


@pytest.mark.parametrize("order", ORDERS)
def test_euler_from_matrix_reproduces_the_matrix_at_gimbal_lock(order, rng):
    for middle in (np.pi / 2, -np.pi / 2):
        angles = np.c_[rng.uniform(-3, 3, 20), np.full(20, middle), rng.uniform(-3, 3, 20)]
        R = matrix_from_euler(angles, order)
        np.testing.assert_allclose(matrix_from_euler(euler_from_matrix(R, order), order), R, atol=1e-9)


@pytest.mark.parametrize("order", ORDERS)
def test_matrix_from_euler_means_what_bvh_channels_mean(order, rng):
    degrees = rng.uniform(-170, 170, (5, 9))
    clip = one_joint_clip(order, degrees)
    local = gsik.io.bvh.bvh_local_rotations(clip)
    np.testing.assert_allclose(matrix_from_euler(np.radians(degrees[:, 0:3]), order), local[:, 0], atol=1e-12)


def test_euler_order_must_be_three_distinct_axes():
    with pytest.raises(BvhError, match="three distinct axes"):
        matrix_from_euler(np.zeros(3), "xxy")


# ---------------------------------------------------------------------------
# Export
# ---------------------------------------------------------------------------


def test_export_of_the_biped_is_rooted_at_hips_with_exact_channels(biped):
    clip = pose_to_bvh(biped, biped.rest)
    assert clip.joints[0].name == "hips"
    assert clip.joints[0].channels == ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    assert np.array_equal(clip.joints[0].offset, [0.0, 0.0, 0.0])
    by_name = {j.name: j for j in clip.joints}
    assert by_name["left_hip"].channels == ("Xrotation", "Yrotation", "Zrotation")
    # Knees and the atlas get three rotation channels (Blender needs 0 or 3), the added ones locked at 0 ...
    assert by_name["left_knee"].channels == ("Xrotation", "Yrotation", "Zrotation")
    assert by_name["atlas"].channels == ("Xrotation", "Yrotation", "Zrotation")
    knee = clip.channel_index("left_knee")
    assert np.array_equal(clip.motion[:, knee][:, 1:], np.zeros((1, 2)))
    # ... or only their own with pad_rotations=False.
    exact = {j.name: j for j in pose_to_bvh(biped, biped.rest, pad_rotations=False).joints}
    assert exact["left_knee"].channels == ("Xrotation",)
    assert exact["atlas"].channels == ("Xrotation", "Yrotation")
    np.testing.assert_allclose(by_name["left_knee"].offset, [0.0, 0.0, -42.0])  # centimetres by default
    # The root channels carry the top joint's world pose: where the definition stands it by default...
    np.testing.assert_allclose(clip.motion[0, :6], [0.0, 0.0, 97.97, 0.0, 0.0, 0.0], atol=1e-9)
    # ... or where world_from_root pins the root.
    W = np.eye(4)
    W[:3, :3] = matrix_from_rotvec([0.0, 0.0, 0.5])
    W[:3, 3] = [1.0, 2.0, 0.0]
    moved = pose_to_bvh(biped, biped.rest, W, root="hips", units="m")
    np.testing.assert_allclose(moved.motion[0, :6], [1.0, 2.0, 0.0, math.degrees(0.5), 0.0, 0.0], atol=1e-9)
    # The knee's channel is its angle in degrees, exactly.
    col = clip.channel_index("left_knee").start
    assert clip.motion[0, col] == pytest.approx(math.degrees(biped.rest[biped.dof_index("left_knee.x")]))


def test_export_writes_sites_as_named_zero_channel_joints_with_an_end_site(biped):
    clip = pose_to_bvh(biped, biped.rest)
    by_name = {j.name: (i, j) for i, j in enumerate(clip.joints)}
    for site in biped.site_names:
        i, joint = by_name[site]
        assert joint.channels == ()
        (child,) = clip.children(i)
        assert clip.joints[child].is_end_site and not np.any(clip.joints[child].offset)
    assert clip.joints[by_name["left_hand"][1].parent].name == "left_elbow"


def test_export_with_y_up_stands_the_rest_pose_along_y(biped):
    z_clip = pose_to_bvh(biped, biped.rest, units="m", up="z")
    y_clip = pose_to_bvh(biped, biped.rest, units="m", up="y")
    z_pos = bvh_forward_kinematics(z_clip)[1][0]
    y_pos = bvh_forward_kinematics(y_clip)[1][0]
    np.testing.assert_allclose(y_pos, z_pos @ Z_UP_TO_Y_UP.T, atol=1e-12)
    head, foot = z_clip.joint_index("head_top"), z_clip.joint_index("left_foot")
    assert y_pos[head, 1] - y_pos[foot, 1] > 1.5
    assert y_clip.joints[0].channels[3:] == ("Yrotation", "Xrotation", "Zrotation")
    # gsik x, y, z rotations become Xrotation, Zrotation (negated) and Yrotation.
    assert {j.name: j for j in y_clip.joints}["left_hip"].channels == ("Xrotation", "Zrotation", "Yrotation")


def test_export_of_a_motion_whose_root_alternates_keeps_one_hierarchy_and_carries_the_travel(biped):
    roots = [("right_foot", "left_foot")[(f // 10) % 2] for f in range(40)]
    motion = smooth_motion(biped, 40, seed=3, roots=roots)
    clip = motion_to_bvh(motion, units="m")
    assert clip.joints[0].name == "hips" and clip.n_frames == 40
    hips = biped.frame_of("hips")
    expected = motion.positions()[:, hips]
    np.testing.assert_allclose(clip.motion[:, 0:3], expected, atol=1e-12)
    assert clip.motion[-1, 0] - clip.motion[0, 0] > 0.5  # the hips travel along x


@pytest.mark.parametrize("units", ["cm", "m"])
@pytest.mark.parametrize("up", ["z", "y"])
def test_round_trip_reproduces_every_joint_and_site_of_the_biped(biped, rng, units, up):
    names = biped.joint_names + biped.site_names
    # Rest pose.
    rest = Motion(biped, biped.rest[None], ("right_foot",), biped.frame_transforms(biped.rest)[
        biped.frame_of("right_foot")][None], 1 / 30)
    assert max_position_difference(rest, round_trip(rest, units, up).motion, names) < 1e-6
    # Random poses anywhere in the limits, each with its own root and place.
    n = 12
    q = rng.uniform(biped.lower, biped.upper, (n, biped.n_dofs))
    roots = rng.choice(["right_foot", "left_foot", "hips", "head", "left_hand"], n)
    W = np.tile(np.eye(4), (n, 1, 1))
    W[:, :3, :3] = [matrix_from_rotvec(v) for v in rng.normal(size=(n, 3))]
    W[:, :3, 3] = rng.normal(size=(n, 3))
    poses = Motion(biped, q, tuple(roots), W, 1 / 30)
    assert max_position_difference(poses, round_trip(poses, units, up).motion, names) < 1e-6
    # A smooth motion whose root alternates between the feet.
    roots = [("right_foot", "left_foot")[(f // 8) % 2] for f in range(32)]
    walk = smooth_motion(biped, 32, seed=7, roots=roots)
    imported = round_trip(walk, units, up)
    assert max_position_difference(walk, imported.motion, names) < 1e-6
    assert imported.scale == (0.01 if units == "cm" else 1.0)
    assert imported.up == up


def test_round_trip_keeps_the_biped_structure(biped):
    padded = round_trip(smooth_motion(biped, 5, seed=1), "cm", "z")
    # The locked channels of knees, elbows and atlas come back as DOFs that stay 0.
    extra = sorted(set(padded.skeleton.dof_names) - set(biped.dof_names))
    assert extra == sorted(f"{j}.{a}" for j, a in [("atlas", "z"), *((f"{s}_{j}", a) for s in ("left", "right")
                                                    for j in ("elbow", "knee") for a in "yz")])
    assert not np.any(padded.motion.q[:, [padded.skeleton.dof_index(n) for n in extra]])
    imported = round_trip(smooth_motion(biped, 5, seed=1), "cm", "z", pad_rotations=False).skeleton
    assert set(imported.joint_names) == set(biped.joint_names)
    assert set(imported.site_names) == set(biped.site_names)
    assert sorted(imported.dof_names) == sorted(biped.dof_names)
    for j, name in enumerate(biped.joint_names[1:], start=1):
        k = imported.joint_names.index(name)
        assert len(imported.joint_dofs[k]) == len(biped.joint_dofs[j])
        f_a = biped.dof_frame[biped.joint_dofs[j][0]] if biped.joint_dofs[j] else biped.joint_frame[j]
        f_b = imported.dof_frame[imported.joint_dofs[k][0]] if imported.joint_dofs[k] else imported.joint_frame[k]
        np.testing.assert_allclose(imported.frame_offset[f_b], biped.frame_offset[f_a], atol=1e-12)
    for d, name in enumerate(biped.dof_names):
        e = imported.dof_index(name)
        np.testing.assert_allclose(imported.frame_axis[imported.dof_frame[e]], biped.frame_axis[biped.dof_frame[d]])
    assert imported.effector_sites[0] == "pelvis"
    assert set(biped.effector_sites) <= set(imported.effector_sites)


def test_round_trip_of_joints_with_fixed_orientations_decomposes_them(rng):
    robot = skeleton_from_urdf(DATA / "humanoid.urdf")
    clip = pose_to_bvh(robot, robot.rest)
    oriented = {j.name: j for j in clip.joints}["l_shoulder"]  # rpy 0.3 0 0, axis x
    assert oriented.channels == tuple(a.upper() + "rotation" for a in EULER_ORDER["z"])
    names = robot.joint_names + robot.site_names
    q = rng.uniform(robot.lower, robot.upper, (10, robot.n_dofs))
    W = np.tile(np.eye(4), (10, 1, 1))
    W[:, :3, 3] = rng.normal(size=(10, 3))
    motion = Motion(robot, q, (robot.root,) * 10, W, 0.02)
    for units, up in itertools.product(("cm", "m"), ("z", "y")):
        assert max_position_difference(motion, round_trip(motion, units, up, up=up).motion, names) < 1e-6


def test_export_unwraps_decomposed_angles_over_the_frames():
    joints = [gsik.JointSpec("base", None, (0, 0, 0)),
              gsik.JointSpec("spin", "base", (0, 0, 0.1), (gsik.RotationSpec((0, 0, 1), -10, 10, 0, "z"),),
                             orientation=matrix_from_rotvec([0.2, 0.0, 0.0]))]
    sk = gsik.build_skeleton("spinner", joints, [gsik.SiteSpec("tip", "spin", (0.1, 0, 0))], effectors=["tip"])
    q = np.linspace(0, 3 * np.pi, 60)[:, None]
    motion = Motion(sk, q, ("base",) * 60, np.tile(np.eye(4), (60, 1, 1)), 0.02)
    clip = motion_to_bvh(motion, units="m")
    angles = clip.motion[:, clip.channel_index("spin")]
    assert np.abs(np.diff(angles, axis=0)).max() < 10.0  # no 360-degree jumps
    assert max_position_difference(motion, import_bvh(clip).motion, ["tip"]) < 1e-9


def test_write_motion_bvh_writes_a_file_read_bvh_reads_back(biped, tmp_path):
    motion = smooth_motion(biped, 6, seed=2)
    for units in ("cm", "m"):
        path = tmp_path / f"walk_{units}.bvh"
        write_motion_bvh(path, motion, units=units, up="y")
        imported = import_bvh(read_bvh(path))
        assert max_position_difference(motion, imported.motion, biped.joint_names) < 1e-6
        assert imported.motion.frame_time == pytest.approx(1 / 30)


def test_export_replaces_characters_bvh_names_cannot_hold():
    joints = [gsik.JointSpec("base link", None, (0, 0, 0)),
              gsik.JointSpec("arm{1}", "base link", (0, 0, 0.1), (gsik.RotationSpec((1, 0, 0), -1, 1),))]
    sk = gsik.build_skeleton("odd", joints, [gsik.SiteSpec("tool tip", "arm{1}", (0, 0, 0.2))])
    clip = pose_to_bvh(sk, [0.0])
    assert [j.name for j in clip.joints if not j.is_end_site] == ["base_link", "arm_1_", "tool_tip"]
    clash = [gsik.JointSpec("a b", None, (0, 0, 0)), gsik.JointSpec("a_b", "a b", (0, 0, 0.1))]
    with pytest.raises(BvhError, match="both become 'a_b'"):
        pose_to_bvh(gsik.build_skeleton("clash", clash), [])


def test_export_rejects_bad_units_up_and_empty_motions(biped):
    with pytest.raises(BvhError, match="unknown units 'mm'; expected one of 'cm', 'm'"):
        pose_to_bvh(biped, biped.rest, units="mm")
    with pytest.raises(BvhError, match="unknown up axis 'x'"):
        pose_to_bvh(biped, biped.rest, up="x")
    empty = Motion(biped, np.zeros((0, biped.n_dofs)), (), np.zeros((0, 4, 4)), 0.1)
    with pytest.raises(BvhError, match="no frames"):
        motion_to_bvh(empty)


def test_third_party_bvh_reader_parses_our_export(biped):
    bvh = pytest.importorskip("bvh")
    motion = smooth_motion(biped, 4, seed=5)
    clip = motion_to_bvh(motion, units="cm", up="y")
    mocap = bvh.Bvh(format_bvh(clip))
    names = [j.name for j in clip.joints if not j.is_end_site]
    assert mocap.get_joints_names() == names
    assert mocap.nframes == 4
    assert mocap.frame_time == pytest.approx(1 / 30)
    for i, joint in enumerate(clip.joints):
        if joint.is_end_site:
            continue
        assert mocap.joint_offset(joint.name) == pytest.approx(tuple(joint.offset), abs=1e-6)
        assert tuple(mocap.joint_channels(joint.name)) == joint.channels
        if joint.parent >= 0:
            assert mocap.joint_parent(joint.name).name == clip.joints[joint.parent].name
        if joint.channels:
            values = mocap.frames_joint_channels(joint.name, list(joint.channels))
            np.testing.assert_allclose(values, clip.motion[:, clip.channel_index(i)], atol=1e-6)
    assert len(mocap.search("End", "Site")) == sum(j.is_end_site for j in clip.joints)
