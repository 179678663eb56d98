"""Pose files: exact round trips, clear errors for every kind of bad file, atomic saves."""

from __future__ import annotations

import math
import os
import stat

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
from gsik import Target
from gsik.io.pose import Pose, PoseRead, pose_from_yaml, pose_to_yaml, read_pose, write_pose
from gsik.rotations import quaternion_from_matrix


@pytest.fixture(scope="module")
def skeleton():
    return gsik.load_skeleton("biped")


def _pose(skeleton, seed: int = 0) -> Pose:
    """A pose with messy (non-round) numbers everywhere."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(skeleton.lower, skeleton.upper)
    solver = gsik.Solver(skeleton, q0=q)
    W = solver.world_from_root
    targets = {}
    for i, (name, T) in enumerate(solver.effector_poses().items()):
        targets[name] = Target.from_transform(T, enabled=i != 1, weight=float(rng.uniform(0, 3)),
                                                  position_only=i == 2)
    return Pose(skeleton.name, solver.root, tuple(W[:3, 3] + rng.normal(0, 0.1, 3)),
                tuple(quaternion_from_matrix(W[:3, :3])), dict(zip(skeleton.dof_names, q.tolist())), targets)


@pytest.fixture()
def pose(skeleton):
    return _pose(skeleton)


@pytest.fixture()
def text(pose):
    return pose_to_yaml(pose)


def _error(text: str, skeleton, source="bad.yaml") -> str:
    with pytest.raises(gsik.PoseError) as info:
        pose_from_yaml(text, skeleton, source)
    return str(info.value)


# -- round trips ----------------------------------------------------------------

def test_round_trip_through_text_is_exact(skeleton, pose, text):
    read = pose_from_yaml(text, skeleton)
    assert isinstance(read, PoseRead)
    assert read.warnings == ()
    assert read.pose == pose
    assert pose_to_yaml(read.pose) == text


def test_round_trip_through_file_is_exact(skeleton, pose, tmp_path):
    path = tmp_path / "pose.yaml"
    write_pose(path, pose)
    read = read_pose(path, skeleton)
    assert read.pose == pose
    assert read.pose.q(skeleton).tolist() == [pose.joints[n] for n in skeleton.dof_names]
    np.testing.assert_array_equal(read.pose.world_from_root, pose.world_from_root)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False, width=64), min_size=3, max_size=3),
       st.floats(min_value=0.0, max_value=1e6, allow_nan=False))
def test_any_finite_numbers_round_trip_bit_for_bit(skeleton, position, weight):
    pose = _pose(skeleton)
    t = pose.targets["head"].replace(position=position, weight=weight)
    pose = pose.replace(targets={**pose.targets, "head": t}, root_position=position)
    again = pose_from_yaml(pose_to_yaml(pose), skeleton).pose
    assert again == pose
    assert [math.copysign(1, v) for v in again.targets["head"].position] == [math.copysign(1, v) for v in position]


def test_target_priorities_round_trip_and_are_checked(skeleton):
    pose = _pose(skeleton)
    pose = pose.replace(targets={**pose.targets, "left_hand": pose.targets["left_hand"].replace(priority=2)})
    text = pose_to_yaml(pose)
    assert text.count("priority:") == 1  # written only where it is not the default
    assert pose_from_yaml(text, skeleton).pose.targets["left_hand"].priority == 2
    assert "must be a whole number >= 0, got -1" in _error(text.replace("priority: 2", "priority: -1"), skeleton)


def test_written_file_is_readable_and_documented(text, skeleton):
    assert text.startswith("# gsik pose")
    assert "format: 1\n" in text and "skeleton: biped\n" in text
    for name in skeleton.dof_names:
        assert f"\n  {name}: " in text


def test_other_root_round_trips(skeleton):
    solver = gsik.Solver(skeleton)
    solver.set_root("left_foot")
    W = solver.world_from_root
    targets = {n: Target.from_transform(T) for n, T in solver.effector_poses().items()}
    pose = Pose("biped", "left_foot", tuple(W[:3, 3]), tuple(quaternion_from_matrix(W[:3, :3])),
                dict(zip(skeleton.dof_names, solver.q.tolist())), targets)
    read = pose_from_yaml(pose_to_yaml(pose), skeleton).pose
    assert read == pose
    assert "right_foot" in read.targets and "left_foot" not in read.targets


def test_optional_target_fields_default(skeleton, text):
    lean = text.replace("    enabled: true\n", "").replace("    weight: ", "    #weight: ")
    t = pose_from_yaml(lean, skeleton).pose.targets["head"]
    assert t.enabled is True and t.weight == 1.0


def test_slightly_denormalised_quaternion_is_normalised(skeleton, text, pose):
    q = pose.targets["head"].orientation
    bad = text.replace(f"orientation: [{', '.join(repr(v) for v in q)}]",
                       f"orientation: [{', '.join(repr(v * 1.001) for v in q)}]", 1)
    assert bad != text
    got = pose_from_yaml(bad, skeleton).pose.targets["head"].orientation
    assert np.allclose(got, q) and math.isclose(np.linalg.norm(got), 1.0)


# -- warnings -------------------------------------------------------------------

def test_out_of_limit_angle_is_clamped_with_a_warning(skeleton, pose):
    text = pose_to_yaml(pose.replace(joints={**pose.joints, "left_knee.x": 0.75}))
    read = pose_from_yaml(text, skeleton, "p.yaml")
    assert read.pose.joints["left_knee.x"] == skeleton.upper[skeleton.dof_index("left_knee.x")] == 0.0
    assert len(read.warnings) == 1
    w = read.warnings[0]
    assert "p.yaml:" in w and "left_knee.x" in w and "0.75" in w and "clamped" in w


# -- errors ---------------------------------------------------------------------

def test_malformed_yaml_names_the_line(skeleton, text):
    lines = text.splitlines()
    lines[12] = " " + lines[12]  # one space too many: "mapping values are not allowed here"
    msg = _error("\n".join(lines), skeleton)
    assert msg.startswith("bad.yaml:13: not valid YAML")


def test_unclosed_flow_mapping_names_the_line(skeleton):
    msg = _error("format: 1\nskeleton: biped\njoints:\n  a: 1\n  b: {c: 2\n  d: 3\n", skeleton)
    assert msg.startswith("bad.yaml:6: not valid YAML")


@pytest.mark.parametrize("content", ["", "# only a comment\n", "[1, 2, 3]\n", "just text\n"])
def test_empty_or_wrong_top_level(skeleton, content):
    msg = _error(content, skeleton)
    assert "bad.yaml" in msg


def test_unknown_joint_lists_the_valid_ones(skeleton, text):
    msg = _error(text.replace("  waist.x:", "  waist.w:"), skeleton)
    assert "unknown joint 'waist.w'" in msg and "'waist.x'" in msg and "'right_ankle.z'" in msg
    assert msg.startswith("bad.yaml:")


def test_missing_joint_is_named(skeleton, text):
    lines = [ln for ln in text.splitlines() if not ln.startswith("  neck.y:")]
    msg = _error("\n".join(lines), skeleton)
    assert "missing" in msg and "'neck.y'" in msg


def test_unknown_effector_lists_the_valid_ones(skeleton, text):
    msg = _error(text.replace("  left_hand:", "  left_paw:"), skeleton)
    assert "unknown effector 'left_paw'" in msg and "'left_hand'" not in msg.split("valid:")[0]
    assert "'head'" in msg.split("valid:")[1]


def test_target_for_the_root_is_an_error(skeleton, text):
    msg = _error(text.replace("  head:", "  right_foot:"), skeleton)
    assert "'right_foot'" in msg and "IK root" in msg


def test_wrong_skeleton_name(skeleton, text):
    msg = _error(text.replace("skeleton: biped", "skeleton: quadruped"), skeleton)
    assert "'quadruped'" in msg and "'biped'" in msg and "skeleton" in msg


def test_unsupported_format(skeleton, text):
    msg = _error(text.replace("format: 1", "format: 7"), skeleton)
    assert "format" in msg and "7" in msg


@pytest.mark.parametrize("field", ["format", "skeleton", "root", "root_transform", "joints", "targets"])
def test_missing_top_level_field(skeleton, text, field):
    lines = text.splitlines()
    out, skipping = [], False
    for ln in lines:
        if ln.startswith(f"{field}:"):
            skipping = True
            continue
        if skipping and ln.startswith(" "):
            continue
        skipping = False
        out.append(ln)
    msg = _error("\n".join(out), skeleton)
    assert "missing" in msg and repr(field) in msg


def test_missing_target_position(skeleton, text):
    start = text.index("  pelvis:")
    pos = text.index("    position:", start)
    bad = text[:pos] + text[text.index("\n", pos) + 1:]
    msg = _error(bad, skeleton)
    assert "targets.pelvis" in msg and "'position'" in msg


@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf", ".NaN"])
def test_nan_or_inf_angle(skeleton, text, value):
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("  waist.y:"))
    lines[i] = f"  waist.y: {value}"
    msg = _error("\n".join(lines), skeleton)
    assert f"bad.yaml:{i + 1}:" in msg and "joints.waist.y" in msg and "finite" in msg


def test_nan_in_target_position(skeleton, text):
    start = text.index("  head:")
    pos = text.index("    position: [", start)
    end = text.index("]", pos)
    bad = text[:pos] + "    position: [0.0, .nan, 1.0" + text[end:]
    msg = _error(bad, skeleton)
    assert "targets.head.position.1" in msg and "finite" in msg


def test_non_unit_quaternion(skeleton, text):
    start = text.index("  orientation: [")
    bad = text[:start] + "  orientation: [2.0, 0.0, 0.0, 0.0]" + text[text.index("\n", start):]
    msg = _error(bad, skeleton)
    assert "bad.yaml:7: root_transform.orientation: must be a unit quaternion" in msg and "norm 2" in msg


def test_string_where_a_number_belongs(skeleton, text):
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("  waist.z:"))
    lines[i] = "  waist.z: forty"
    msg = _error("\n".join(lines), skeleton)
    assert "joints.waist.z" in msg and "number" in msg and "'forty'" in msg


def test_boolean_flags_must_be_booleans(skeleton, text):
    msg = _error(text.replace("enabled: true", "enabled: 3", 1), skeleton)
    assert "enabled" in msg and "true or false" in msg


def test_negative_weight(skeleton, text):
    start = text.index("  head:")
    i = text.index("    weight: ", start)
    bad = text[:i] + "    weight: -1.0" + text[text.index("\n", i):]
    msg = _error(bad, skeleton)
    assert "targets.head.weight" in msg and ">= 0" in msg


def test_unknown_field(skeleton, text):
    msg = _error(text.replace("    position_only: false", "    position_only: false\n    colour: red", 1), skeleton)
    assert "colour" in msg and "valid fields" in msg


def test_duplicate_key(skeleton, text):
    msg = _error(text.replace("  waist.x:", "  waist.y: 0.0\n  waist.x:"), skeleton)
    assert "duplicate key 'waist.y'" in msg


def test_unknown_root(skeleton, text):
    msg = _error(text.replace("root: right_foot", "root: tail"), skeleton)
    assert "unknown root 'tail'" in msg and "'left_foot'" in msg


def test_read_pose_missing_file_is_a_file_error(skeleton, tmp_path):
    with pytest.raises(gsik.GsikFileError) as info:
        read_pose(tmp_path / "nope.yaml", skeleton)
    assert "nope.yaml" in str(info.value)


def test_read_pose_error_names_the_file(skeleton, tmp_path, text):
    path = tmp_path / "broken.yaml"
    path.write_text(text.replace("skeleton: biped", "skeleton: robot"))
    with pytest.raises(gsik.PoseError) as info:
        read_pose(path, skeleton)
    assert str(path) in str(info.value)


# -- the data classes -------------------------------------------------------------

def test_pose_is_immutable(pose):
    with pytest.raises(Exception):
        pose.root = "left_foot"  # type: ignore[misc]
    with pytest.raises(TypeError):
        pose.joints["waist.x"] = 1.0  # type: ignore[index]
    with pytest.raises(TypeError):
        pose.targets["head"] = None  # type: ignore[index]


def test_pose_rejects_bad_values():
    with pytest.raises(gsik.TargetError):
        Target((0.0, float("nan"), 0.0))
    with pytest.raises(gsik.TargetError):
        Target((0.0, 0.0, 0.0), (2.0, 0.0, 0.0, 0.0))
    with pytest.raises(gsik.TargetError):
        Target((0.0, 0.0, 0.0), weight=-1.0)
    with pytest.raises(gsik.PoseError):
        Pose("biped", "right_foot", (0, 0, 0), (1, 0, 0, 0), {"waist.x": float("inf")}, {})


# -- saving ---------------------------------------------------------------------

def test_failed_write_leaves_the_old_file_byte_identical(pose, tmp_path, monkeypatch):
    path = tmp_path / "pose.yaml"
    path.write_bytes(b"old contents\n")

    def fail(*_args, **_kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", fail)
    with pytest.raises(gsik.GsikFileError) as info:
        write_pose(path, pose)
    assert "No space left" in str(info.value)
    assert path.read_bytes() == b"old contents\n"
    assert os.listdir(tmp_path) == ["pose.yaml"]  # no temporary file left behind


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root ignores directory permissions")
def test_write_into_read_only_directory_fails_cleanly(pose, tmp_path):
    path = tmp_path / "pose.yaml"
    path.write_bytes(b"old\n")
    tmp_path.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        with pytest.raises(gsik.GsikFileError):
            write_pose(path, pose)
    finally:
        tmp_path.chmod(stat.S_IRWXU)
    assert path.read_bytes() == b"old\n"


def test_write_to_missing_directory_fails_cleanly(pose, tmp_path):
    with pytest.raises(gsik.GsikFileError) as info:
        write_pose(tmp_path / "no" / "such" / "dir" / "pose.yaml", pose)
    assert "pose.yaml" in str(info.value)


def test_write_pose_needs_a_pose(tmp_path):
    with pytest.raises(gsik.PoseError):
        write_pose(tmp_path / "x.yaml", {"not": "a pose"})  # type: ignore[arg-type]
    assert not (tmp_path / "x.yaml").exists()
