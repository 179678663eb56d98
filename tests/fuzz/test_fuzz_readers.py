"""Every reader against hostile files: read, or refused with a GsikError naming the file (and line); nothing else."""

from __future__ import annotations

import functools
import random

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gsik
from fuzzing import HOSTILE, MAX_MESSAGE, check_refusal, fuzz, pose_of, seeds
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import import_bvh
from gsik.io.pose import pose_from_yaml, read_pose, write_pose
from gsik.io.urdf import read_urdf
from gsik.io.urdf_skeleton import skeleton_from_urdf


@pytest.fixture(scope="module")
def biped():
    return gsik.load_skeleton("biped")


# -- mutation fuzzing: a few hundred files per reader (benchmarks/fuzz_long.py runs thousands) ----------------

@pytest.mark.parametrize("kind, n", [("pose", 250), ("skeleton", 250), ("bvh", 400), ("urdf", 400)])
def test_mutated_files_are_read_or_refused_with_a_clear_error(kind, n):
    outcome = fuzz(kind, n, seed=2024)
    shown = [(problem, text[:200]) for text, problem, _ in outcome.crashes[:3]]
    assert outcome.crashes == [], shown
    assert outcome.refused > n // 10  # the mutations do reach the checks
    assert outcome.total == n


@pytest.mark.parametrize("kind, suffix", [("pose", ".yaml"), ("skeleton", ".yaml"), ("bvh", ".bvh"),
                                          ("urdf", ".urdf")])
def test_files_of_mangled_bytes_are_refused_naming_the_file(kind, suffix, tmp_path, biped):
    read = {"pose": lambda p: read_pose(p, biped), "skeleton": gsik.load_skeleton,
            "bvh": lambda p: import_bvh(read_bvh(p)), "urdf": lambda p: skeleton_from_urdf(read_urdf(p))}[kind]
    rng = random.Random(7)
    data = seeds()[kind][0].encode("utf-8")
    for i in range(60):
        mangled = bytearray(data)
        for _ in range(rng.randint(1, 3)):
            at = rng.randrange(len(mangled))
            mangled[at:at + rng.randint(1, 4)] = bytes(rng.randrange(256) for _ in range(rng.randint(0, 4)))
        if i % 10 == 0:
            mangled = bytes(mangled).decode("utf-8", "replace").encode(rng.choice(["utf-16", "utf-32", "cp1252"]),
                                                                         "replace")
        path = tmp_path / f"mangled{i}{suffix}"
        path.write_bytes(bytes(mangled))
        try:
            read(path)
        except Exception as exc:  # noqa: BLE001 - the contract under test
            assert check_refusal(exc, str(path)) is None, (check_refusal(exc, str(path)), str(exc)[:300])


# -- the hostile files, through the readers a user's file goes through --------------------------------------

YAML_FIXTURES = [
    ("alias_bomb_pose.yaml", 10, "more than 1,000,000 values (counting what aliases repeat)"),
    ("alias_bomb_skeleton.yaml", 9, "more than 1,000,000 values (counting what aliases repeat)"),
    ("self_alias.yaml", 2, "alias *s refers to a list or mapping it is inside of"),
    ("deep_nesting.yaml", 3, "nested deeper than"),
    ("deep_mapping.yaml", 35, "nested deeper than"),
    ("huge_int_pose.yaml", 1, "is too large"),
    ("huge_int_skeleton.yaml", 5, "is too large"),
    ("huge_float.yaml", 5, "is too large for a float"),
    ("python_tag.yaml", 2, "is not allowed"),
    ("custom_tag.yaml", 2, "is not allowed"),
    ("merge_key.yaml", 4, "merge keys"),
    ("two_documents.yaml", 3, "one YAML document"),
    ("nul_byte.yaml", 2, "U+0000"),
]


@pytest.mark.parametrize("name, line, words", YAML_FIXTURES)
def test_hostile_yaml_is_refused_by_the_skeleton_and_pose_readers(name, line, words, biped):
    path = str(HOSTILE / name)
    for read, error in ((gsik.load_skeleton, gsik.SkeletonError), (lambda p: read_pose(p, biped), gsik.PoseError)):
        with pytest.raises(error) as info:
            read(path)
        assert str(info.value).startswith(f"{path}:{line}: ") and words in str(info.value)
        assert len(str(info.value)) < 400


