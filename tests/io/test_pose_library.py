"""Pose files with a library of named poses: exact round trips, today's single-pose files still read, clear errors."""

from __future__ import annotations

import os

import pytest

import gsik
from gsik.io.pose import pose_from_yaml, pose_to_yaml, read_pose, write_pose

from test_pose import _pose  # a pose with messy numbers  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")


@pytest.fixture(scope="module")
def skeleton():
    return gsik.load_skeleton("biped")


@pytest.fixture()
def library(skeleton):
    return (("reach", _pose(skeleton, 1)), ("crouch: low", _pose(skeleton, 2)), ("T", _pose(skeleton, 3)))


def test_library_round_trip_is_exact(skeleton, library, tmp_path):
    pose = _pose(skeleton, 0)
    path = tmp_path / "lib.yaml"
    write_pose(path, pose, library)
    read = read_pose(path, skeleton)
    assert read.pose == pose and read.library == library and read.warnings == ()
    assert pose_to_yaml(read.pose, read.library) == path.read_text()


def test_a_single_pose_file_reads_as_before_with_an_empty_library(skeleton):
    pose = _pose(skeleton, 0)
    text = pose_to_yaml(pose)
    assert "library" not in text
    read = pose_from_yaml(text, skeleton)
    assert read.pose == pose and read.library == ()
    pose_, warnings = read[:2]  # the first two fields are as they were
    assert pose_ == pose and warnings == ()


def test_library_errors_name_the_entry_and_line(skeleton, library):
    text = pose_to_yaml(_pose(skeleton, 0), library)
    dup = text.replace("- name: T", "- name: reach")
    with pytest.raises(gsik.PoseError, match=r"lib.yaml:\d+: library.2.name: duplicate pose name 'reach'"):
        pose_from_yaml(dup, skeleton, "lib.yaml")
    bad = text.replace("    joints:\n      waist.x", "    joints:\n      waist.q", 1)
    with pytest.raises(gsik.PoseError, match=r"library\.0\.joints\.waist\.q: unknown joint 'waist\.q'"):
        pose_from_yaml(bad, skeleton, "lib.yaml")
    with pytest.raises(gsik.PoseError, match="library: must be a list of named poses"):
        pose_from_yaml(text.split("library:")[0] + "library: 3\n", skeleton, "lib.yaml")


def test_an_out_of_limit_angle_in_a_library_pose_is_clamped_with_a_warning(skeleton, library):
    text = pose_to_yaml(_pose(skeleton, 0), library[:1])
    head, lib = text.split("library:")
    lines = lib.splitlines()
    i = next(k for k, line in enumerate(lines) if line.strip().startswith("left_knee.x:"))
    lines[i] = "      left_knee.x: 9.0"
    read = pose_from_yaml(head + "library:" + "\n".join(lines) + "\n", skeleton, "lib.yaml")
    assert len(read.warnings) == 1 and "library.0.joints.left_knee.x: angle 9.0 rad" in read.warnings[0]
