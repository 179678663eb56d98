"""What the document keeps besides the pose, without any display: keys, clip and pole targets, each change one undo
step, saved and opened with the pose file (and a bad file changes nothing)."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik.anim.motion import Motion
from gsik_studio.model import Document
from gsik_studio.model.kept import kept_state
from gsik_studio.model.timeline import TimelineState


@pytest.fixture()
def doc():
    return Document()


def texts(doc) -> list[str]:
    return [c.text for c in doc.history.commands[:doc.history.index]]


def elbow_motion(doc, n=12):
    sk = doc.skeleton
    q = np.tile(sk.rest, (n, 1))
    q[:, sk.dof_index("left_elbow.x")] = np.linspace(0.1, 1.5, n)
    W = np.tile(doc.solver.world_from_root, (n, 1, 1))
    W[:, 1, 3] += np.linspace(0.0, 0.6, n)
    return Motion(sk, q, ("right_foot",) * n, W, 1 / 24)


def _reach(doc, dz=0.25):
    doc.move_target("left_hand", np.array(doc.targets["left_hand"].position) + [0.0, 0.1, dz])


def test_add_move_delete_key_are_each_one_undo_step_and_undo_exactly(doc):
    tl = doc.timeline
    tl.add_key(0)
    _reach(doc)
    tl.add_key(20)
    keyed = dict(tl.keys)
    tl.move_key(20, 30)
    tl.delete_key(0)
    assert texts(doc) == ["Add key at frame 0", "Move left hand", "Add key at frame 20", "Move key 20 to 30",
                          "Delete key at frame 0"]
    assert sorted(tl.keys) == [30]
    doc.undo()
    assert sorted(tl.keys) == [0, 30]
    doc.undo()
    assert tl.keys == keyed  # the baked sequence follows the keys back: frame 20 is the key again
    np.testing.assert_array_equal(tl.motion.q[20], np.clip(keyed[20].q(doc.skeleton), doc.skeleton.lower,
                                                           doc.skeleton.upper))
    doc.undo()
    assert sorted(tl.keys) == [0]
    doc.redo()
    doc.redo()
    assert sorted(tl.keys) == [0, 30] and tl.keys[30] == keyed[20]
    tl.move_key(30, 30)  # nowhere: no step
    assert doc.history.undo_text == "Move key 20 to 30"


def test_loading_and_discarding_a_clip_are_each_one_undo_step(doc):
    tl = doc.timeline
    m = elbow_motion(doc)
    shown = []
    tl.events.content.connect(lambda: shown.append((tl.clip, tl.n_frames)))
    tl.load(m, "reach.bvh", "Import reach.bvh")
    tl.scrub(5)
    tl.end_scrub()
    tl.discard()
    assert texts(doc) == ["Import reach.bvh", "Scrub reach.bvh", "Discard reach.bvh"]
    assert tl.clip is None and tl.n_frames == TimelineState().length  # the keys' timeline again
    doc.undo()
    assert tl.clip is m and tl.name == "reach.bvh" and tl.frame == 5  # the frame scrubbed to stays
    assert shown[-1] == (m, 12)
    doc.undo()
    doc.undo()
    assert tl.clip is None and tl.name == "" and doc.pose() == doc.history.commands[0].before
    doc.redo()
    assert tl.clip is m and tl.frame == 5  # undo and redo keep the current frame
    tl.discard()
    tl.discard()  # nothing to discard: no step
    assert doc.history.undo_text == "Discard reach.bvh" and not doc.history.can_redo


def test_pole_on_off_and_a_dragged_pole_are_each_one_undo_step(doc):
    c = doc.controls
    c.set_poles(True)
    start = c.poles["left_knee"].position.copy()
    drag = object()
    for dx in (0.05, 0.1, 0.3):  # one mouse drag: many moves, one step
        c.move_pole("left_knee", start + (dx, 0.0, 0.0), drag)
    doc.end_drag()
    c.set_pole_enabled("right_elbow", False)
    assert texts(doc) == ["Pole targets on", "Move pole left_knee", "Pole right_elbow off"]
    assert "right_elbow" not in doc.solver.targets and "left_knee" in doc.solver.targets
    doc.undo()
    assert "right_elbow" in c.poles and "right_elbow" in doc.solver.targets
    doc.undo()
    np.testing.assert_array_equal(c.poles["left_knee"].position, start)
    # The solver aims the knee at the point of its swing nearest the pole: at the pole's rest place, the knee itself.
    np.testing.assert_allclose(doc.solver.targets["left_knee"].position, c.joint_position("left_knee"), atol=1e-9)
    doc.redo()
    np.testing.assert_array_equal(c.poles["left_knee"].position, start + (0.3, 0.0, 0.0))
    c.set_poles(False)
    assert c.poles == {} and "left_knee" not in doc.solver.targets
    assert texts(doc) == ["Pole targets on", "Move pole left_knee", "Pole targets off"]
    doc.undo()
    assert set(c.poles) == {"left_knee", "right_knee", "left_elbow", "right_elbow"}
    doc.undo()
    doc.undo()
    assert c.poles == {} and not doc.history.can_undo
    with pytest.raises(gsik.TargetError, match="no pole target on 'hips'"):
        c.set_pole_enabled("hips", True)


def _everything(doc):
    """Keys, poles and a library pose in ``doc``; a clip in the returned state's second document."""
    tl = doc.timeline
    tl.add_key(0)
    _reach(doc)
    for _ in range(100):
        doc.step()
    tl.add_key(15)
    doc.controls.set_poles(True)
    doc.controls.move_pole("left_knee", doc.controls.poles["left_knee"].position + (0.2, 0.1, 0.0))
    doc.controls.set_pole_enabled("left_elbow", False)
    doc.library.add("reach")


