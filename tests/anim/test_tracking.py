"""Tests for gsik.anim.tracking: following a clip's own effector poses, warm-started."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
import gsik.io.bvh
from gsik.io.bvh import format_bvh, parse_bvh
from gsik.io.bvh_skeleton import import_bvh, motion_to_bvh
from gsik.errors import SolverError
from gsik.anim.motion import Motion
from gsik.rotations import matrix_from_rotvec
from gsik.anim.tracking import TrackResult, track_clip

SIX = ("head", "pelvis", "left_hand", "right_hand", "left_foot", "right_foot")


def smooth_biped_motion(sk: gsik.Skeleton, n_frames: int, seed: int) -> Motion:
    """Slow sinusoids within the limits (at most ~0.03 rad per frame at 30 fps), the hips walking along x."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames) / 30.0
    half = 0.5 * (sk.upper - sk.lower)
    q = np.clip(sk.rest + 0.25 * half * np.sin(2 * np.pi * rng.uniform(0.1, 0.4, sk.n_dofs) * t[:, None]
                                                  + rng.uniform(0, 2 * np.pi, sk.n_dofs)), sk.lower, sk.upper)
    W = np.tile(np.eye(4), (n_frames, 1, 1))
    W[:, :3, :3] = [matrix_from_rotvec([0.0, 0.0, 0.3 * np.sin(s)]) for s in t]
    W[:, :3, 3] = np.c_[0.5 * t, np.zeros(n_frames), np.full(n_frames, 0.95)]
    return Motion(sk, q, ("hips",) * n_frames, W, 1.0 / 30.0)


@pytest.fixture(scope="module")
def reimported():
    """A smooth biped clip exported to BVH text (cm) and imported back."""
    biped = gsik.load_skeleton("biped")
    text = format_bvh(motion_to_bvh(smooth_biped_motion(biped, 60, seed=1), units="cm"))
    return import_bvh(parse_bvh(text))


def test_a_reimported_clip_is_tracked_closely(reimported):
    # The plain solver measure: warm-started from the rest pose, no posture.
    result = track_clip(reimported.skeleton, reimported.motion, effectors=SIX, follow_clip=False)
    assert isinstance(result, TrackResult)
    F = reimported.motion.n_frames
    assert result.effector_names == ("head", "pelvis", "left_hand", "right_hand", "left_foot", "right_foot")
    assert result.position_errors.shape == (F, 6) and result.orientation_errors.shape == (F, 6)
    assert result.frame_seconds.shape == (F,) and np.all(result.frame_seconds > 0)
    assert result.statuses[0] is gsik.Status.CONVERGED
    after_start = result.position_errors[5:].max(axis=1)
    assert after_start.max() < 0.01
    assert np.median(after_start) < 0.001
    assert result.orientation_errors[5:].max() < 0.05
    summary = result.summary()
    assert summary.frames == F - 1
    assert summary.max_position_error == pytest.approx(result.position_errors[1:].max())
    assert summary.mean_position_error == pytest.approx(result.position_errors[1:].mean())
    assert summary.median_frame_seconds == pytest.approx(np.median(result.frame_seconds[1:]))
    assert np.all(result.steps[1:] >= 1) and np.all(result.steps[1:] <= 5)


def test_the_solved_motion_reaches_the_targets_it_reports(reimported):
    result = track_clip(reimported.skeleton, reimported.motion, effectors=["left_hand", "right_foot"],
                        steps_per_frame=2)
    solved = result.motion
    assert solved.skeleton is reimported.skeleton
    assert solved.roots == ("hips",) * solved.n_frames
    np.testing.assert_allclose(solved.world_from_root, reimported.motion.world_from_root, atol=1e-12)
    sk = reimported.skeleton
    for f in (0, 17, 59):
        got = solved.frames(f)[1][[sk.frame_of("left_hand"), sk.frame_of("right_foot")]]
        want = reimported.motion.frames(f)[1][[sk.frame_of("left_hand"), sk.frame_of("right_foot")]]
        np.testing.assert_allclose(np.linalg.norm(got - want, axis=1), result.position_errors[f], atol=1e-12)
    assert np.all(solved.q >= sk.lower - 1e-12) and np.all(solved.q <= sk.upper + 1e-12)


def test_a_foot_can_be_the_root_pinned_where_the_clip_has_it(reimported):
    result = track_clip(reimported.skeleton, reimported.motion, effectors=SIX, root="right_foot")
    assert "right_foot" not in result.effector_names  # the root is pinned, not tracked
    sk = reimported.skeleton
    foot = sk.frame_of("right_foot")
    np.testing.assert_allclose(result.motion.positions()[:, foot], reimported.motion.positions()[:, foot],
                               atol=1e-9)
    assert result.position_errors[5:].max() < 0.01


def test_tracking_retargets_onto_another_skeleton_by_name(reimported):
    biped = gsik.load_skeleton("biped")  # the original, with its real joint limits
    result = track_clip(biped, reimported.motion, effectors={"left_hand": "left_hand", "head": "head"},
                        root="pelvis", position_only=True)
    assert result.motion.skeleton is biped
    assert np.all(result.orientation_errors == 0.0)
    assert result.position_errors[5:].max() < 0.01


