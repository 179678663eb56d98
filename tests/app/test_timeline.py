"""The timeline model without any display: wall-clock playback, transport, keys and their interpolation."""

from __future__ import annotations

import os

import numpy as np
import pytest

import gsik
from gsik.anim.motion import Motion
from gsik_studio.model import Document
from gsik_studio.model.keys import interpolated_targets, slerp
from gsik_studio.model.timeline import DEFAULT_LENGTH
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.rotations import matrix_from_axis_angle, quaternion_from_matrix

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")


class Clock:
    """A fake clock the test moves by hand [s]."""

    def __init__(self):
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


@pytest.fixture()
def doc():
    d = Document()
    for _ in range(200):
        d.step()
        if not d.needs_solving:
            break
    return d


@pytest.fixture()
def clock(doc):
    c = Clock()
    doc.timeline.clock = c
    return c


def elbow_motion(doc, n=30, frame_time=1 / 30):
    sk = doc.skeleton
    q = np.tile(sk.rest, (n, 1))
    q[:, sk.dof_index("left_elbow.x")] = np.linspace(0.1, 1.5, n)
    W = np.tile(doc.solver.world_from_root, (n, 1, 1))
    W[:, 1, 3] += np.linspace(0.0, 0.6, n)
    return Motion(sk, q, ("right_foot",) * n, W, frame_time)


def test_playing_shows_the_frame_the_clock_says_dropping_frames(doc, clock):
    tl = doc.timeline
    m = elbow_motion(doc)
    tl.load(m, "Reach")
    assert tl.play() and tl.playing and tl.frame == 0
    clock.t += 10.5 / 30  # a slow frame: 10 frames' time went by
    assert tl.tick() and tl.frame == 10
    np.testing.assert_array_equal(doc.q, m.q[10])
    clock.t += 1.0  # past the end: the last frame stays, playing stops
    assert not tl.tick() and not tl.playing and tl.frame == m.n_frames - 1
    np.testing.assert_array_equal(doc.q, m.q[-1])
    assert doc.history.undo_text == "Reach" and tl.clip is m  # kept on the timeline


def test_pause_keeps_the_frame_and_play_goes_on_from_it(doc, clock):
    tl = doc.timeline
    tl.load(elbow_motion(doc), "Reach")
    tl.play()
    clock.t += 5 / 30
    tl.tick()
    tl.pause()
    clock.t += 1.0
    assert not tl.tick() and tl.frame == 5 and doc.playing is None
    tl.play()
    clock.t += 3 / 30
    tl.tick()
    assert tl.frame == 8


def test_stop_goes_back_to_the_first_frame_as_one_undo_step(doc, clock):
    tl = doc.timeline
    m = elbow_motion(doc)
    before = doc.pose()
    tl.load(m, "Reach")
    tl.play()
    clock.t += 12 / 30
    tl.tick()
    tl.stop()
    assert not tl.playing and tl.frame == 0 and doc.playing is None
    np.testing.assert_array_equal(doc.q, m.q[0])
    doc.undo()
    assert doc.pose() == before


def test_loop_starts_over(doc, clock):
    tl = doc.timeline
    tl.load(elbow_motion(doc, n=10), "Reach")
    tl.set_loop(True)
    tl.play()
    clock.t += 13 / 30
    assert tl.tick() and tl.playing and tl.frame == 3


def test_scrub_shows_a_frame_and_is_one_undo_step(doc, clock):
    tl = doc.timeline
    m = elbow_motion(doc)
    before = doc.pose()
    tl.load(m, "Reach")
    for f in (3, 17, 25):
        tl.scrub(f)
    tl.end_scrub()
    np.testing.assert_array_equal(doc.q, m.q[25])
    assert [c.text for c in doc.history.commands] == ["Load Reach", "Scrub Reach"]  # loading is a step of its own
    doc.undo()
    assert doc.pose() == before


def test_an_edit_while_playing_stops_the_clock(doc, clock):
    tl = doc.timeline
    tl.load(elbow_motion(doc), "Reach")
    tl.play()
    clock.t += 4 / 30
    tl.tick()
    doc.set_root("left_foot")
    clock.t += 4 / 30
    assert not tl.tick() and not tl.playing and tl.frame == 4
    assert [c.text for c in doc.history.commands] == ["Load Reach", "Reach", "Root on left foot"]


def test_a_motion_of_another_skeleton_is_refused(doc):
    other = skeleton_from_urdf(os.path.join(DATA, "two_link_arm.urdf"))
    m = Motion(other, np.tile(other.rest, (2, 1)), (other.root,) * 2, np.tile(np.eye(4), (2, 1, 1)), 0.1)
    with pytest.raises(gsik.GsikError, match="skeleton"):
        doc.timeline.load(m, "x")


