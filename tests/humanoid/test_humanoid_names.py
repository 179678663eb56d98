"""Humanoid recognition by name (issue 17, item 1): every convention, its helpers, overrides and clear refusals."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from humanoid_rigs import CONVENTIONS, build

import gsik
from gsik.humanoid import HUMANOID_BONES, REQUIRED_BONES, Rig, recognise, rig_from_clip, rig_from_skeleton
from gsik.humanoid.names import label

HERE = Path(__file__).resolve()
MOCAP = next((p / "shared" / "mocap" for p in HERE.parents[3:5] if (p / "shared" / "mocap").is_dir()), None)


@pytest.mark.parametrize("up", ["y", "z"])
@pytest.mark.parametrize("a_pose", [False, True], ids=["T", "A"])
@pytest.mark.parametrize("conv", CONVENTIONS, ids=[c.name for c in CONVENTIONS])
def test_every_convention_maps_every_required_bone_to_its_joint(conv, a_pose, up):
    t = build(conv, a_pose, up)
    r = recognise(t.rig)
    assert set(REQUIRED_BONES) <= set(t.expect)
    assert {b: r.bones.get(b) for b in t.expect} == t.expect
    assert all(r.method[b] == "name" and 0.8 <= r.confidence[b] <= 1.0 for b in t.expect)
    want_up = [0.0, 1.0, 0.0] if up == "y" else [0.0, 0.0, 1.0]
    want_forward = [0.0, 0.0, 1.0] if up == "y" else [0.0, -1.0, 0.0]
    np.testing.assert_allclose(r.up, want_up, atol=1e-9)
    np.testing.assert_allclose(r.forward, want_forward, atol=1e-9)
    assert r.height == pytest.approx(182.0 if "headTop" in dict(conv.trunk).values() else 162.0, abs=25.0)


def test_twist_share_and_roll_bones_are_not_the_joint_and_are_listed_as_ignored():
    t = build(next(c for c in CONVENTIONS if c.name == "character_creator"))
    r = recognise(t.rig)
    assert r.bones["leftUpperArm"] == "CC_Base_L_Upperarm" and r.bones["leftLowerLeg"] == "CC_Base_L_Calf"
    assert r.ignored["CC_Base_L_UpperarmTwist01"] == "twist"
    assert r.ignored["CC_Base_R_KneeShareBone"] == "share"
    assert r.ignored["CC_Base_L_ToeBaseShareBone"] == "share"
    assert r.ignored["CC_Base_L_Mid1"] == "finger"
    assert r.ignored["CC_Base_FacialBone"] == "face"
    assert r.ignored["CC_Base_NeckTwist02"] == "twist"  # NeckTwist01 is the neck: the rig's only neck
    assert label("LeftUpLeg_Roll") == ("left", "upperLeg", "roll")
    assert set(r.ignored).isdisjoint(r.bones.values())


@pytest.mark.parametrize("names, side, kind", [
    (("lThigh", "lShldr", "lForeArm"), "left", ("upperLeg", "shoulder", "lowerArm")),
    (("thigh_r", "calf_r", "upperarm_r", "lowerarm_r", "clavicle_r", "foot_r", "ball_r"), "right",
     ("upperLeg", "lowerLeg", "upperArm", "lowerArm", "collar", "foot", "toes")),
    (("lfemur", "ltibia", "lhumerus", "lradius", "lhand", "lfoot", "ltoes", "lclavicle"), "left",
     ("upperLeg", "lowerLeg", "upperArm", "lowerArm", "hand", "foot", "toes", "collar")),
    (("Bip01 R Thigh", "Bip01 R Calf", "Bip01 R UpperArm", "Bip01 R Forearm", "Bip01 R Clavicle"), "right",
     ("upperLeg", "lowerLeg", "upperArm", "lowerArm", "collar")),
    (("DEF-thigh.L", "DEF-shin.L", "DEF-upper_arm.L", "DEF-forearm.L", "DEF-shoulder.L"), "left",
     ("upperLeg", "lowerLeg", "upperArm", "lowerArm", "shoulder")),
    (("mixamorig:LeftUpLeg", "other:LeftLeg", "LeftArm", "LeftForeArm", "LeftShoulder"), "left",
     ("upperLeg", "lowerLeg", "upperArm", "lowerArm", "shoulder")),
    (("CC_Base_L_Thigh", "CC_Base_L_Calf", "CC_Base_L_Upperarm", "CC_Base_L_Forearm", "CC_Base_L_Clavicle"), "left",
     ("upperLeg", "lowerLeg", "upperArm", "lowerArm", "collar")),
    (("LeftUpperLeg", "LeftLowerArm", "Left Hand", "L Foot", "foot.L", "L_Hand"), "left",
     ("upperLeg", "lowerArm", "hand", "foot", "foot", "hand")),
    (("Character1_RightUpLeg", "Bip001 R Calf", "Bip01_R_Foot", "ik_hand_r_twist"), "right",
     ("upperLeg", "lowerLeg", "foot", None)),
])
def test_names_give_side_and_part_in_every_spelling(names, side, kind):
    assert [(label(n).side, label(n).kind) for n in names] == [(side, k) for k in kind]


@pytest.mark.parametrize("names", [("pelvis", "spine_01", "spine_05", "neck_01", "head"),
                                   ("CC_Base_Pelvis", "CC_Base_Hip", "CC_Base_Waist", "CC_Base_Spine01",
                                    "CC_Base_NeckTwist01", "CC_Base_Head"),
                                   ("root", "lowerback", "upperback", "thorax", "lowerneck", "upperneck", "head")])
def test_trunk_names_read_as_trunk_parts(names):
    kinds = [label(n).kind for n in names]
    assert kinds[0] == "hips" and kinds[-1] == "head" and set(kinds[1:-1]) <= {"hips", "spine", "neck"}


def test_a_collar_before_a_shoulder_makes_the_shoulder_the_arm_and_a_shoulder_before_an_arm_the_clavicle():
    collar = recognise(build(next(c for c in CONVENTIONS if c.name == "mocap_collar")).rig)
    assert collar.bones["leftShoulder"] == "LeftCollar" and collar.bones["leftUpperArm"] == "LeftShoulder"
    mixamo = recognise(build(CONVENTIONS[0]).rig)
    assert mixamo.bones["leftShoulder"] == "mixamorig:LeftShoulder"
    assert mixamo.bones["leftUpperArm"] == "mixamorig:LeftArm"
    makehuman = recognise(build(next(c for c in CONVENTIONS if c.name == "makehuman")).rig)
    assert makehuman.bones["leftShoulder"] == "clavicle.L" and makehuman.ignored["shoulder01.L"] == "helper"


def test_overrides_win_and_bad_ones_name_the_valid_choices():
    t = build(CONVENTIONS[0])
    r = recognise(t.rig, {"leftHand": "mixamorig:LeftHandIndex1"})
    assert r.bones["leftHand"] == "mixamorig:LeftHandIndex1" and r.method["leftHand"] == "map"
    assert r.confidence["leftHand"] == 1.0
    with pytest.raises(gsik.HumanoidError, match="'leftHnd'.*valid: .*'leftHand'"):
        recognise(t.rig, {"leftHnd": "mixamorig:LeftHand"})
    with pytest.raises(gsik.HumanoidError, match="'Nope'.*not in the rig.*'mixamorig:Hips'"):
        recognise(t.rig, {"leftHand": "Nope"})


def test_a_rig_that_is_no_humanoid_is_refused_naming_what_is_missing():
    rig = Rig(("base", "link1", "link2", "tool"), (-1, 0, 1, 2), np.arange(12.0).reshape(4, 3))
    with pytest.raises(gsik.HumanoidError, match="no joint found for 'hips'.*'rightFoot'.*joints: 'base'"):
        recognise(rig)
    r = recognise(build(CONVENTIONS[0]).rig)
    with pytest.raises(gsik.HumanoidError, match="'tail' is not a humanoid bone"):
        r.joint("tail")
    assert r.joint("leftFoot") == "mixamorig:LeftFoot"
    assert isinstance(gsik.HumanoidError("x"), gsik.GsikError)


def test_bad_rig_data_is_refused():
    with pytest.raises(gsik.HumanoidError, match="parent 1 is not an earlier joint"):
        Rig(("a", "b"), (-1, 1), np.zeros((2, 3)))
    with pytest.raises(gsik.HumanoidError, match="expected finite \\(2, 3\\)"):
        Rig(("a", "b"), (-1, 0), np.zeros((3, 3)))


def test_the_biped_skeleton_is_recognised_from_its_frames():
    r = recognise(rig_from_skeleton(gsik.load_skeleton("biped")))
    assert {b: r.bones[b] for b in ("hips", "spine", "neck", "head", "leftUpperArm", "leftLowerArm", "leftHand",
                                    "rightUpperLeg", "rightLowerLeg", "rightFoot", "rightToes")} == {
        "hips": "hips", "spine": "waist", "neck": "neck", "head": "atlas", "leftUpperArm": "left_shoulder",
        "leftLowerArm": "left_elbow", "leftHand": "left_hand", "rightUpperLeg": "right_hip",
        "rightLowerLeg": "right_knee", "rightFoot": "right_ankle", "rightToes": "right_toe"}
    np.testing.assert_allclose(r.up, [0, 0, 1])
    np.testing.assert_allclose(r.forward, [0, 1, 0])  # the biped faces +y
    assert list(r.bones) == [b for b in HUMANOID_BONES if b in r.bones]


def test_a_clip_rig_keeps_its_joints_and_end_sites():
    t = build(CONVENTIONS[0])
    rig = rig_from_clip(t.clip)
    assert rig.names == t.rig.names and rig.parents == t.rig.parents
    np.testing.assert_allclose(rig.rest_positions - rig.rest_positions[0], t.rig.rest_positions
                               - t.rig.rest_positions[0], atol=1e-9)


@pytest.mark.skipif(MOCAP is None, reason="the real clips of ../shared/mocap are not beside the repository")
def test_the_real_rigs_are_recognised_by_name():
    from gsik.io.bvh import read_bvh

    cc = recognise(rig_from_clip(read_bvh(MOCAP / "cmu" / "002_03.bvh")))
    assert {b: cc.bones[b] for b in ("hips", "spine", "neck", "head", "leftShoulder", "leftUpperArm",
                                     "rightLowerLeg", "rightToes")} == {
        "hips": "CC_Base_Hip", "spine": "CC_Base_Waist", "neck": "CC_Base_NeckTwist01", "head": "CC_Base_Head",
        "leftShoulder": "CC_Base_L_Clavicle", "leftUpperArm": "CC_Base_L_Upperarm", "rightLowerLeg": "CC_Base_R_Calf",
        "rightToes": "CC_Base_R_ToeBase"}
    assert cc.ignored["CC_Base_L_ForearmTwist01"] == "twist"
    bvhtools = recognise(rig_from_clip(read_bvh(MOCAP / "mocap_bvhtools_test.bvh")))
    assert bvhtools.bones["leftShoulder"] == "LeftShoulder" and bvhtools.bones["leftUpperArm"] == "LeftArm"