def _same(a, b) -> None:
    """Two kept states hold the same keys, library and poles, and clips with equal frames."""
    assert a.library == b.library and a.poles == b.poles
    ta, tb = a.timeline, b.timeline
    assert ta._replace(clip=None) == tb._replace(clip=None)
    assert (ta.clip is None) == (tb.clip is None)
    if ta.clip is not None:
        np.testing.assert_array_equal(ta.clip.q, tb.clip.q)
        np.testing.assert_array_equal(ta.clip.world_from_root, tb.clip.world_from_root)
        assert ta.clip.roots == tb.clip.roots and ta.clip.frame_time == tb.clip.frame_time


def test_save_and_open_keep_keys_poles_library_and_the_clip(doc, tmp_path):
    _everything(doc)
    path = tmp_path / "kept.yaml"
    doc.save(path)
    other = Document()
    assert other.open(path) == ()
    _same(kept_state(other), kept_state(doc))
    assert other.pose() == doc.pose() and not other.dirty and not other.history.can_undo
    assert "left_elbow" not in other.solver.targets and "left_knee" in other.solver.targets
    np.testing.assert_array_equal(other.solver.targets["left_knee"].position, doc.solver.targets["left_knee"].position)
    # A clip (and no keys) round-trips too, and the timeline plays it at its own frame time.
    clip_doc = Document()
    clip_doc.timeline.load(elbow_motion(clip_doc), "reach.bvh")
    clip_doc.save(tmp_path / "clip.yaml")
    other.open(tmp_path / "clip.yaml")
    _same(kept_state(other), kept_state(clip_doc))
    assert other.timeline.keys == {} and other.controls.poles == {} and other.library.names == ()
    assert other.timeline.frame_time == 1 / 24 and other.timeline.name == "reach.bvh"


def test_a_key_sequence_keeps_its_fps_and_length(doc, tmp_path):
    doc.timeline.add_key(4)
    doc.save(tmp_path / "k.yaml")
    text = (tmp_path / "k.yaml").read_text()
    assert "  fps: 30.0\n  length: 90\n" in text
    (tmp_path / "k.yaml").write_text(text.replace("  fps: 30.0\n  length: 90\n", "  fps: 12.0\n  length: 9\n"))
    doc.open(tmp_path / "k.yaml")
    tl = doc.timeline
    assert tl.frame_time == 1 / 12 and tl.n_frames == 9 and tl.motion.n_frames == 9
    np.testing.assert_array_equal(tl.motion.q[8], tl.motion.q[4])  # frames after the last key hold it


