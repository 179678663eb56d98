"""Tests for gsik.io.bvh: parsing and validation (writing: test_bvh_write.py; FK and properties: test_bvh_fk.py)."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from bvh_cases import BASE, DATA, delete_line, insert_line, replace_line

from gsik.errors import BvhError, GsikError, GsikFileError
from gsik.io.bvh import (
    BvhClip,
    BvhJoint,
    bvh_forward_kinematics,
    bvh_local_translations,
    format_bvh,
    parse_bvh,
    read_bvh,
)

# ---------------------------------------------------------------------------
# Valid files
# ---------------------------------------------------------------------------


def test_base_parses():
    clip = parse_bvh(BASE)
    assert clip.names == ("Hips", "Chest", "Chest_end")
    assert [j.parent for j in clip.joints] == [-1, 0, 1]
    assert [j.is_end_site for j in clip.joints] == [False, False, True]
    assert clip.joints[0].channels == (
        "Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation",
    )
    assert clip.joints[2].channels == ()
    assert clip.n_frames == 2 and clip.n_channels == 9 and clip.n_joints == 3
    assert clip.frame_time == 0.04
    assert clip.duration == pytest.approx(0.08)
    np.testing.assert_array_equal(clip.motion[1], [0, 1, 0, 11, 21, 31, 4, 5, 6])
    np.testing.assert_array_equal(clip.joints[2].offset, [0, 0.5, 0])


def test_walk_zxy_fixture():
    clip = read_bvh(DATA / "walk_zxy.bvh")
    assert clip.names == (
        "Hips", "Spine", "Neck", "Head", "Head_end",
        "LeftArm", "LeftForeArm", "LeftForeArm_end",
        "RightArm", "RightForeArm", "RightForeArm_end",
        "LeftUpLeg", "LeftLeg", "LeftLeg_end",
        "RightUpLeg", "RightLeg", "RightLeg_end",
    )
    assert sum(not j.is_end_site for j in clip.joints) == 12
    assert clip.n_frames == 4 and clip.n_channels == 6 + 11 * 3
    assert clip.frame_time == 0.033333
    zxy = ("Zrotation", "Xrotation", "Yrotation")
    assert clip.joints[0].channels == ("Xposition", "Yposition", "Zposition") + zxy
    assert all(j.channels == zxy for j in clip.joints[1:] if not j.is_end_site)
    assert clip.joints[clip.joint_index("LeftForeArm")].parent == clip.joint_index("LeftArm")
    assert clip.joints[clip.joint_index("LeftUpLeg")].parent == 0
    np.testing.assert_array_equal(clip.joints[clip.joint_index("Head")].offset, [0, 0.1, 0.02])
    np.testing.assert_array_equal(clip.motion[1, :4], [0.01, 0.96, 0.01, 9.9957])
    assert clip.motion[3, -1] == 8.0378


def test_mixamo_fixture_crlf_tabs_namespaces_split_frames():
    raw = (DATA / "mixamo_zyx_crlf.bvh").read_bytes()
    assert b"\r\n" in raw and b"\t" in raw  # the fixture really has CRLF and tabs
    clip = read_bvh(DATA / "mixamo_zyx_crlf.bvh")
    assert clip.names[0] == "mixamorig:Hips"
    assert clip.names[5:7] == ("mixamorig:HeadTop_End", "mixamorig:HeadTop_End_end")
    assert clip.names[-1] == "mixamorig:LeftFoot_end"
    zyx = ("Zrotation", "Yrotation", "Xrotation")
    assert clip.joints[0].channels == ("Xposition", "Yposition", "Zposition") + zyx
    assert clip.joints[clip.joint_index("mixamorig:LeftLeg")].channels == zyx
    assert clip.n_frames == 3 and clip.n_channels == 30
    assert clip.frame_time == 0.0333333
    # Each frame spans two lines: value 10 of frame 2 starts the second line.
    assert clip.motion[1, 9] == -2.5554
    assert clip.motion[1, 10] == -5.2984
    # Same clip as the LF, one-line-per-frame version of the same data.
    lf = raw.decode().replace("\r\n", "\n")
    assert parse_bvh(lf) == clip


def test_six_channel_fixture():
    clip = read_bvh(DATA / "six_channel.bvh")
    six = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
    assert clip.names == ("root", "spine", "head", "head_end", "leg", "leg_end")
    assert all(j.channels == six for j in clip.joints if not j.is_end_site)
    assert clip.n_frames == 2 and clip.n_channels == 24 and clip.frame_time == 0.05
    # Position channels of a non-root joint replace its offset.
    t = bvh_local_translations(clip)
    spine = clip.channel_index("spine")
    np.testing.assert_array_equal(t[:, 1], clip.motion[:, spine][:, :3])
    np.testing.assert_array_equal(t[:, 3], np.broadcast_to([0, 0.2, 0], (2, 3)))


def test_cm_scale_fixture_with_zero_channel_joint():
    clip = read_bvh(DATA / "cm_scale.bvh")
    assert clip.names == ("Hips", "LHipJoint", "LeftUpLeg", "LeftLeg", "LeftLeg_end", "Spine", "Head", "Head_end")
    assert clip.joints[1].channels == ()
    assert clip.channel_index(1) == slice(6, 6)
    assert clip.n_channels == 18 and clip.n_frames == 3
    assert clip.frame_time == 0.0083333
    np.testing.assert_array_equal(clip.joints[3].offset, [0, -42, 0])
    R, p = bvh_forward_kinematics(clip)
    np.testing.assert_array_equal(p[:, 0], clip.motion[:, :3])  # root: the position channels
    np.testing.assert_array_equal(p[:, 1], p[:, 0])  # zero offset, zero channels
    np.testing.assert_array_equal(R[:, 1], R[:, 0])
    # Head end ~ 95 + 10 + 58 + 18 cm above the ground: centimetre scale survives.
    assert 170 < p[0, 7, 1] < 190


@pytest.mark.parametrize(
    "variant",
    [
        pytest.param(BASE.replace("\n", "\r\n"), id="crlf"),
        pytest.param(BASE.replace("\n", "\r"), id="cr"),
        pytest.param("\ufeff" + BASE, id="bom"),
        pytest.param(BASE.replace("\t", "    "), id="spaces"),
        pytest.param(BASE.replace("\n", "  \t\n"), id="trailing-whitespace"),
        pytest.param(BASE.replace("\n", "\n\n"), id="blank-lines"),
        pytest.param(BASE.replace("Frame Time: 0.04", "Frame Time :\t 0.04"), id="frame-time-spacing"),
        pytest.param(BASE.replace("Frame Time: 0.04", "Frame Time:0.04"), id="frame-time-glued"),
        pytest.param(BASE.replace("Frames: 2", "Frames:2"), id="frames-glued"),
        pytest.param(BASE.replace("Frames: 2", "FRAMES: 2").replace("Frame Time", "frame time"), id="case"),
        pytest.param(
            BASE.replace("ROOT Hips\n{", "ROOT Hips {").replace("Site\n\t\t{", "Site {"), id="brace-same-line"
        ),
        pytest.param(BASE.replace("JOINT Chest\n\t{", "JOINT Chest{"), id="brace-glued"),
        pytest.param(BASE.replace("0 1 0 11 21 31 4 5 6", "0 1 0 11\n21 31\n4 5 6"), id="frame-split"),
        pytest.param(BASE.replace("3\n0 1 0 11", "3 0 1 0 11"), id="frames-joined"),
        pytest.param(BASE.replace("OFFSET 0 1 0", "OFFSET 0.0 1.000 -0.0e0"), id="number-forms"),
        pytest.param(BASE.replace("Xrotation", "XROTATION").replace("Yposition", "yposition"), id="channel-case"),
        pytest.param(BASE.replace("\t\tOFFSET 0 1 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation",
                                  "\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\t\tOFFSET 0 1 0"),
                     id="channels-before-offset"),
        pytest.param(BASE + "\n\n   \n", id="trailing-blank-lines"),
    ],
)
def test_lenient_variants_parse_like_base(variant):
    assert parse_bvh(variant) == parse_bvh(BASE)


def test_zero_frames():
    text = BASE.split("Frames:")[0] + "Frames: 0\nFrame Time: 0.1\n"
    clip = parse_bvh(text)
    assert clip.n_frames == 0 and clip.motion.shape == (0, 9)
    R, p = bvh_forward_kinematics(clip)
    assert R.shape == (0, 3, 3, 3) and p.shape == (0, 3, 3)
    assert parse_bvh(format_bvh(clip)) == clip


def test_end_site_name_made_unique():
    text = BASE.replace(
        "\t}\n}\nMOTION",
        "\t}\n\tJOINT Chest_end\n\t{\n\t\tOFFSET 1 0 0\n\t\tCHANNELS 0\n\t}\n}\nMOTION",
    )
    clip = parse_bvh(text)
    assert clip.names == ("Hips", "Chest", "Chest_end2", "Chest_end")
    assert clip.joints[2].is_end_site and not clip.joints[3].is_end_site


def test_leaf_joint_without_end_site():
    text = BASE.replace("\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 0.5 0\n\t\t}\n", "")
    clip = parse_bvh(text)
    assert clip.names == ("Hips", "Chest")


def test_clip_helpers():
    clip = read_bvh(DATA / "walk_zxy.bvh")
    assert clip.channel_index(0) == slice(0, 6)
    assert clip.channel_index("Spine") == slice(6, 9)
    assert clip.channel_index("Head_end") == slice(15, 15)
    assert clip.children(0) == (1, 11, 14)
    assert clip.channel_labels()[:7] == (
        "Hips Xposition", "Hips Yposition", "Hips Zposition",
        "Hips Zrotation", "Hips Xrotation", "Hips Yrotation", "Spine Zrotation",
    )
    with pytest.raises(BvhError, match="no joint 'Tail'"):
        clip.joint_index("Tail")
    with pytest.raises(BvhError, match="out of range"):
        clip.channel_index(-1)
    shorter = dataclasses.replace(clip, motion=clip.motion[:2])
    assert shorter.n_frames == 2 and shorter.joints == clip.joints


def test_clip_is_read_only():
    clip = parse_bvh(BASE)
    assert not clip.motion.flags.writeable
    assert not clip.joints[0].offset.flags.writeable
    with pytest.raises(ValueError):
        clip.motion[0, 0] = 1.0
    with pytest.raises(ValueError):
        clip.joints[1].offset[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        clip.frame_time = 1.0  # type: ignore[misc]


# ---------------------------------------------------------------------------
# Malformed files
# ---------------------------------------------------------------------------

MALFORMED = [
    # id, text, expected line, message pattern
    ("empty", "", 1, r"empty file"),
    ("whitespace-only", " \n\t\n\r\n", 1, r"empty file"),
    ("truncated-one-value", replace_line(20, "0 1 0 11 21 31 4 5"), 20,
     r"truncated MOTION data: expected 18 values \(2 frames x 9 channels\), found 17"),
    ("truncated-one-frame", delete_line(20), 19, r"truncated MOTION data: expected 18 values .*found 9\b"),
    ("truncated-no-data", BASE.split("0 1 0 10")[0], 18, r"truncated MOTION data: .*found 0\b"),
    ("too-many-values", replace_line(20, "0 1 0 11 21 31 4 5 6 7"), 20,
     r"too many MOTION values: expected 18 values .*found 19"),
    ("extra-frame", insert_line(21, "0 1 0 12 22 32 7 8 9"), 21, r"too many MOTION values: .*found 27"),
    ("channels-too-few-names", replace_line(9, "\t\tCHANNELS 3 Zrotation Xrotation"), 9,
     r"CHANNELS of JOINT 'Chest' declares 3 channels but lists 2"),
    ("channels-too-many-names", replace_line(9, "\t\tCHANNELS 2 Zrotation Xrotation Yrotation"), 9,
     r"CHANNELS of JOINT 'Chest' on line 9 declares 2 channels but lists more"),
    ("unknown-channel", replace_line(9, "\t\tCHANNELS 3 Zrotation Wrotation Yrotation"), 9,
     r"unknown channel name 'Wrotation'"),
    ("duplicate-channel", replace_line(9, "\t\tCHANNELS 3 Zrotation Zrotation Yrotation"), 9,
     r"duplicate channel 'Zrotation'"),
    ("channel-count-not-int", replace_line(9, "\t\tCHANNELS three Zrotation Xrotation Yrotation"), 9,
     r"CHANNELS count of JOINT 'Chest' must be a non-negative integer, found 'three'"),
    ("channel-count-negative", replace_line(9, "\t\tCHANNELS -3 Zrotation Xrotation Yrotation"), 9,
     r"non-negative integer, found '-3'"),
    ("missing-close-brace", delete_line(14), 15,
     r"unbalanced braces: '\{' opened on line 3 for ROOT 'Hips' is never closed"),
    ("missing-close-brace-no-motion", delete_line(14, BASE.split("MOTION")[0]), 14,
     r"unbalanced braces: '\{' opened on line 3 for ROOT 'Hips' is never closed"),
    ("extra-close-brace", insert_line(16, "}"), 16, r"unbalanced braces: '\}' without a matching '\{'"),
    ("root-inside-joint", insert_line(10, "\t\tROOT Other"), 10,
     r"unbalanced braces: found 'ROOT' inside JOINT 'Chest'"),
    ("non-numeric-motion", replace_line(20, "0 1 0 11 21 31 4 abc 6"), 20,
     r"non-numeric value 'abc' in MOTION data \(frame 2, channel 'Chest Xrotation'\)"),
    ("comma-decimal", replace_line(19, "0 1 0 10 20,5 30 1 2 3"), 19, r"non-numeric value '20,5'"),
    ("underscore-number", replace_line(19, "0 1 0 10 1_000 30 1 2 3"), 19, r"non-numeric value '1_000'"),
    ("nan-motion", replace_line(19, "0 1 0 nan 20 30 1 2 3"), 19,
     r"non-finite value 'nan' in MOTION data \(frame 1, channel 'Hips Zrotation'\)"),
    ("inf-motion", replace_line(20, "0 1 0 11 21 31 4 5 -inf"), 20, r"non-finite value '-inf'"),
    ("nan-offset", replace_line(12, "\t\t\tOFFSET 0 NaN 0"), 12,
     r"non-finite value 'NaN' in OFFSET of End Site of 'Chest'"),
    ("non-numeric-offset", replace_line(8, "\t\tOFFSET 0 x 0"), 8, r"non-numeric value 'x' in OFFSET of JOINT 'Chest'"),
    ("short-offset", replace_line(8, "\t\tOFFSET 0 1"), 8, r"OFFSET of JOINT 'Chest' needs 3 numbers, found 2"),
    ("long-offset", replace_line(8, "\t\tOFFSET 0 1 0 7"), 8, r"unexpected number '7'.*OFFSET takes exactly 3"),
    ("missing-offset", delete_line(8), 6, r"JOINT 'Chest' has no OFFSET"),
    ("missing-channels", delete_line(9), 6, r"JOINT 'Chest' has no CHANNELS"),
    ("second-offset", insert_line(9, "\t\tOFFSET 0 1 0"), 9, r"JOINT 'Chest' has a second OFFSET"),
    ("missing-hierarchy", delete_line(1), 1, r"expected 'HIERARCHY' at the start of the file, found 'ROOT'"),
    ("missing-root", replace_line(2, "JOINT Hips"), 2, r"expected 'ROOT' after HIERARCHY, found 'JOINT'"),
    ("root-without-name", replace_line(2, "ROOT"), 3, r"ROOT on line 2 has no name"),
    ("missing-motion-keyword", delete_line(16), 16, r"expected 'MOTION' after the hierarchy, found 'Frames:'"),
    ("missing-motion-section", BASE.split("MOTION")[0], 15, r"missing MOTION section"),
    ("missing-frames", delete_line(17), 17, r"missing 'Frames:' line before 'Frame Time:'"),
    ("missing-frames-eof", BASE.split("Frames")[0], 16, r"missing 'Frames:' line after MOTION"),
    ("garbage-instead-of-frames", replace_line(17, "Frmes: 2"), 17, r"expected 'Frames: <count>' after MOTION"),
    ("missing-frame-time", delete_line(18), 18, r"expected 'Frame Time: <seconds>', found '0 1 0 10"),
    ("missing-frame-time-eof", BASE.split("Frame Time")[0], 17, r"missing 'Frame Time:' line"),
    ("negative-frames", replace_line(17, "Frames: -2"), 17, r"negative frame count -2"),
    ("fractional-frames", replace_line(17, "Frames: 2.5"), 17, r"frame count must be an integer, found '2.5'"),
    ("non-numeric-frame-time", replace_line(18, "Frame Time: fast"), 18, r"non-numeric value 'fast' in Frame Time"),
    ("nan-frame-time", replace_line(18, "Frame Time: nan"), 18, r"non-finite value 'nan' in Frame Time"),
    ("zero-frame-time", replace_line(18, "Frame Time: 0"), 18, r"Frame Time must be positive"),
    ("duplicate-joint", replace_line(6, "\tJOINT Hips"), 6, r"duplicate joint name 'Hips' \(first defined on line 2\)"),
    ("end-site-channels", insert_line(12, "\t\t\tCHANNELS 1 Xrotation"), 12,
     r"End Site of 'Chest' cannot have channels"),
    ("end-site-child", insert_line(12, "\t\t\tJOINT Toe"), 12, r"End Site of 'Chest' cannot contain 'JOINT'"),
    ("end-without-site", replace_line(10, "\t\tEnd"), 11, r"expected 'Site' after 'End', found '\{'"),
    ("joint-without-brace", delete_line(7), 7, r"expected '\{' after JOINT Chest, found 'OFFSET'"),
    ("name-with-space", replace_line(6, "\tJOINT Left Chest"), 6, r"expected '\{' after JOINT Left, found 'Chest'"),
    ("unexpected-token", insert_line(9, "\t\tSCALE 2"), 9, r"unexpected 'SCALE' in JOINT 'Chest'"),
    ("second-root", insert_line(16, "ROOT Other\n{\n}"), 16, r"a second ROOT"),
]


@pytest.mark.parametrize("text, line, pattern", [c[1:] for c in MALFORMED], ids=[c[0] for c in MALFORMED])
def test_malformed_raises_with_line(text, line, pattern):
    with pytest.raises(BvhError) as info:
        parse_bvh(text, source="walk.bvh")
    err = info.value
    assert err.line == line, str(err)
    assert err.path == "walk.bvh"
    assert str(err).startswith(f"walk.bvh:{line}: "), str(err)
    assert re.search(pattern, str(err)), str(err)
    assert isinstance(err, GsikError) and isinstance(err, ValueError)


@pytest.mark.parametrize("case", ["truncated-one-value", "missing-close-brace", "nan-motion", "missing-frames"])
def test_malformed_line_numbers_survive_crlf(case):
    _, text, line, pattern = next(c for c in MALFORMED if c[0] == case)
    with pytest.raises(BvhError) as info:
        parse_bvh(text.replace("\n", "\r\n"))
    assert info.value.line == line and re.search(pattern, str(info.value))


def test_read_bvh_names_the_path(tmp_path):
    path = tmp_path / "bad.bvh"
    path.write_text(replace_line(17, "Frames: -1"))
    with pytest.raises(BvhError) as info:
        read_bvh(path)
    assert info.value.path == str(path) and info.value.line == 17
    assert str(info.value).startswith(f"{path}:17: ")


def test_read_bvh_missing_file(tmp_path):
    with pytest.raises(GsikFileError) as info:
        read_bvh(tmp_path / "nope.bvh")
    assert isinstance(info.value, OSError) and "nope.bvh" in str(info.value)


def test_read_bvh_latin1_names(tmp_path):
    path = tmp_path / "latin1.bvh"
    path.write_bytes(BASE.replace("Chest", "Br\u00fcst").encode("latin-1"))
    assert read_bvh(path).names[1] == "Br\u00fcst"


@pytest.mark.parametrize(
    "make, pattern",
    [
        (lambda c: BvhClip(c.joints, c.frame_time, c.motion[:, :-1]), r"motion must have shape \(n_frames, 9\)"),
        (lambda c: BvhClip(c.joints, 0.0, c.motion), r"frame_time must be a positive"),
        (lambda c: BvhClip(c.joints, c.frame_time, np.full_like(c.motion, np.nan)), r"non-finite"),
        (lambda c: BvhClip((), c.frame_time, c.motion), r"at least one joint"),
        (lambda c: BvhClip(c.joints[1:], c.frame_time, c.motion), r"must be the root"),
        (lambda c: BvhClip((c.joints[0], c.joints[0]), c.frame_time, c.motion), r"duplicate joint name"),
        (lambda c: BvhJoint("a b", -1, (0, 0, 0)) and BvhClip((BvhJoint("a b", -1, (0, 0, 0)),), 1.0, np.zeros((1, 0))),
         r"one non-empty token"),
        (lambda c: BvhJoint("e", 0, (0, 0, 0), ("Xrotation",), is_end_site=True), r"cannot have channels"),
        (lambda c: BvhJoint("j", 0, (0, 0, 0), ("Wrotation",)), r"unknown channel 'Wrotation'"),
        (lambda c: BvhJoint("j", 0, (0, 0)), r"offset must have shape \(3,\)"),
    ],
)
def test_clip_construction_is_validated(make, pattern):
    with pytest.raises(BvhError, match=pattern):
        make(parse_bvh(BASE))


def test_clip_must_be_depth_first():
    j = [
        BvhJoint("root", -1, (0, 0, 0), ()),
        BvhJoint("a", 0, (1, 0, 0), ()),
        BvhJoint("b", 0, (0, 1, 0), ()),
        BvhJoint("a_child", 1, (1, 0, 0), ()),  # child of 'a' after 'a''s subtree closed
    ]
    with pytest.raises(BvhError, match="depth-first"):
        BvhClip(tuple(j), 0.1, np.zeros((1, 0)))
