"""Tests for gsik.io.bvh: parsing, validation, writing and the clip's own FK."""

from __future__ import annotations

import dataclasses
import os
import re
import stat
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.io.bvh import (
    CHANNEL_NAMES,
    BvhClip,
    BvhJoint,
    bvh_forward_kinematics,
    bvh_local_rotations,
    bvh_local_translations,
    format_bvh,
    parse_bvh,
    read_bvh,
    write_bvh,
)
from gsik.errors import BvhError, GsikError, GsikFileError

DATA = Path(__file__).resolve().parents[1] / "data"

# Line numbers of this text are used by the malformed-file cases below.
BASE = """\
HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Chest
\t{
\t\tOFFSET 0 1 0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 0.5 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.04
0 1 0 10 20 30 1 2 3
0 1 0 11 21 31 4 5 6
"""


def lines_of(text: str = BASE) -> list[str]:
    return text.split("\n")


def replace_line(n: int, new: str, text: str = BASE) -> str:
    """``text`` with 1-based line ``n`` replaced by ``new``."""
    lines = lines_of(text)
    lines[n - 1] = new
    return "\n".join(lines)


def delete_line(n: int, text: str = BASE) -> str:
    lines = lines_of(text)
    del lines[n - 1]
    return "\n".join(lines)


def insert_line(n: int, new: str, text: str = BASE) -> str:
    """``text`` with ``new`` inserted so that it becomes line ``n``."""
    lines = lines_of(text)
    lines.insert(n - 1, new)
    return "\n".join(lines)


# Independent rotation matrices (degrees) to check the module against.
def rx(d: float) -> np.ndarray:
    c, s = np.cos(np.radians(d)), np.sin(np.radians(d))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(d: float) -> np.ndarray:
    c, s = np.cos(np.radians(d)), np.sin(np.radians(d))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(d: float) -> np.ndarray:
    c, s = np.cos(np.radians(d)), np.sin(np.radians(d))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


AXIS_MATRIX = {"X": rx, "Y": ry, "Z": rz}


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


# ---------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["walk_zxy.bvh", "mixamo_zyx_crlf.bvh", "six_channel.bvh", "cm_scale.bvh"])
def test_round_trip_fixtures(name):
    clip = read_bvh(DATA / name)
    text = format_bvh(clip)
    again = parse_bvh(text)
    assert again == clip
    assert format_bvh(again) == text


def test_format_layout():
    text = format_bvh(parse_bvh(BASE), precision=2)
    assert text.splitlines()[:12] == [
        "HIERARCHY",
        "ROOT Hips",
        "{",
        "\tOFFSET 0.00 0.00 0.00",
        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
        "\tJOINT Chest",
        "\t{",
        "\t\tOFFSET 0.00 1.00 0.00",
        "\t\tCHANNELS 3 Zrotation Xrotation Yrotation",
        "\t\tEnd Site",
        "\t\t{",
        "\t\t\tOFFSET 0.00 0.50 0.00",
    ]
    assert text.splitlines()[12:] == [
        "\t\t}",
        "\t}",
        "}",
        "MOTION",
        "Frames: 2",
        "Frame Time: 0.04",
        "0.00 1.00 0.00 10.00 20.00 30.00 1.00 2.00 3.00",
        "0.00 1.00 0.00 11.00 21.00 31.00 4.00 5.00 6.00",
    ]
    assert text.endswith("\n")


def test_round_trip_to_printed_precision():
    clip = parse_bvh(BASE)
    noisy = BvhClip(clip.joints, 1 / 30, clip.motion + np.pi / 1000)
    again = parse_bvh(format_bvh(noisy, precision=3))
    np.testing.assert_allclose(again.motion, noisy.motion, atol=0.5e-3 + 1e-12)
    assert again.frame_time == 1 / 30  # the frame time is written exactly


def test_format_rejects_bad_precision():
    with pytest.raises(BvhError, match="precision"):
        format_bvh(parse_bvh(BASE), precision=-1)


def test_write_and_read_back(tmp_path):
    clip = read_bvh(DATA / "walk_zxy.bvh")
    path = tmp_path / "out.bvh"
    write_bvh(path, clip)
    assert read_bvh(path) == clip
    assert os.listdir(tmp_path) == ["out.bvh"]


@pytest.fixture
def old_file(tmp_path):
    path = tmp_path / "take.bvh"
    path.write_bytes(b"old contents\r\n")
    return path


@pytest.mark.parametrize("failing", ["replace", "fsync"])
def test_write_failure_leaves_old_file(old_file, monkeypatch, failing):
    def boom(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, failing, boom)
    with pytest.raises(OSError) as info:
        write_bvh(old_file, parse_bvh(BASE))
    monkeypatch.undo()
    assert isinstance(info.value, GsikFileError) and info.value.errno == 28
    assert "No space left on device" in str(info.value)
    assert old_file.read_bytes() == b"old contents\r\n"
    assert os.listdir(old_file.parent) == [old_file.name]  # no temp file left behind