@pytest.mark.parametrize("old, new, message", [
    ("  left_knee:", "  hips:", "pole target on 'hips': the studio has pole targets on"),
    ("    - frame: 15", "    - frame: 0", "keys.poses.1.frame: a second key at frame 0"),
    ("  fps: 30.0", "  fps: -3.0", "keys.fps: must be from 0.001 to 1000 frames per second"),
])
def test_a_bad_file_changes_nothing(doc, tmp_path, old, new, message):
    _everything(doc)
    path = tmp_path / "bad.yaml"
    doc.save(path)
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    before, kept, history = doc.pose(), kept_state(doc), list(doc.history.commands)
    other = Document()
    other.timeline.load(elbow_motion(other), "mine")
    mine = kept_state(other)
    for d, k in ((doc, kept), (other, mine)):
        with pytest.raises(gsik.PoseError, match=message):
            d.open(path)
        _same(kept_state(d), k)
    assert doc.pose() == before and doc.history.commands == history


def test_new_clears_keys_clip_and_poles(doc):
    _everything(doc)
    doc.new()
    assert doc.timeline.keys == {} and doc.controls.poles == {} and doc.library.names == ()
    assert kept_state(doc) == kept_state(Document()) and "left_knee" not in doc.solver.targets


@pytest.mark.parametrize("frame", [-1, 10**12, 2.5, float("nan"), "3", True])
def test_a_key_at_a_frame_no_file_could_keep_is_refused_and_changes_nothing(doc, frame):
    doc.timeline.add_key(0)
    with pytest.raises(gsik.GsikError, match="a key's frame must be a whole number >= 0 and <= 9999"):
        doc.timeline.add_key(frame)
    with pytest.raises(gsik.GsikError, match="a key's frame must be a whole number"):
        doc.timeline.move_key(0, frame)
    assert sorted(doc.timeline.keys) == [0] and texts(doc) == ["Add key at frame 0"]


@pytest.mark.parametrize("position", [[1e300, 0, 0], [float("nan")] * 3, "up", [0.1, 0.2]])
def test_a_hostile_pole_position_is_refused_and_changes_nothing(doc, position):
    doc.controls.set_poles(True)
    poles = doc.controls.pole_snapshot()
    with pytest.raises(gsik.GsikError):
        doc.controls.move_pole("left_knee", position)
    assert doc.controls.pole_snapshot() == poles and texts(doc) == ["Pole targets on"]


def test_a_timeline_without_keys_keeps_its_length_and_fps_and_old_files_open_as_before(doc, tmp_path):
    doc.save(tmp_path / "plain.yaml")
    assert "keys:" not in (tmp_path / "plain.yaml").read_text()  # a new document's timeline: nothing to save
    doc.timeline.set_length(150)
    doc.timeline.set_fps(25)
    doc.save(tmp_path / "long.yaml")
    assert "keys:\n  fps: 25.0\n  length: 150\n  poses: []\n" in (tmp_path / "long.yaml").read_text()
    other = Document()
    other.open(tmp_path / "long.yaml")
    assert (other.timeline.n_frames, other.timeline.frame_time, other.timeline.keys) == (150, 1 / 25, {})
    other.open(tmp_path / "plain.yaml")  # a file without a keys block: a new document's timeline
    assert (other.timeline.n_frames, other.timeline.key_fps) == (Document().timeline.n_frames, 30.0)
    old = tmp_path / "old.yaml"  # keys written before timelines had their own length: up to the last key
    old.write_text((tmp_path / "long.yaml").read_text().replace("  length: 150\n", ""))
    other.open(old)
    assert other.timeline.n_frames == 1 and other.timeline.key_fps == 25.0
