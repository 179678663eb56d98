"""The bundled biped, the YAML schema's validation, and forward-kinematics invariants."""

import copy

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
from gsik.balance import center_of_mass
from gsik.io.skeleton_yaml import _bundled_dir
from gsik.kinematics import world_frames

from solver_helpers import random_q

BIPED_YAML = (_bundled_dir() / "biped.yaml").read_text()


def biped_dict():
    return yaml.safe_load(BIPED_YAML)


def test_biped_has_the_papers_structure(biped):
    assert biped.n_dofs == 30
    assert len(biped.segment_names) == 14
    ball_joints = [n for n, d in zip(biped.joint_names, biped.joint_dofs) if len(d) == 3]
    assert len(ball_joints) == 8
    assert biped.root == "right_foot"
    assert biped.effector_names == ("head", "pelvis", "left_hand", "right_hand", "left_foot")
    assert biped.with_root("left_foot").effector_names == ("head", "pelvis", "left_hand", "right_hand", "right_foot")


def test_biped_stands_upright_at_rest(biped):
    T = biped.frame_transforms(biped.rest)
    head_top = T[biped.frame_of("head_top"), :3, 3]
    assert 1.70 < head_top[2] < 1.80
    for foot in ("left_foot", "right_foot"):
        assert abs(T[biped.frame_of(foot), 2, 3]) < 1e-3  # soles on the floor
        np.testing.assert_allclose(T[biped.frame_of(foot), :3, :3], np.eye(3), atol=1e-9)  # flat
    assert T[biped.frame_of("right_hand"), 0, 3] > 0 > T[biped.frame_of("left_hand"), 0, 3]


def test_the_biped_has_the_ranges_a_kneel_and_a_deep_squat_need(biped):
    """Human ranges (skeletons/README.md): a kneel needs about 148 deg of hip and 150 deg of knee flexion."""
    for side in ("left", "right"):
        assert biped.upper[biped.dof_index(f"{side}_hip.x")] >= np.radians(148)
        assert biped.lower[biped.dof_index(f"{side}_knee.x")] <= -np.radians(150)
        assert biped.upper[biped.dof_index(f"{side}_ankle.x")] >= np.radians(20)  # dorsiflexion (AAOS: 20 deg)
    # the sides mirror each other: a roll (y) or twist (z) limit changes sign, a pitch (x) limit does not
    for name in biped.dof_names:
        if name.startswith("left_"):
            i, j = biped.dof_index(name), biped.dof_index("right_" + name[5:])
            lo, hi = (biped.lower[i], biped.upper[i]) if name.endswith(".x") else (-biped.upper[i], -biped.lower[i])
            assert (lo, hi) == (biped.lower[j], biped.upper[j]), name


def test_knees_and_elbows_bend_one_way_only(biped):
    for joint, (lo, hi) in {"left_knee.x": (-2.79, 0.0), "right_knee.x": (-2.79, 0.0),
                            "left_elbow.x": (0.0, 2.62), "right_elbow.x": (0.0, 2.62)}.items():
        i = biped.dof_index(joint)
        assert (biped.lower[i], biped.upper[i]) == (lo, hi)
    # A bent knee moves the ankle backwards (-y), a bent elbow moves the hand forwards (+y).
    q = biped.rest.copy()
    q[biped.dof_index("left_knee.x")] = -1.0
    q[biped.dof_index("left_elbow.x")] = 1.0
    T0, T1 = biped.frame_transforms(biped.rest), biped.frame_transforms(q)
    assert T1[biped.frame_of("left_ankle"), 1, 3] < T0[biped.frame_of("left_ankle"), 1, 3] - 0.1
    assert T1[biped.frame_of("left_hand"), 1, 3] > T0[biped.frame_of("left_hand"), 1, 3] + 0.1


