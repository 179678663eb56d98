"""The document's typed signals and the frame loop, without any display: each signal fires for its change only."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik_studio.model import Document, DocumentEvents, FrameLoop

SIGNALS = DocumentEvents.__slots__


class Recorder:
    """Which of a document's signals fired, in order, since the last :meth:`take`."""

    def __init__(self, doc: Document):
        self.fired: list[str] = []
        for name in SIGNALS:
            getattr(doc.events, name).connect(lambda name=name: self.fired.append(name))

    def take(self) -> set[str]:
        out, self.fired = set(self.fired), []
        return out


def _settled(doc: Document) -> Document:
    for _ in range(500):
        doc.step()
        if not doc.needs_solving:
            break
    return doc


@pytest.fixture()
def doc():
    return _settled(Document())


@pytest.fixture()
def rec(doc):
    return Recorder(doc)


def _up(doc, name, dz):
    return np.array(doc.targets[name].position) + [0.0, 0.0, dz]


def test_moving_a_target_fires_targets_history_and_file_once(doc, rec):
    doc.move_target("head", _up(doc, "head", 0.01))
    assert rec.take() == {"targets", "history", "file"}  # a new undo step; the document became dirty


def test_later_moves_of_one_drag_fire_only_targets(doc, rec):
    doc.move_target("head", _up(doc, "head", 0.01), drag=7)
    rec.take()
    doc.move_target("head", _up(doc, "head", 0.01), drag=7)
    assert rec.fired == ["targets"]  # merged into the same undo step, already dirty


def test_a_second_edit_on_a_dirty_document_does_not_fire_file(doc, rec):
    doc.move_target("head", _up(doc, "head", 0.01))
    rec.take()
    doc.rotate_target("head", "z", 0.1)
    assert rec.take() == {"targets", "history"}


def test_target_options_fire_options_not_targets(doc, rec):
    doc.set_target_options("pelvis", weight=2.5)
    assert rec.take() == {"options", "history", "file"}
    doc.set_target_options("pelvis", weight=2.5)  # no change: no command, no signal
    assert rec.take() == set()


def test_settings_fire_settings_only(doc, rec):
    doc.configure(sweeps=5)
    assert rec.fired == ["settings"]


def test_pose_edits_undo_and_redo_fire_pose_and_history(doc, rec):
    doc.set_root("left_foot")
    assert rec.take() == {"pose", "history", "file"}
    doc.undo()
    assert rec.take() == {"pose", "history", "file"}  # back to the saved state: clean again
    doc.redo()
    assert rec.take() == {"pose", "history", "file"}
    assert doc.undo()
    rec.take()
    assert not doc.undo() and rec.take() == set()  # nothing left to undo: nothing fires


def test_saving_fires_file_only(doc, rec, tmp_path):
    doc.move_target("head", _up(doc, "head", 0.01))
    rec.take()
    doc.save(str(tmp_path / "p.yaml"))
    assert rec.fired == ["file"]
    doc.save()  # same path, already clean: nothing changed
    assert rec.fired == ["file"]


def test_open_and_new_fire_pose_history_and_file(doc, rec, tmp_path):
    path = str(tmp_path / "p.yaml")
    doc.save(path)
    rec.take()
    doc.open(path)
    assert rec.take() == {"pose", "history"}  # same path, clean before and after
    doc.new()
    assert rec.take() == {"pose", "history", "file"}  # the path went away


def test_solver_steps_fire_nothing(doc, rec):
    doc.move_target("head", _up(doc, "head", 0.1))
    rec.take()
    doc.step()
    assert rec.fired == []


def test_playback_fires_pose_per_frame_then_records_one_step(doc, rec):
    frames = [{"head": gsik.Target(_up(doc, "head", 0.01 * k))} for k in range(1, 4)]
    pb = doc.playback(frames, "Nod")
    assert rec.fired == []
    while pb.advance():
        pass
    assert rec.fired[:3] == ["pose", "pose", "pose"]
    assert set(rec.fired[3:]) == {"pose", "history", "file"} and doc.history.undo_text == "Nod"
    assert doc.playing is None


# -- the frame loop ------------------------------------------------------------------------------
@pytest.fixture()
def loop(doc):
    return FrameLoop(doc, readout_interval=3600.0)


def _count(signal) -> list:
    calls = []
    signal.connect(lambda *a: calls.append(a))
    return calls


def test_loop_wakes_on_an_edit_and_steps_until_settled(doc, loop):
    wakes, frames = _count(loop.events.wake), _count(loop.events.frame)
    assert not loop.solve_frame() and frames == []  # settled: no frame
    doc.move_target("left_hand", _up(doc, "left_hand", 0.2))
    assert len(wakes) == 1
    n = 0
    while loop.solve_frame():
        n += 1
        assert n < 500
    assert len(frames) == n + 1 and not doc.needs_solving


def test_paused_loop_does_not_step(doc, loop):
    loop.set_paused(True)
    wakes = _count(loop.events.wake)
    q = doc.q
    doc.move_target("left_hand", _up(doc, "left_hand", 0.2))
    assert wakes == [] and not loop.solve_frame()
    np.testing.assert_array_equal(doc.q, q)
    loop.set_paused(False)
    assert len(wakes) == 1 and loop.solve_frame()


def test_readouts_are_throttled_but_forced_when_the_loop_stops(doc, loop):
    readouts = _count(loop.events.readouts)
    doc.move_target("left_hand", _up(doc, "left_hand", 0.2))
    loop.solve_frame()
    assert len(readouts) == 1  # the first frame after a long pause
    loop.solve_frame()
    assert len(readouts) == 1  # within readout_interval: not again
    while loop.solve_frame():
        pass
    assert len(readouts) == 2  # settled: the final state is shown at once


def test_loop_plays_frames_then_goes_back_to_solving(doc, loop):
    frames = [{"head": gsik.Target(_up(doc, "head", 0.01 * k))} for k in range(1, 3)]
    loop.play(frames, "Nod")
    assert loop.playback is not None and not loop.solving
    assert loop.play_frame() and loop.play_frame()
    assert not loop.play_frame() and loop.playback is None
    assert doc.history.undo_text == "Nod"


def test_a_failing_playback_says_why_and_stops(doc, loop):
    class Broken(dict):
        def items(self):
            raise gsik.GsikError("broken frame")

    messages = _count(loop.events.message)
    loop.play([Broken()], "Bad")
    assert not loop.play_frame()
    assert messages == [("Playback stopped: broken frame",)]
    assert loop.playback is None and doc.history.undo_text == "Bad"