def test_slerp_halfway_is_half_the_angle():
    q0 = quaternion_from_matrix(np.eye(3))
    q1 = quaternion_from_matrix(matrix_from_axis_angle(np.array([0.0, 0.0, 1.0]), 1.2))
    half = quaternion_from_matrix(matrix_from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.6))
    np.testing.assert_allclose(slerp(q0, q1, 0.5), half, atol=1e-12)
    np.testing.assert_allclose(slerp(q0, -np.asarray(q1), 0.5), half, atol=1e-12)  # the short way


def test_keys_interpolate_targets_and_key_frames_are_exact(doc, clock):
    tl = doc.timeline
    tl.add_key(0)
    start = doc.pose()
    hand = np.array(doc.targets["left_hand"].position)
    doc.move_target("left_hand", hand + [0.0, 0.25, 0.3])
    for _ in range(200):
        doc.step()
    tl.add_key(20)
    end = doc.pose()
    assert tl.n_frames == DEFAULT_LENGTH  # a new document's timeline: keys anywhere on it
    mid = interpolated_targets(start, end, 0.5)["left_hand"].position
    np.testing.assert_allclose(mid, hand + [0.0, 0.125, 0.15], atol=1e-12)
    m = tl.motion
    assert m.n_frames == DEFAULT_LENGTH
    np.testing.assert_array_equal(m.q[0], start.q(doc.skeleton))
    np.testing.assert_array_equal(m.q[20], end.q(doc.skeleton))
    tl.scrub(10)
    got = doc.effector_poses()["left_hand"][:3, 3]
    assert np.linalg.norm(got - mid) < 0.01  # solved from the interpolated target
    # Move and delete keys.
    tl.end_scrub()
    tl.move_key(20, 30)
    assert sorted(tl.keys) == [0, 30] and tl.motion.n_frames == DEFAULT_LENGTH
    np.testing.assert_array_equal(tl.motion.q[-1], tl.motion.q[30])  # frames after the last key hold it
    tl.move_key(30, 120)  # a key past the end makes the timeline longer
    assert tl.n_frames == 121 and tl.key_length == 121
    tl.delete_key(120)
    assert sorted(tl.keys) == [0]
    with pytest.raises(gsik.GsikError, match="no key at frame 7"):
        tl.delete_key(7)


def test_keys_refused_while_a_clip_is_loaded(doc):
    doc.timeline.load(elbow_motion(doc), "Reach")
    with pytest.raises(gsik.GsikError, match="discard"):
        doc.timeline.add_key()
    doc.timeline.discard()
    assert doc.timeline.add_key() == 0


def test_a_new_document_starts_with_an_empty_timeline(doc):
    doc.timeline.add_key(0)
    doc.timeline.add_key(8)
    doc.new()
    assert doc.timeline.keys == {} and doc.timeline.clip is None and doc.timeline.n_frames == DEFAULT_LENGTH
    doc.timeline.load(elbow_motion(doc), "Reach")
    doc.new()
    assert doc.timeline.clip is None and doc.timeline.motion is None


def test_with_no_clip_the_timeline_has_a_length_and_fps_to_key_and_step_anywhere(doc):
    tl = doc.timeline
    assert (tl.n_frames, tl.frame_time, tl.motion) == (DEFAULT_LENGTH, 1 / 30, None)
    tl.scrub(45)  # nothing to show yet: only the current frame moves
    assert tl.frame == 45 and not doc.history.commands
    assert tl.add_key() == 45
    tl.step_frame(-5)
    assert tl.frame == 40
    tl.step_frame(10_000)
    assert tl.frame == DEFAULT_LENGTH - 1
    tl.jump_to_key(-1)
    assert tl.frame == 45
    tl.jump_to_key(-1)  # no key before: stays
    assert tl.frame == 45
    tl.set_length(240)
    tl.set_fps(24)
    assert tl.n_frames == 240 and tl.frame_time == 1 / 24 and tl.motion.n_frames == 240
    assert doc.history.undo_text == "Set timeline to 24 fps"
    with pytest.raises(gsik.GsikError, match=r"timeline's length \(a key is at frame 45\) must be a whole number >= 46"):
        tl.set_length(30)
    for bad in (0.0, -1.0, float("nan"), 5000.0):
        with pytest.raises(gsik.GsikError, match="frames per second"):
            tl.set_fps(bad)
    assert (tl.n_frames, tl.key_fps) == (240, 24)
    doc.undo()
    doc.undo()
    assert (tl.n_frames, tl.key_fps, sorted(tl.keys)) == (DEFAULT_LENGTH, 30, [45])


def test_discarding_a_clip_gives_back_the_keys_timeline(doc):
    tl = doc.timeline
    tl.set_length(60)
    tl.add_key(12)
    tl.load(elbow_motion(doc), "Reach")
    assert tl.n_frames == 30 and tl.keys  # the clip plays; the keys wait under it
    tl.scrub(20)
    tl.end_scrub()
    tl.discard()
    assert tl.clip is None and tl.n_frames == 60 and sorted(tl.keys) == [12] and tl.frame == 20