def test_ball_joint_expands_into_three_frames_joined_by_zero_length_links(biped):
    names = [f"left_shoulder.{a}" for a in "xyz"]
    frames = [biped.frame_names.index(n) for n in names]
    assert biped.frame_parent[frames[1]] == frames[0] and biped.frame_parent[frames[2]] == frames[1]
    np.testing.assert_array_equal(biped.frame_offset[frames[1]], 0.0)
    np.testing.assert_array_equal(biped.frame_offset[frames[2]], 0.0)
    np.testing.assert_array_equal(biped.frame_axis[frames], np.eye(3))
    assert biped.joint_frame[biped.joint_names.index("left_shoulder")] == frames[2]


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=50, deadline=None)
def test_fk_keeps_bone_lengths_and_ball_joint_centres(biped, seed):
    q = random_q(biped, np.random.default_rng(seed))
    P0 = biped.frame_transforms(biped.rest)[:, :3, 3]
    T = biped.frame_transforms(q)
    P = T[:, :3, 3]
    for a, b in biped.bone_frames:
        assert abs(np.linalg.norm(P[a] - P[b]) - np.linalg.norm(P0[a] - P0[b])) < 1e-12
    # The three frames of a ball joint share one centre; rotations stay orthonormal.
    for j, dofs in zip(biped.joint_names, biped.joint_dofs):
        if len(dofs) < 2:
            continue
        frames = biped.dof_frame[list(dofs)]
        assert np.ptp(P[frames], axis=0).max() < 1e-12, j
    R = T[:, :3, :3]
    np.testing.assert_allclose(np.einsum("nij,nkj->nik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)


def test_fk_matches_a_hand_computed_elbow_bend(biped):
    q = np.zeros(biped.n_dofs)
    q[biped.dof_index("right_elbow.x")] = np.pi / 2
    T = biped.frame_transforms(q)
    elbow = T[biped.frame_of("right_elbow"), :3, 3]
    hand = T[biped.frame_of("right_hand"), :3, 3]
    # Rotating (0, 0, -0.33) by +90 degrees about x gives (0, 0.33, 0).
    np.testing.assert_allclose(hand - elbow, [0.0, 0.33, 0.0], atol=1e-12)


def test_load_by_path_equals_load_by_name(biped, tmp_path):
    p = tmp_path / "copy.yaml"
    p.write_text(BIPED_YAML)
    other = gsik.load_skeleton(p)
    assert other.dof_names == biped.dof_names
    np.testing.assert_array_equal(other.frame_offset, biped.frame_offset)


def test_arrays_are_read_only(biped):
    with pytest.raises(ValueError):
        biped.lower[0] = 0.0


def _mutated(fn):
    d = copy.deepcopy(biped_dict())
    fn(d)
    return d


def _joint(d, name):
    return next(j for j in d["joints"] if j["name"] == name)


BAD_SKELETONS = {
    "unknown parent": (lambda d: _joint(d, "left_knee").update(parent="left_hipp"), "parent 'left_hipp' is not a joint"),
    "cycle": (lambda d: (_joint(d, "hips").update(parent="left_knee")), "cycle"),
    "two tops": (lambda d: _joint(d, "left_hip").update(parent=None), "exactly one joint may have no parent"),
    "duplicate joint": (lambda d: d["joints"].append(dict(_joint(d, "neck"))), "duplicate joint name 'neck'"),
    "duplicate site": (lambda d: d["sites"].append({"name": "head", "parent": "hips"}), "duplicate name 'head'"),
    "lower above upper": (lambda d: _joint(d, "left_knee")["rotations"][0].update(limits=[0.5, -0.5]),
                          "lower limit 0.5 is above upper limit -0.5"),
    "nan offset": (lambda d: _joint(d, "neck").update(offset=[0, float("nan"), 0.3]), "must be finite"),
    "inf limit": (lambda d: _joint(d, "neck")["rotations"][0].update(limits=[-1, float("inf")]), "must be finite"),
    "unknown axis": (lambda d: _joint(d, "neck")["rotations"][0].update(axis="w"), "axis must be x, y, z"),
    "missing joints": (lambda d: d.pop("joints"), "missing field 'joints'"),
    "missing limits": (lambda d: _joint(d, "neck")["rotations"][0].pop("limits"), "missing field 'limits'"),
    "missing name": (lambda d: d.pop("name"), "missing field 'name'"),
    "unknown field": (lambda d: _joint(d, "neck").update(lenght=3), "unknown field 'lenght'"),
    "rest outside limits": (lambda d: _joint(d, "left_knee")["rotations"][0].update(rest=1.0),
                            "rest angle 1.0 is outside the limits"),
    "offset not a vector": (lambda d: _joint(d, "neck").update(offset=[1, 2]), "offset must be a list of 3 numbers"),
    "text for a number": (lambda d: _joint(d, "neck").update(offset=[0, "up", 1]), "offset[1] must be a number"),
    "unknown effector": (lambda d: d["effectors"].append("tail"), "effector 'tail' is not a site"),
    "unknown root": (lambda d: d.update(root="tail"), "root 'tail' is not a joint or site"),
    "bad segment end": (lambda d: d["segments"].append({"name": "x", "from": "hips", "to": "nose"}),
                        "'nose' is not a joint or site"),
    "site on unknown joint": (lambda d: d["sites"].append({"name": "nose", "parent": "face"}),
                              "parent 'face' is not a joint"),
    "zero axis": (lambda d: _joint(d, "neck")["rotations"][0].update(axis=[0, 0, 0]), "axis must not be zero"),
    "bad quaternion": (lambda d: _joint(d, "neck").update(orientation=[2, 0, 0, 0]), "unit quaternion"),
    "wrong units": (lambda d: d.update(units="cm"), "units must be 'm'"),
    "negative mass": (lambda d: _segment(d, "head").update(mass=-1.0), "mass must be finite and >= 0"),
    "mass over a moving joint": (lambda d: d["segments"].append({"name": "leg", "from": "left_hip",
                                                                 "to": "left_ankle", "mass": 5.0}),
                                 "segment 'leg' has a mass but its points are not fixed in one joint's frame"),
    "sole of two corners": (lambda d: _site(d, "left_foot").update(sole=[[0, 0], [1, 0]]),
                            "sole must be at least 3 finite [x, y] corners"),
    "sole on a line": (lambda d: _site(d, "left_foot").update(sole=[[0, 0], [1, 0], [2, 0]]), "lie on one line"),
    "future format": (lambda d: d.update(format=99), "format 99 is not supported"),
}


def _segment(d, name):
    return next(s for s in d["segments"] if s["name"] == name)


def _site(d, name):
    return next(s for s in d["sites"] if s["name"] == name)


def test_biped_weighs_73_kg_with_its_centre_of_mass_at_hip_height(biped):
    assert biped.total_mass == pytest.approx(73.0)
    assert sorted(biped.soles) == ["left_foot", "right_foot"]
    c = center_of_mass(biped.mass_model, *world_frames(biped, biped.rest))
    assert abs(c[0]) < 1e-9 and 0.9 < c[2] < 1.05  # on the mid-plane, about 56% of 1.75 m


def test_target_names_are_the_joints_and_sites(biped):
    assert set(biped.target_names) == set(biped.joint_names) | set(biped.site_names)


@pytest.mark.parametrize("case", sorted(BAD_SKELETONS))
def test_invalid_skeleton_raises_one_clear_error(case):
    mutate, expected = BAD_SKELETONS[case]
    text = yaml.safe_dump(_mutated(mutate), sort_keys=False)
    with pytest.raises(gsik.SkeletonError) as info:
        gsik.skeleton_from_yaml(text, source="bad.yaml")
    message = str(info.value)
    assert message.startswith("bad.yaml: ")
    assert expected in message


def test_malformed_yaml_names_the_line():
    with pytest.raises(gsik.SkeletonError, match=r"bad\.yaml:3: not valid YAML: .*cannot start any token"):
        gsik.skeleton_from_yaml("name: x\njoints:\n\t- a\n", source="bad.yaml")


def test_unknown_bundled_name_lists_the_valid_ones():
    with pytest.raises(gsik.SkeletonError, match="no bundled skeleton 'quadruped'; bundled: 'biped'"):
        gsik.load_skeleton("quadruped")


def test_missing_file_is_a_skeleton_error(tmp_path):
    with pytest.raises(gsik.SkeletonError, match="cannot read skeleton file"):
        gsik.load_skeleton(tmp_path / "nope.yaml")


def test_unknown_names_list_the_choices(biped):
    with pytest.raises(gsik.SkeletonError, match="no joint or site 'elbow'.*'left_elbow'"):
        biped.frame_of("elbow")
    with pytest.raises(gsik.SkeletonError, match="no degree of freedom 'left_knee.y'"):
        biped.dof_index("left_knee.y")


def test_chain_length_bounds_how_far_apart_any_pose_puts_two_frames():
    sk = gsik.load_skeleton("biped")
    L = sk.chain_length
    np.testing.assert_allclose(L, L.T)
    assert np.all(np.diag(L) == 0.0)
    rng = np.random.default_rng(7)
    reached = np.zeros_like(L)
    for _ in range(200):
        p = sk.frame_transforms(rng.uniform(sk.lower, sk.upper))[:, :3, 3]
        reached = np.maximum(reached, np.linalg.norm(p[:, None] - p[None], axis=2))
    assert np.all(reached <= L + 1e-12)
    shoulder, hand = sk.frame_of("left_shoulder"), sk.frame_of("left_hand")
    assert reached[shoulder, hand] > 0.99 * L[shoulder, hand]  # the straight arm reaches its bound