@pytest.mark.parametrize(
    "clip, precision",
    [(None, 6), ("not a clip", 6), ("base", -3), ("base", 1.5)],
)
def test_unformattable_write_leaves_old_file(old_file, clip, precision):
    clip = parse_bvh(BASE) if clip == "base" else clip
    with pytest.raises(BvhError):
        write_bvh(old_file, clip, precision=precision)  # type: ignore[arg-type]
    assert old_file.read_bytes() == b"old contents\r\n"
    assert os.listdir(old_file.parent) == [old_file.name]


def test_write_keeps_permissions(old_file):
    old_file.chmod(0o640)
    write_bvh(old_file, parse_bvh(BASE))
    assert stat.S_IMODE(old_file.stat().st_mode) == 0o640
    assert read_bvh(old_file) == parse_bvh(BASE)


def test_write_into_missing_directory(tmp_path):
    with pytest.raises(GsikFileError):
        write_bvh(tmp_path / "missing" / "x.bvh", parse_bvh(BASE))


# ---------------------------------------------------------------------------
# Forward kinematics
# ---------------------------------------------------------------------------

CHAIN = """\
HIERARCHY
ROOT A
{
  OFFSET 1 2 3
  CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT B
  {
    OFFSET 1 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 2 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.1
0 0 0 0 0 0
90 0 0 0 90 0
"""


