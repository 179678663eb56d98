"""Tests for gsik.io.bvh_skeleton: the import of clips as skeletons and motions, and issue 9's cases (padded short joints, wrapping channels, whole-clip up axis, writing back into the clip)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from bvh_skeleton_cases import (
    DATA,
    FIXTURES,
    clip_world_positions,
    one_joint_clip,
    smooth_motion,
)

import gsik
from gsik.anim.motion import Motion
from gsik.errors import BvhError
from gsik.io.bvh import BvhClip, BvhJoint, bvh_forward_kinematics, format_bvh, parse_bvh, read_bvh
from gsik.io.bvh_skeleton import (
    Z_UP_TO_Y_UP,
    BvhImportWarning,
    clip_with_motion,
    detect_scale,
    detect_up,
    detect_up_reason,
    import_bvh,
    motion_to_bvh,
    pose_to_bvh,
    skeleton_from_bvh,
)

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
