"""Pose files with keys, poles and a clip: exact round trips, files without them still read, bounded, clear errors."""

from __future__ import annotations

import os

import numpy as np
import pytest

import gsik
from gsik.anim.motion import Motion
from gsik.io.pose import Clip, KeySequence, Pole, pose_from_yaml, pose_to_yaml, read_pose, write_pose
from gsik.io.pose.sequence import MAX_SEQUENCE_FRAMES
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.io.yaml_safe import MAX_CHARS
from gsik.rotations import matrix_from_axis_angle

from test_pose import _pose  # a pose with messy numbers  # noqa: E402

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")


@pytest.fixture(scope="module")
def skeleton():
    return gsik.load_skeleton("biped")


def _clip(skeleton, n=6, seed=0) -> Clip:
    """A clip with messy numbers: random angles, a turning and travelling root that swaps feet."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(skeleton.lower, skeleton.upper, (n, skeleton.n_dofs))
    W = np.tile(np.eye(4), (n, 1, 1))
    for i in range(n):
        axis = rng.normal(size=3)
        W[i, :3, :3] = matrix_from_axis_angle(axis / np.linalg.norm(axis), rng.uniform(-3, 3))
        W[i, :3, 3] = rng.normal(0, 1, 3)
    roots = tuple("left_foot" if i % 2 else "right_foot" for i in range(n))
    return Clip("walk: take 2.bvh", Motion(skeleton, q, roots, W, 1 / 120))


@pytest.fixture()
def everything(skeleton):
    keys = KeySequence(((0, _pose(skeleton, 1)), (7, _pose(skeleton, 2)), (40, _pose(skeleton, 3))), 24.0, 61)
    poles = {"left_knee": Pole((0.1234567891, -0.3, 0.45), True), "right_elbow": Pole((-1e-7, 2.5, 1.0), False)}
    return dict(keys=keys, poles=poles, clip=_clip(skeleton))


def _same_clip(a: Clip, b: Clip) -> None:
    assert a.name == b.name and a.motion.roots == b.motion.roots and a.motion.frame_time == b.motion.frame_time
    np.testing.assert_array_equal(a.motion.q, b.motion.q)
    np.testing.assert_array_equal(a.motion.world_from_root, b.motion.world_from_root)


def test_keys_poles_and_clip_round_trip_exactly(skeleton, everything, tmp_path):
    pose = _pose(skeleton, 0)
    library = (("reach", _pose(skeleton, 4)),)
    path = tmp_path / "all.yaml"
    write_pose(path, pose, library, **everything)
    read = read_pose(path, skeleton)
    assert read.pose == pose and read.library == library and read.warnings == ()
    assert read.keys == everything["keys"] and dict(read.poles) == everything["poles"]
    _same_clip(read.clip, everything["clip"])
    assert pose_to_yaml(read.pose, read.library, read.keys, read.poles, read.clip) == path.read_text()


def test_a_file_without_them_reads_as_before(skeleton):
    pose = _pose(skeleton, 0)
    text = pose_to_yaml(pose)
    assert not any(k in text for k in ("keys:", "poles:", "clip:"))
    read = pose_from_yaml(text, skeleton)
    assert read.pose == pose and read.keys is None and dict(read.poles) == {} and read.clip is None


def test_fps_and_length_default_and_an_empty_key_list_reads(skeleton):
    text = pose_to_yaml(_pose(skeleton, 0), keys=KeySequence(((3, _pose(skeleton, 1)),)))
    assert "fps: 30.0" in text and "length: 4" in text
    bare = text.replace("  fps: 30.0\n", "").replace("  length: 4\n", "")
    assert pose_from_yaml(bare, skeleton).keys == KeySequence(((3, _pose(skeleton, 1)),), 30.0, 4)
    empty = pose_from_yaml(pose_to_yaml(_pose(skeleton, 0), keys=KeySequence(())), skeleton)
    assert empty.keys == KeySequence((), 30.0, 0)


def _replace(text: str, old: str, new: str) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize("old, new, message", [
    ("    - frame: 7", "    - frame: 0", r"bad.yaml:\d+: keys.poses.1.frame: a second key at frame 0"),
    ("    - frame: 7", f"    - frame: {MAX_SEQUENCE_FRAMES}", r"keys.poses.1.frame: must be a whole number from 0 to"),
    ("    - frame: 7", "    - frame: 7.0", r"keys.poses.1.frame: must be a whole number"),
    ("  length: 61", "  length: 12", r"keys.length: must be at least the last key's frame \+ 1 \(41\), got 12"),
    ("  length: 61", "  length: 10000000000", r"keys.length: must be a whole number from 0 to 10000"),
    ("  fps: 24.0", "  fps: 0", r"keys.fps: must be from 0.001 to 1000 frames per second, got 0"),
    ("  fps: 24.0", "  fps: .nan", r"keys.fps: must be a finite number"),
    ("  left_knee:", "  left_kneee:", r"poles.left_kneee: unknown joint 'left_kneee'; valid: "),
    ("    enabled: false\nclip:", "    enabled: 0\nclip:", r"poles.right_elbow.enabled: must be true or false"),
    ("    position: [0.1234567891", "    position: [1.0e+7", r"poles.left_knee.position: must be within"),
    ("  frame_time: 0.008333333333333333", "  frame_time: -1.0",
     r"clip.frame_time: must be from 0.0001 to 1000 seconds, got -1.0"),
    ("  dofs: [waist.x, ", "  dofs: [", r"clip.dofs: must list the skeleton's 30 DOFs in its order"),
    ("    - root: left_foot", "    - root: knee", r"clip.frames.1.root: unknown root 'knee'"),
    ("      world_from_root: [[", "      world_from_root: [[0.0, 0.0, 0.0, 0.0], [",
     r"clip.frames.0.world_from_root: must be 3 rows of 4 numbers \(rotation \| position\), got 4 rows"),
    ("      world_from_root: [[", "      world_from_root: [[true, ", r"clip.frames.0.world_from_root.0: must be a list "
                                                                      r"of 4 numbers"),
    ("      angles: [", "      angles: [1.0, ", r"clip.frames.0.angles: must be a list of 30 numbers"),
    ("  frames:\n", "  frames: []\n  x:\n",
     r"clip.x: unknown field; valid fields: 'name', 'frame_time', 'dofs', 'frames'"),
])
def test_errors_name_the_file_line_field_and_value(skeleton, everything, old, new, message):
    text = _replace(pose_to_yaml(_pose(skeleton, 0), **everything), old, new)
    with pytest.raises(gsik.PoseError, match=message):
        pose_from_yaml(text, skeleton, "bad.yaml")


_ROTATION = r"the first three columns must be a rotation \(orthonormal within 1e-06, determinant \+1\)"


@pytest.mark.parametrize("field, line, message", [
    ("world_from_root", "      world_from_root: [[1.5, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]",
     _ROTATION),
    ("world_from_root", "      world_from_root: [[1.0, 0.0, 0.0, 2.0e+6], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]",
     r"must .*within 1e\+06 m of the origin"),
    ("root", "    - root: waist.x", r"unknown root 'waist.x'; valid: any joint or site"),
])
def test_a_clip_frame_the_reader_refuses_is_never_written(skeleton, everything, field, line, message):
    m = everything["clip"].motion
    W, roots = m.world_from_root.copy(), list(m.roots)
    if field == "root":
        roots[2] = "waist.x"  # a rotation's frame: Motion takes it, a pose file does not
    else:
        W[2, :3] = [[float(v) for v in row.split(", ")] for row in line.split("[[")[1].split("]]")[0].split("], [")]
    bad = Clip("c", Motion(skeleton, m.q, tuple(roots), W, m.frame_time))
    with pytest.raises(gsik.PoseError, match=rf"gsik would not read this pose file back \(clip.frames.2.{field}: "
                                             + message):
        pose_to_yaml(_pose(skeleton, 0), clip=bad)
    lines = pose_to_yaml(_pose(skeleton, 0), clip=everything["clip"]).splitlines()
    k = [i for i, text in enumerate(lines) if text.strip().startswith(("- root:", "world_from_root:")[field != "root"])]
    lines[k[2]] = line  # frame 2's
    with pytest.raises(gsik.PoseError, match=rf"bad.yaml:\d+: clip.frames.2.{field}: " + message):
        pose_from_yaml("\n".join(lines) + "\n", skeleton, "bad.yaml")


def test_an_empty_clip_is_refused(skeleton, everything):
    text = pose_to_yaml(_pose(skeleton, 0), clip=everything["clip"])
    with pytest.raises(gsik.PoseError, match=r"clip.frames: must hold at least one frame"):
        pose_from_yaml(text.split("  frames:")[0] + "  frames: []\n", skeleton, "bad.yaml")


def test_an_out_of_limit_angle_in_a_key_is_clamped_with_a_warning(skeleton):
    text = pose_to_yaml(_pose(skeleton, 0), keys=KeySequence(((5, _pose(skeleton, 1)),)))
    head, keys = text.split("keys:")
    lines = keys.split("\n")
    i = next(k for k, line in enumerate(lines) if line.strip().startswith("left_knee.x:"))
    lines[i] = lines[i].split(":")[0] + ": 9.0"
    read = pose_from_yaml(head + "keys:" + "\n".join(lines), skeleton, "k.yaml")
    assert len(read.warnings) == 1 and "keys.poses.0.joints.left_knee.x: angle 9.0 rad" in read.warnings[0]


def test_an_alias_bomb_in_a_clip_is_refused_by_the_bounded_reader(skeleton, everything):
    text = pose_to_yaml(_pose(skeleton, 0), clip=everything["clip"])
    head = text.split("  frames:")[0]
    bomb = ["  frames: &f0 [" + ", ".join(["1.0"] * 10) + "]"]
    bomb += [f"  x{k}: &f{k} [" + ", ".join([f"*f{k - 1}"] * 10) + "]" for k in range(1, 9)]
    with pytest.raises(gsik.PoseError, match="bad.yaml"):
        pose_from_yaml(head + "\n".join(bomb) + "\n", skeleton, "bad.yaml")


def test_a_clip_too_long_to_read_back_is_refused_at_save_and_nothing_is_written(skeleton, tmp_path):
    n = MAX_CHARS // 900 + 200  # a biped frame takes about 900 characters
    long = _clip(skeleton, n=n)
    path = tmp_path / "long.yaml"
    path.write_text("old\n")
    with pytest.raises(gsik.PoseError, match=rf"the clip 'walk: take 2.bvh' has {n} frames.*discard or shorten"):
        write_pose(path, _pose(skeleton, 0), clip=long)
    assert path.read_text() == "old\n"


def test_keys_or_a_clip_of_another_skeleton_are_refused_at_save(skeleton):
    arm = skeleton_from_urdf(os.path.join(DATA, "two_link_arm.urdf"))
    pose = _pose(skeleton, 0)
    with pytest.raises(gsik.PoseError, match="key at frame 2 is for skeleton 'other'"):
        pose_to_yaml(pose, keys=KeySequence(((2, pose.replace(skeleton="other")),)))
    clip = Clip("c", Motion(arm, arm.rest[None], (arm.root,), np.eye(4)[None], 0.1))
    with pytest.raises(gsik.PoseError, match=f"clip 'c' is for skeleton '{arm.name}', not 'biped'"):
        pose_to_yaml(pose, clip=clip)