def test_fk_two_joint_chain_exact():
    R, p = bvh_forward_kinematics(parse_bvh(CHAIN))
    # Rest: offsets add up.
    np.testing.assert_array_equal(p[0], [[1, 2, 3], [2, 2, 3], [2, 4, 3]])
    np.testing.assert_array_equal(R[0], np.broadcast_to(np.eye(3), (3, 3, 3)))
    # A turns 90 deg about Z: B's offset (1,0,0) becomes (0,1,0).
    # B turns 90 deg about X: the tip's (0,2,0) becomes (0,0,2), then Rz keeps it.
    np.testing.assert_array_equal(p[1], [[1, 2, 3], [1, 3, 3], [1, 3, 5]])
    np.testing.assert_array_equal(R[1, 0], [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    np.testing.assert_array_equal(R[1, 1], [[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(R[1, 2], R[1, 1])  # the End Site has no rotation of its own


def test_fk_position_channels_replace_offset():
    text = CHAIN.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT",
                         "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  JOINT")
    text = text.replace("0 0 0 0 0 0\n90 0 0 0 90 0", "5 6 7 0 0 0 0 0 0\n5 6 7 90 0 0 0 90 0")
    R, p = bvh_forward_kinematics(parse_bvh(text))
    np.testing.assert_array_equal(p[:, 0], [[5, 6, 7], [5, 6, 7]])  # not offset + position
    np.testing.assert_array_equal(p[1, 2], [5, 7, 9])


def test_fk_partial_position_channels():
    text = CHAIN.replace("CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT", "CHANNELS 1 Yposition\n  JOINT")
    text = text.replace("0 0 0 0 0 0\n90 0 0 0 90 0", "0 0 0 0\n10 0 0 0")
    t = bvh_local_translations(parse_bvh(text))
    np.testing.assert_array_equal(t[:, 0], [[1, 0, 3], [1, 10, 3]])


def single_joint_clip(channels: tuple[str, ...], values) -> BvhClip:
    return BvhClip(
        (BvhJoint("j", -1, (0, 0, 0), channels), BvhJoint("j_end", 0, (1, 0, 0), (), is_end_site=True)),
        0.1,
        np.array([values], dtype=float),
    )


def test_channel_order_matters():
    angles = (30.0, 40.0, 50.0)  # first, second, third channel in file order
    zxy = ("Zrotation", "Xrotation", "Yrotation")
    xyz = ("Xrotation", "Yrotation", "Zrotation")
    R_zxy = bvh_local_rotations(single_joint_clip(zxy, angles))[0, 0]
    R_xyz = bvh_local_rotations(single_joint_clip(xyz, angles))[0, 0]
    np.testing.assert_allclose(R_zxy, rz(30) @ rx(40) @ ry(50), atol=1e-14)
    np.testing.assert_allclose(R_xyz, rx(30) @ ry(40) @ rz(50), atol=1e-14)
    assert not np.allclose(R_zxy, R_xyz, atol=1e-3)


def test_rotations_exact_at_quarter_turns():
    R = bvh_local_rotations(single_joint_clip(("Zrotation",), [-270.0]))[0, 0]
    np.testing.assert_array_equal(R, [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    R = bvh_local_rotations(single_joint_clip(("Yrotation",), [180.0]))[0, 0]
    np.testing.assert_array_equal(R, [[-1, 0, 0], [0, 1, 0], [0, 0, -1]])


def test_fk_fixture_matches_chain_products():
    """World transforms of a real file equal the explicit product along each chain."""
    clip = read_bvh(DATA / "walk_zxy.bvh")
    R, p = bvh_forward_kinematics(clip)
    f, j = 2, clip.joint_index("LeftForeArm_end")
    chain = []
    while j >= 0:
        chain.append(j)
        j = clip.joints[j].parent
    world_R, world_p = np.eye(3), np.zeros(3)
    for k in reversed(chain):
        joint = clip.joints[k]
        vals = dict(zip(joint.channels, clip.motion[f, clip.channel_index(k)]))
        t = np.array([vals.get(a + "position", joint.offset[i]) for i, a in enumerate("XYZ")])
        local = np.eye(3)
        for c in joint.channels:
            if c.endswith("rotation"):
                local = local @ AXIS_MATRIX[c[0]](vals[c])
        world_p = world_p + world_R @ t
        world_R = world_R @ local
    np.testing.assert_allclose(p[f, chain[0]], world_p, atol=1e-12)
    np.testing.assert_allclose(R[f, chain[0]], world_R, atol=1e-12)


# ---------------------------------------------------------------------------
# Properties
# ---------------------------------------------------------------------------

decimal_angles = st.integers(-720_000_000, 720_000_000).map(lambda n: n / 1e6)  # 6 decimals
decimal_lengths = st.integers(-10_000_000, 10_000_000).map(lambda n: n / 1e6)


@settings(max_examples=60, deadline=None)
@given(
    channels=st.lists(st.sampled_from(CHANNEL_NAMES), unique=True, max_size=6).flatmap(st.permutations),
    data=st.data(),
)
def test_random_channel_orders_round_trip(channels, data):
    channels = tuple(channels)
    n_frames = data.draw(st.integers(0, 3))
    values = data.draw(
        st.lists(st.lists(decimal_angles, min_size=len(channels), max_size=len(channels)),
                 min_size=n_frames, max_size=n_frames)
    )
    offset = data.draw(st.tuples(decimal_lengths, decimal_lengths, decimal_lengths))
    clip = BvhClip(
        (BvhJoint("j", -1, offset, channels), BvhJoint("j_end", 0, (1, 0, 0), (), is_end_site=True)),
        data.draw(st.sampled_from([1 / 30, 1 / 120, 0.04, 0.0083333])),
        np.array(values, dtype=float).reshape(n_frames, len(channels)),
    )
    again = parse_bvh(format_bvh(clip))
    assert again == clip
    # The local rotation is the product of the rotation channels in file order.
    R = bvh_local_rotations(again)
    for f in range(n_frames):
        expected = np.eye(3)
        for c, v in zip(channels, values[f]):
            if c.endswith("rotation"):
                expected = expected @ AXIS_MATRIX[c[0]](v)
        np.testing.assert_allclose(R[f, 0], expected, atol=1e-12)


@st.composite
def random_clips(draw) -> BvhClip:
    """A random hierarchy in depth-first order with random channels and motion."""
    n = draw(st.integers(1, 8))
    joints: list[BvhJoint] = []
    stack: list[int] = []
    for i in range(n):
        if i == 0:
            parent = -1
        else:
            depth = draw(st.integers(1, len(stack)))
            del stack[depth:]
            parent = stack[-1]
        ends_here = i > 0 and draw(st.booleans())
        if ends_here:
            name = f"{joints[parent].name}_end"
            if any(j.name == name for j in joints):
                ends_here = False
        if not ends_here:
            name = draw(st.from_regex(r"[A-Za-z][A-Za-z0-9_:.\-]{0,8}", fullmatch=True))
            if any(j.name == name for j in joints) or name.endswith("_end"):
                name = f"j{i}"
                while any(j.name == name for j in joints):  # a drawn name may already be "j<i>"
                    name += "x"
        channels = () if ends_here else tuple(
            draw(st.lists(st.sampled_from(CHANNEL_NAMES), unique=True, max_size=6).flatmap(st.permutations))
        )
        offset = draw(st.tuples(decimal_lengths, decimal_lengths, decimal_lengths))
        joints.append(BvhJoint(name, parent, offset, channels, is_end_site=ends_here))
        if not ends_here:
            stack.append(i)
    n_channels = sum(len(j.channels) for j in joints)
    n_frames = draw(st.integers(0, 3))
    motion = draw(st.lists(decimal_angles, min_size=n_frames * n_channels, max_size=n_frames * n_channels))
    return BvhClip(tuple(joints), 0.04, np.array(motion, dtype=float).reshape(n_frames, n_channels))


@settings(max_examples=60, deadline=None)
@given(random_clips())
def test_random_hierarchies_round_trip(clip):
    text = format_bvh(clip)
    again = parse_bvh(text)
    assert again == clip
    assert format_bvh(again) == text
    R, p = bvh_forward_kinematics(again)
    assert R.shape == (clip.n_frames, clip.n_joints, 3, 3) and p.shape == (clip.n_frames, clip.n_joints, 3)
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
