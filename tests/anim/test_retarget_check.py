"""Every retarget checks its own result (issue 17, items 3 and 4): rotations, joint errors, planted feet."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gsik import load_skeleton
from gsik.anim.motion import Motion
from gsik.anim.retarget import Retargeter, skeleton_height
from gsik.anim.retarget_check import Tolerances, check_retarget, rotation_check
from gsik.errors import ToleranceError
from gsik.io.bvh import read_bvh

DATA = Path(__file__).resolve().parents[1] / "data"
MAPPING = {"left_hip": "LeftUpLeg", "left_knee": "LeftLeg"}


def _motion(n: int = 5, q=None, W=None) -> Motion:
    sk = load_skeleton("biped")
    q = np.broadcast_to(sk.rest, (n, sk.n_dofs)) if q is None else q
    W = np.broadcast_to(np.eye(4), (n, 4, 4)) if W is None else W
    return Motion(sk, q, ("pelvis",) * n, W, 1 / 30)


def test_a_result_within_tolerance_passes():
    errors = np.full((5, 2), 0.010)
    check = check_retarget(_motion(), errors, MAPPING, 1.75, (0.2, 0.01))
    assert check.ok and check.reasons == () and check.worst_p95 == pytest.approx(0.010)
    check.raise_if_outside()


def test_a_frame_that_is_not_a_rotation_is_named_with_its_clip_frame():
    W = np.broadcast_to(np.eye(4), (5, 4, 4)).copy()
    W[3, :3, :3] = [[1, 0, 0], [1, 0, 0], [0, 0, 0]]  # rank one: a pelvis frame the clip could not define
    assert rotation_check(_motion(W=W)).clip_frame == 3
    check = check_retarget(_motion(W=W), np.zeros((5, 2)), MAPPING, 1.75, (0.0, 0.0))
    assert not check.ok
    with pytest.raises(ToleranceError, match=r"is not a rotation at clip frame 3 .*degenerate frame.*--force"):
        check.raise_if_outside()


def test_joint_errors_over_two_percent_of_the_height_name_the_worst_joints_and_frames():
    errors = np.zeros((40, 2))
    errors[:, 1] = 0.030
    errors[2, 1] = 0.080  # one frame: the p95 stays 30 mm
    assert check_retarget(_motion(40), errors, MAPPING, 1.75, (0.0, 0.0)).ok  # 30 mm p95 < 35 mm
    check = check_retarget(_motion(40), errors, MAPPING, 1.0, (0.0, 0.0))  # 20 mm on a 1 m body
    assert not check.ok and check.joints[0].frame == "left_knee" and check.joints[0].worst_frame == 2
    assert "left_knee (LeftLeg)" in check.message() and "at frame 2" in check.message()
    assert "reason: the mapping" in check.message()
    degenerate = np.zeros(40, dtype=bool)
    degenerate[2] = True
    assert "reason: a degenerate frame" in check_retarget(_motion(40), errors, MAPPING, 1.0, (0, 0),
                                                          degenerate).message()


def test_a_joint_whose_chain_is_at_a_limit_is_blamed_on_the_limit():
    sk = load_skeleton("biped")
    q = np.broadcast_to(sk.rest, (5, sk.n_dofs)).copy()
    q[:, sk.dof_index("left_knee.x")] = sk.lower[sk.dof_index("left_knee.x")]
    errors = np.full((5, 2), 0.1)
    message = check_retarget(_motion(q=q), errors, {"left_knee": "LeftLeg", "left_ankle": "LeftFoot"}, 1.75,
                             (0.0, 0.0)).message()
    assert "reason: a limit (left_knee.x at its lower limit)" in message


def test_sliding_feet_fail_the_check():
    check = check_retarget(_motion(), np.zeros((5, 2)), MAPPING, 1.75, (0.3, 0.3))
    assert not check.ok and "planted feet slide at p95 0.300 m/s" in check.message()
    assert check_retarget(_motion(), np.zeros((5, 2)), MAPPING, 1.75, (0.3, 0.3),
                          tolerances=Tolerances(slide_fraction=0.2)).ok


def test_a_walk_whose_feet_slide_when_retargeted_keeps_them_planted():
    """A long-shinned biped's walk onto the biped: bone directions at the biped's lengths slide the feet at
    0.2 m/s; pinned, they slide ten times less and the result is within its tolerance."""
    clip = read_bvh(DATA / "retarget" / "long_shin_walk.bvh")
    r = Retargeter(load_skeleton("biped"), clip).retarget(clip)
    assert len(r.contacts.spans) >= 8 and r.height == pytest.approx(skeleton_height(load_skeleton("biped")))
    before, after = r.slide
    assert before > 0.1 and after < before / 8, r.slide
    check = r.check()
    assert check.ok, check.reasons
    feet = [r.motion.skeleton.frame_of(f) for f in r.contacts.names]
    at = r.motion.positions()[:, feet]
    for k, a, b in r.contacts.spans:  # each contact holds one place to within millimetres
        assert np.linalg.norm(at[a:b, k] - at[a:b, k].mean(axis=0), axis=-1).max() < 0.005


def test_a_foot_that_creeps_through_a_long_stance_is_released_and_planted_anew():
    """A biped standing 4 s while its body creeps 9 cm forward (2.25 cm/s: slow enough to be planted throughout).
    One pin held at the stance's mean would be 4.5 cm from the clip's feet at either end, over the check's 35 mm;
    released each time a foot leaves its spot by 1% of the height and planted anew, the result passes with the
    feet held still while planted."""
    from gsik.io.bvh_skeleton import motion_to_bvh

    sk = load_skeleton("biped")
    n = 120
    W = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    W[:, 2, 3] = 1.0
    W[:, 1, 3] = np.linspace(0.0, 0.09, n)
    clip = motion_to_bvh(Motion(sk, np.broadcast_to(sk.rest, (n, sk.n_dofs)), ("pelvis",) * n, W, 1 / 30), up="y")
    extra = {"left_shoulder": "left_shoulder", "right_shoulder": "right_shoulder", "atlas": "atlas", "waist": "waist"}
    r = Retargeter(sk, clip, extra).retarget(clip)
    assert r.contacts.planted.mean() > 0.9  # the feet are planted nearly throughout
    feet = [list(r.mapping).index(f) for f in r.contacts.names]
    assert r.errors[:, feet].max() < 0.02 * r.height  # released before a pin is 2% of the height from the clip
    check = r.check()
    assert check.ok, check.reasons
    assert len(r.contacts.spans) >= 8 and r.slide[1] < 0.005, r.slide  # re-planted, and held while planted