def test_tracking_defaults_to_the_effectors_both_skeletons_share(reimported):
    result = track_clip(reimported.skeleton, reimported.motion, steps_per_frame=1)
    expected = tuple(n for n in reimported.skeleton.effector_sites if n != "hips")
    assert result.effector_names == expected


def test_tracking_rejects_unknown_names_and_bad_arguments(reimported):
    sk, motion = reimported.skeleton, reimported.motion
    with pytest.raises(SolverError, match="'nose' is not an effector of skeleton 'bvh'; effectors: 'pelvis'"):
        track_clip(sk, motion, effectors=["nose"])
    with pytest.raises(SolverError, match="has no joint or site 'tail' for effector 'head'"):
        track_clip(sk, motion, effectors={"head": "tail"})
    with pytest.raises(SolverError, match="steps_per_frame must be a whole number >= 1"):
        track_clip(sk, motion, steps_per_frame=0)
    with pytest.raises(SolverError, match="unknown solver setting"):
        track_clip(sk, motion, effectors=["head"], speed=3)
    empty = Motion(sk, np.zeros((0, sk.n_dofs)), (), np.zeros((0, 4, 4)), 0.1)
    with pytest.raises(SolverError, match="no frames"):
        track_clip(sk, empty)


# -- issue 9: keeping the clip's body ---------------------------------------------------------------

DATA = __import__("pathlib").Path(__file__).resolve().parents[1] / "data"


def test_following_the_clip_keeps_every_joint_where_the_clip_has_it(reimported):
    sk, motion = reimported.skeleton, reimported.motion
    kept = track_clip(sk, motion, effectors=["left_hand", "right_foot"])
    assert kept.body_height == pytest.approx(np.median(np.ptp(motion.positions()[:, :, 2], axis=1)))
    assert set(kept.body_names) == set(sk.joint_names) | set(sk.site_names)
    assert kept.body_errors.shape == (motion.n_frames, len(kept.body_names))
    assert kept.body_errors.max() < 1e-3 and kept.position_errors.max() < 1e-3
    assert np.all(kept.steps[1:] == 0)  # the clip's own pose meets its own targets: no step needed
    # The plain solver measure: from the rest pose, no posture; the untracked joints go their own way.
    plain = track_clip(sk, motion, effectors=["left_hand", "right_foot"], follow_clip=False)
    table = plain.body_table()
    assert table[0].max_error > 0.02 and not table[0].tracked
    assert [r.percentile_error for r in table] == sorted((r.percentile_error for r in table), reverse=True)


def test_untracked_dofs_follow_the_clip_exactly(reimported):
    sk, motion = reimported.skeleton, reimported.motion
    result = track_clip(sk, motion, effectors=["left_hand"])
    # The right arm and the legs are not needed by the left hand: they pass through.
    for name in ("right_elbow.x", "left_knee.x", "right_hip.y"):
        d = sk.dof_index(name)
        np.testing.assert_allclose(result.motion.q[:, d], motion.q[:, d], atol=1e-6)


def test_joints_are_targets_with_their_own_priority_and_position_only(reimported):
    sk, motion = reimported.skeleton, reimported.motion
    result = track_clip(sk, motion, effectors=["left_hand", "left_knee", "right_elbow"],
                        position_only=["left_knee"], priorities={"right_elbow": 2}, follow_clip=False)
    assert result.effector_names == ("left_hand", "left_knee", "right_elbow")
    assert np.all(result.orientation_errors[:, 1] == 0.0) and result.orientation_errors[:, 2].max() > 0.0
    assert result.position_errors[5:].max() < 0.01
    with pytest.raises(SolverError, match="position_only names 'head', which is not tracked"):
        track_clip(sk, motion, effectors=["left_hand"], position_only=["head"])
    with pytest.raises(SolverError, match="priorities name 'head', which is not tracked"):
        track_clip(sk, motion, effectors=["left_hand"], priorities={"head": 1})
    with pytest.raises(SolverError, match="priority of 'left_hand' must be a whole number >= 0"):
        track_clip(sk, motion, effectors=["left_hand"], priorities={"left_hand": -1})


def test_a_wrapping_channel_is_followed_continuously():
    clip = gsik.io.bvh.read_bvh(DATA / "wrap_channel.bvh")
    targets = ["LeftHand_end", "LeftFoot_end"]
    unwrapped = import_bvh(clip)
    result = track_clip(unwrapped.skeleton, unwrapped.motion, targets)
    assert result.position_errors.max() < 1e-3 and result.body_errors.max() < 0.01
    plain = track_clip(unwrapped.skeleton, unwrapped.motion, targets, follow_clip=False)
    assert plain.position_errors.max() < 1e-3
    # The solved spine turns continuously through +-180 degrees, as the clip does once unwrapped.
    spine = np.degrees(result.motion.q[:, unwrapped.skeleton.dof_index("Spine.y")])
    assert np.abs(np.diff(spine)).max() < 15 and np.abs(spine).max() > 180


def test_progress_is_called_once_per_frame(reimported):
    calls = []
    track_clip(reimported.skeleton, reimported.motion, effectors=["head"], progress=lambda d, t: calls.append((d, t)))
    F = reimported.motion.n_frames
    assert calls == [(f + 1, F) for f in range(F)]
