"""Tests for gsik.io.bvh_skeleton: BVH export of poses and motions, import of clips as skeletons."""

from __future__ import annotations

import itertools
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import gsik
from gsik.io.bvh import BvhClip, BvhJoint, bvh_forward_kinematics, format_bvh, parse_bvh, read_bvh
from gsik.io.bvh_skeleton import (
    EULER_ORDER,
    Z_UP_TO_Y_UP,
    BvhImportWarning,
    clip_with_motion,
    detect_scale,
    detect_up,
    detect_up_reason,
    euler_from_matrix,
    import_bvh,
    matrix_from_euler,
    motion_to_bvh,
    pose_to_bvh,
    skeleton_from_bvh,
    write_motion_bvh,
)
from gsik.errors import BvhError
from gsik.anim.motion import Motion
from gsik.rotations import matrix_from_rotvec
from gsik.io.urdf_skeleton import skeleton_from_urdf

DATA = Path(__file__).resolve().parents[1] / "data"
FIXTURES = sorted(p.name for p in DATA.glob("*.bvh"))
ORDERS = ["".join(p) for p in itertools.permutations("xyz")]
PRECISION = {"cm": 6, "m": 8}


# ---------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------


def smooth_motion(sk: gsik.Skeleton, n_frames: int, seed: int, roots=None) -> Motion:
    """Sinusoidal angles within the limits, the hips travelling along x; ``roots`` (a per-frame list) re-pins them."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames) / 30.0
    half = 0.5 * (sk.upper - sk.lower)
    phase = rng.uniform(0.0, 2.0 * np.pi, sk.n_dofs)
    freq = rng.uniform(0.1, 0.4, sk.n_dofs)
    q = np.clip(sk.rest + 0.4 * half * np.sin(2.0 * np.pi * freq * t[:, None] + phase), sk.lower, sk.upper)
    top = sk.joint_names[0]
    W = np.tile(np.eye(4), (n_frames, 1, 1))
    W[:, :3, :3] = [matrix_from_rotvec([0.0, 0.0, 0.8 * s]) for s in np.sin(t)]
    W[:, :3, 3] = np.c_[0.6 * t, 0.1 * np.sin(t), 0.95 + 0.02 * np.cos(3 * t)]
    if roots is None:
        return Motion(sk, q, (top,) * n_frames, W, 1.0 / 30.0)
    # Re-pin each frame at its own root, where the top-pinned pose puts it.
    W_root = np.empty_like(W)
    for f in range(n_frames):
        R, p = gsik.kinematics.world_frames(sk, q[f], W[f], top)
        i = sk.frame_of(roots[f])
        W_root[f] = np.eye(4)
        W_root[f, :3, :3] = R[i]
        W_root[f, :3, 3] = p[i]
    return Motion(sk, q, tuple(roots), W_root, 1.0 / 30.0)


def round_trip(motion: Motion, file_units: str, file_up: str, pad_rotations: bool = True, **import_options):
    clip = motion_to_bvh(motion, units=file_units, up=file_up, pad_rotations=pad_rotations)
    text = format_bvh(clip, PRECISION[file_units])
    return import_bvh(parse_bvh(text), **import_options)


def max_position_difference(original: Motion, imported: Motion, names) -> float:
    a = original.positions()
    b = imported.positions()
    fa = [original.skeleton.frame_of(n) for n in names]
    fb = [imported.skeleton.frame_of(n) for n in names]
    return float(np.abs(a[:, fa] - b[:, fb]).max())


def clip_world_positions(clip: BvhClip, scale: float, up: str) -> np.ndarray:
    """The clip's own FK positions in gsik's world [m]."""
    M = Z_UP_TO_Y_UP.T if up == "y" else np.eye(3)
    return scale * bvh_forward_kinematics(clip)[1] @ M.T


def one_joint_clip(order: str, angles_deg: np.ndarray) -> BvhClip:
    """ROOT + one 3-channel JOINT with rotation channels in ``order`` + End Site."""
    channels = tuple(a.upper() + "rotation" for a in order)
    joints = (
        BvhJoint("Hips", -1, (0.0, 0.0, 0.0), ("Xposition", "Yposition", "Zposition") + channels),
        BvhJoint("Arm", 0, (0.3, 0.1, 0.0), channels),
        BvhJoint("Forearm", 1, (0.0, 0.0, 0.4), channels),
        BvhJoint("Forearm_end", 2, (0.25, 0.05, -0.1), is_end_site=True),
    )
    n = angles_deg.shape[0]
    roots = np.c_[np.linspace(0, 1, n), np.zeros(n), np.full(n, 0.9)]
    return BvhClip(joints, 0.04, np.c_[roots, angles_deg])


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


# ---------------------------------------------------------------------------
# Import
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("fixture", FIXTURES)
def test_import_reproduces_the_files_own_forward_kinematics(fixture):
    clip = read_bvh(DATA / fixture)
    result = import_bvh(clip)
    expected = clip_world_positions(clip, result.scale, result.up)
    got = result.motion.positions()
    frames = [result.skeleton.frame_of(j.name) for j in clip.joints]
    exact = 1 if result.warnings else clip.n_frames  # sliding joints: only the first frame is exact
    np.testing.assert_allclose(got[:exact, frames], expected[:exact], atol=1e-6)


def test_import_warns_about_position_channels_that_change():
    clip = read_bvh(DATA / "six_channel.bvh")
    result = import_bvh(clip)
    assert len(result.warnings) == 3
    assert all("position channels change" in w for w in result.warnings)
    assert {w.split("'")[1] for w in result.warnings} == {"spine", "head", "leg"}
    with pytest.warns(BvhImportWarning, match="joint '(spine|head|leg)'"):
        skeleton_from_bvh(clip)


def test_import_of_a_clip_without_warnings_emits_none():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        skeleton, motion = skeleton_from_bvh(read_bvh(DATA / "walk_zxy.bvh"))
    assert motion.n_frames == 4 and skeleton.n_dofs == 33


@pytest.mark.parametrize("order", ["zxy", "zyx", "xyz", "yxz", "yzx", "xzy"])
def test_import_keeps_each_channel_order_and_reproduces_its_forward_kinematics(order, rng):
    degrees = rng.uniform(-179, 179, (6, 9))
    clip = parse_bvh(format_bvh(one_joint_clip(order, degrees), 9))
    result = import_bvh(clip, up="z", scale=1.0)
    sk = result.skeleton
    arm = sk.joint_names.index("Arm")
    assert [sk.dof_names[d] for d in sk.joint_dofs[arm]] == [f"Arm.{a}" for a in order]
    axes = [sk.frame_axis[sk.dof_frame[d]] for d in sk.joint_dofs[arm]]
    np.testing.assert_array_equal(axes, [np.eye(3)["xyz".index(a)] for a in order])
    got = result.motion.positions()[:, [sk.frame_of(j.name) for j in clip.joints]]
    np.testing.assert_allclose(got, clip_world_positions(clip, 1.0, "z"), atol=1e-9)
    # The angles are the file's, unwrapped: equal up to whole turns.
    turns = (result.motion.q[:, sk.dof_index(f"Arm.{order[0]}")] - np.radians(degrees[:, 3])) / (2 * np.pi)
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-12)


def test_import_of_a_y_up_file_turns_it_to_z_up():
    clip = read_bvh(DATA / "walk_zxy.bvh")
    assert detect_up(clip) == "y"
    result = import_bvh(clip)
    sk = result.skeleton
    p = result.motion.positions()[0]
    assert p[sk.frame_of("Head_end"), 2] - p[sk.frame_of("LeftLeg_end"), 2] > 1.5
    # Yrotation turns about gsik's z, Zrotation about -y.
    spine = sk.joint_names.index("Spine")
    axes = {sk.dof_names[d]: sk.frame_axis[sk.dof_frame[d]] for d in sk.joint_dofs[spine]}
    np.testing.assert_allclose(axes["Spine.y"], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(axes["Spine.z"], [0, -1, 0], atol=1e-15)
    as_z = import_bvh(clip, up="z")
    assert as_z.up == "z"
    np.testing.assert_allclose(as_z.motion.positions()[0] @ Z_UP_TO_Y_UP, p, atol=1e-12)


def test_import_detects_centimetres_or_takes_the_given_scale():
    cm = read_bvh(DATA / "cm_scale.bvh")
    assert detect_scale(cm) == 0.01
    assert detect_scale(read_bvh(DATA / "walk_zxy.bvh")) == 1.0
    assert detect_scale(parse_bvh(format_bvh(pose_to_bvh(gsik.load_skeleton("biped"),
                                                          gsik.load_skeleton("biped").rest)).replace(
        "OFFSET 0.000000 0.000000 -42.000000", "OFFSET 0.000000 0.000000 -4200.000000"))) == 0.001
    default = import_bvh(cm)
    inches = import_bvh(cm, scale=0.0254)
    assert default.scale == 0.01 and inches.scale == 0.0254
    np.testing.assert_allclose(inches.motion.positions(), default.motion.positions() * 2.54, atol=1e-12)
    with pytest.raises(BvhError, match="scale must be a positive number"):
        import_bvh(cm, scale=0.0)


def test_import_keeps_namespaced_names_or_strips_them():
    clip = read_bvh(DATA / "mixamo_zyx_crlf.bvh")
    kept = import_bvh(clip).skeleton
    assert kept.joint_names[0] == "mixamorig:Hips"
    assert "mixamorig:Spine.z" in kept.dof_names
    stripped = import_bvh(clip, strip_namespace=True)
    assert stripped.skeleton.joint_names[0] == "Hips"
    assert "Spine.z" in stripped.skeleton.dof_names
    np.testing.assert_allclose(stripped.motion.positions(), import_bvh(clip).motion.positions())
    clash = BvhClip((BvhJoint("a:Hips", -1, (0, 0, 0), ("Xrotation",)), BvhJoint("b:Hips", 0, (0, 1, 0), ())),
                    0.1, np.zeros((1, 1)))
    with pytest.raises(BvhError, match="'a:Hips' and 'b:Hips' are both 'Hips'"):
        import_bvh(clash, strip_namespace=True)


def test_import_makes_zero_channel_joints_with_children_fixed_joints():
    sk = import_bvh(read_bvh(DATA / "cm_scale.bvh")).skeleton
    j = sk.joint_names.index("LHipJoint")
    assert sk.joint_dofs[j] == ()
    assert sk.joint_names[sk.joint_parent[sk.joint_names.index("LeftUpLeg")]] == "LHipJoint"


def test_import_limits_contain_every_frame(rng):
    degrees = rng.uniform(-60, 60, (8, 9))
    degrees[:, 5] = np.linspace(0.0, 250.0, 8)  # beyond half a turn, continuously
    clip = one_joint_clip("zxy", degrees)
    wide = import_bvh(clip, up="z").skeleton
    d = wide.dof_index("Arm.y")
    # Past half a turn: half a turn of room beyond the clip's range on both sides.
    assert wide.lower[d] == pytest.approx(-np.pi) and wide.upper[d] == pytest.approx(np.radians(250.0 + 180.0))
    assert wide.lower[wide.dof_index("Arm.z")] == -np.pi and wide.upper[wide.dof_index("Arm.z")] == np.pi
    tight = import_bvh(clip, up="z", limits="from_motion", margin=0.1)
    sk, q = tight.skeleton, tight.motion.q
    np.testing.assert_allclose(sk.lower, q.min(axis=0) - 0.1)
    np.testing.assert_allclose(sk.upper, q.max(axis=0) + 0.1)
    assert np.all((sk.lower <= sk.rest) & (sk.rest <= sk.upper))
    gsik.Solver(sk, q0=q[3])  # every frame is a valid starting pose
    with pytest.raises(BvhError, match="unknown limits 'tight'; expected one of 'wide', 'from_motion'"):
        import_bvh(clip, limits="tight")


def test_import_default_effectors_are_the_sites_and_the_pelvis():
    result = import_bvh(read_bvh(DATA / "walk_zxy.bvh"))
    sk = result.skeleton
    assert result.effectors == ("Hips_site", "Head_end", "LeftForeArm_end", "RightForeArm_end", "LeftLeg_end",
                                "RightLeg_end")
    assert sk.effector_sites == result.effectors
    assert sk.root == "Hips"
    p = result.motion.positions()
    np.testing.assert_allclose(p[:, sk.frame_of("Hips_site")], p[:, sk.frame_of("Hips")])


def test_import_makes_a_site_for_each_joint_chosen_as_effector():
    result = import_bvh(read_bvh(DATA / "walk_zxy.bvh"), effectors=["LeftForeArm", "Head_end"], root="RightLeg_end")
    sk = result.skeleton
    assert result.effectors == ("LeftForeArm_site", "Head_end")
    assert sk.root == "RightLeg_end"
    assert sk.effector_names == ("LeftForeArm_site", "Head_end")
    p = result.motion.positions()
    np.testing.assert_allclose(p[:, sk.frame_of("LeftForeArm_site")], p[:, sk.frame_of("LeftForeArm")])
    with pytest.raises(BvhError, match="no joint or site 'LeftHand' to use as an effector; joints: 'Hips'"):
        import_bvh(read_bvh(DATA / "walk_zxy.bvh"), effectors=["LeftHand"])
    with pytest.raises(BvhError, match="no joint or site 'Pelvis' to use as the root"):
        import_bvh(read_bvh(DATA / "walk_zxy.bvh"), root="Pelvis")


def test_import_rejects_what_is_not_a_clip():
    with pytest.raises(BvhError, match="needs a gsik.io.bvh.BvhClip"):
        import_bvh("walk.bvh")
    with pytest.raises(BvhError, match="unknown up axis 'x'"):
        import_bvh(read_bvh(DATA / "walk_zxy.bvh"), up="x")


def test_imported_clip_with_no_frames_gives_an_empty_motion():
    clip = parse_bvh(format_bvh(one_joint_clip("zxy", np.zeros((0, 9)))))
    result = import_bvh(clip, up="z")
    assert result.motion.n_frames == 0
    assert result.skeleton.n_dofs == 6


# ---------------------------------------------------------------------------
# Issue 9: padded short joints, wrapping channels, whole-clip up axis, writing back into the clip
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("up", ["z", "y"])
def test_padded_short_joints_keep_every_frame_of_the_motion(biped, up):
    motion = smooth_motion(biped, 12, seed=5)
    padded = motion_to_bvh(motion, units="m", up=up)
    exact = motion_to_bvh(motion, units="m", up=up, pad_rotations=False)
    rotations = {j.name: [c for c in j.channels if c.endswith("rotation")] for j in padded.joints}
    assert all(len(r) in (0, 3) for r in rotations.values())
    # One order for every rotating joint but the root (which turns about the vertical first).
    assert len({tuple(r) for name, r in rotations.items() if r and name != "hips"}) == 1
    np.testing.assert_allclose(bvh_forward_kinematics(padded)[1], bvh_forward_kinematics(exact)[1], atol=1e-12)


def test_export_with_end_sites_writes_lone_sites_as_end_sites(biped):
    clip = pose_to_bvh(biped, biped.rest, end_sites=True)
    assert "left_hand" not in clip.names and "head" in clip.names  # the atlas holds head and head_top: joints
    hand = clip.joint_index("left_elbow_end")
    assert clip.joints[hand].is_end_site
    np.testing.assert_allclose(clip.joints[hand].offset, 100 * biped.frame_offset[biped.frame_of("left_hand")])


def test_import_unwraps_a_wrapping_channel_and_its_limits_follow():
    clip = read_bvh(DATA / "wrap_channel.bvh")
    raw = clip.motion[:, clip.channel_index("Spine").start + 1]
    assert np.abs(np.diff(raw)).max() > 300  # the file wraps: +178 -> -178
    imported = import_bvh(clip)
    sk, q = imported.skeleton, imported.motion.q
    d = sk.dof_index("Spine.y")
    assert np.abs(np.diff(np.degrees(q[:, d]))).max() < 15  # continuous
    turns = (q[:, d] - np.radians(raw)) / (2 * np.pi)
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-12)
    assert sk.lower[d] <= q[:, d].min() and q[:, d].max() <= sk.upper[d] and np.abs(q[:, d]).max() > np.pi
    # Unwrapping changes nothing in the poses.
    np.testing.assert_allclose(imported.motion.positions()[:, [sk.frame_of(n) for n in clip.names]],
                               clip_world_positions(clip, 0.01, "y"), atol=1e-9)


def test_up_axis_is_judged_over_the_whole_clip_not_its_rest_pose_or_first_frame():
    clip = read_bvh(DATA / "up_misleading_first_frame.bvh")
    rest = clip_world_positions(BvhClip(clip.joints, clip.frame_time, np.zeros((1, clip.n_channels))), 1.0, "z")
    first = bvh_forward_kinematics(clip)[1][0]
    assert np.ptp(rest[0][:, 2]) > np.ptp(rest[0][:, 1]) and np.ptp(first[:, 2]) > np.ptp(first[:, 1])
    assert detect_up(clip) == "y"
    up, why = detect_up_reason(clip)
    assert up == "y" and why.startswith("y up: over 30 frames the body is")
    assert import_bvh(clip).up_reason == why
    assert import_bvh(clip, up="z").up_reason == "as given"


@pytest.mark.parametrize("name", ["wrap_channel.bvh", "mixamo_zyx_crlf.bvh", "blender_chain_zyx_m.bvh"])
def test_clip_with_its_own_motion_is_the_clip(name):
    clip = read_bvh(DATA / name)
    imported = import_bvh(clip, strip_namespace=name.startswith("mixamo"))
    back = clip_with_motion(imported, imported.motion)
    assert back.joints == clip.joints and back.frame_time == clip.frame_time
    diff = back.motion - clip.motion
    np.testing.assert_allclose(diff, 360.0 * np.round(diff / 360.0), atol=1e-9)  # whole turns at most
    np.testing.assert_allclose(clip_with_motion(imported, imported.motion, wrap_angles=True).motion,
                               _wrapped(clip), atol=1e-9)


def _wrapped(clip: BvhClip) -> np.ndarray:
    """The clip's motion with its rotation channels in [-180, 180)."""
    out = clip.motion.copy()
    rot = [k for k, c in enumerate(c for j in clip.joints for c in j.channels) if c.endswith("rotation")]
    out[:, rot] = np.remainder(out[:, rot] + 180.0, 360.0) - 180.0
    return out


def test_clip_with_motion_recomputes_the_root_when_another_joint_was_pinned():
    clip = read_bvh(DATA / "walk_zxy.bvh")
    imported = import_bvh(clip)
    sk, motion = imported.skeleton, imported.motion
    foot = "LeftLeg_end"
    W = np.array([gsik.rotations.transform(*[a[sk.frame_of(foot)] for a in motion.frames(f)])
                  for f in range(motion.n_frames)])
    repinned = Motion(sk, motion.q, (foot,) * motion.n_frames, W, motion.frame_time)
    back = clip_with_motion(imported, repinned)
    np.testing.assert_allclose(bvh_forward_kinematics(back)[1], bvh_forward_kinematics(clip)[1], atol=1e-6)
    with pytest.raises(BvhError, match="the motion has 2 frames, the clip 4"):
        clip_with_motion(imported, Motion(sk, motion.q[:2], motion.roots[:2], motion.world_from_root[:2], 0.1))