@pytest.mark.parametrize("name", ["utf16_bom.yaml", "latin1_name.yaml"])
def test_text_that_is_not_utf8_is_refused_naming_the_file(name):
    with pytest.raises(gsik.GsikError, match="not UTF-8"):
        gsik.load_skeleton(str(HOSTILE / name))


def test_a_utf8_byte_order_mark_is_read():
    with pytest.raises(gsik.SkeletonError, match="missing field 'joints'"):  # read past the mark
        gsik.load_skeleton(str(HOSTILE / "utf8_bom.yaml"))


def test_a_million_character_name_gives_a_short_message(tmp_path):
    path = tmp_path / "long.yaml"
    path.write_text("format: 1\nname: " + "n" * 1_000_000 + "\njoints: 7\n", encoding="utf-8")
    with pytest.raises(gsik.SkeletonError) as info:
        gsik.load_skeleton(path)
    assert "joints" in str(info.value) and len(str(info.value)) < 400


@pytest.mark.parametrize("name, line", [("huge_offset.bvh", 4), ("huge_motion.bvh", 15)])
def test_bvh_numbers_beyond_float_are_refused_with_their_line(name, line):
    path = str(HOSTILE / name)
    with pytest.raises(gsik.BvhError) as info:
        read_bvh(path)
    assert str(info.value).startswith(f"{path}:{line}: ") and "1e400" in str(info.value)


@pytest.mark.parametrize("name, words", [("bogus_encoding.urdf", "no-such-codec"), ("overflow_axis.urdf", "1e400"),
                                         ("xml_bomb.urdf", "")])
def test_hostile_urdf_is_refused_naming_the_file(name, words):
    path = str(HOSTILE / name)
    with pytest.raises(gsik.UrdfError) as info:
        skeleton_from_urdf(read_urdf(path))
    assert path in str(info.value) and words in str(info.value)
    assert len(str(info.value)) < 400


def test_a_urdf_axis_of_huge_components_is_normalised_without_overflow():
    robot = read_urdf(HOSTILE / "huge_axis.urdf")
    assert robot.joints[0].axis.tolist() == pytest.approx([2**-0.5, 2**-0.5, 0.0])
    skeleton = skeleton_from_urdf(robot)
    assert skeleton.frame_axis[skeleton.dof_frame[0]].tolist() == pytest.approx([2**-0.5, 2**-0.5, 0.0])


# -- names of any characters save and read back exactly ----------------------------------------------------

def test_bvh_names_of_yaml_syntax_survive_a_pose_round_trip(tmp_path):
    skeleton = import_bvh(read_bvh(HOSTILE / "hostile_names.bvh")).skeleton
    assert "[root]" in skeleton.joint_names and "'single" in skeleton.joint_names
    pose = pose_of(skeleton)
    path = tmp_path / "names.yaml"
    write_pose(path, pose)
    assert read_pose(path, skeleton).pose == pose


# -- structured fuzzing: a valid pose with one value replaced by anything ----------------------------------

_hostile_values = (st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=50)
                   | st.lists(st.floats(), max_size=5) | st.dictionaries(st.text(max_size=5), st.integers(),
                                                                         max_size=3)
                   | st.sampled_from([10**400, -(10**20), 2**63, 1e308, -1e308, 5e-324, float("nan")]))


_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)


@functools.cache
def _biped() -> gsik.Skeleton:
    return gsik.load_skeleton("biped")


def _leaves(data, path=()):
    if isinstance(data, dict):
        for k, v in data.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            yield from _leaves(v, path + (i,))
    yield path


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_a_pose_with_any_value_anywhere_is_read_or_refused(data):
    biped = _biped()
    pose = yaml.load(seeds()["pose"][0], Loader=_LOADER)
    path = data.draw(st.sampled_from(sorted(_leaves(pose), key=str)))
    value = data.draw(_hostile_values)
    if path:
        node = pose
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value
    else:
        pose = value
    text = yaml.dump(pose, Dumper=_DUMPER)
    try:
        pose_from_yaml(text, biped, "s.yaml")
    except Exception as exc:  # noqa: BLE001 - the contract under test
        assert check_refusal(exc, "s.yaml") is None, (check_refusal(exc, "s.yaml"), str(exc)[:MAX_MESSAGE])
