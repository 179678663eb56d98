"""The timeline bar in the real window under Xvfb: real clicks on its buttons and its slider."""

from __future__ import annotations

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui



def _click_slider(qtbot, slider, frame, y=None):
    from PySide6.QtCore import QPoint, Qt

    qtbot.mouseClick(slider, Qt.LeftButton, pos=QPoint(slider.x_of(frame), slider.height() // 4 if y is None else y))


def _drag_slider(qtbot, slider, start_frame, end_frame, y):
    from PySide6.QtCore import QPoint, Qt
    from PySide6.QtTest import QTest

    a, b = QPoint(slider.x_of(start_frame), y), QPoint(slider.x_of(end_frame), y)
    QTest.mousePress(slider, Qt.LeftButton, Qt.NoModifier, a)
    QTest.mouseMove(slider, QPoint((a.x() + b.x()) // 2, y))
    QTest.mouseMove(slider, b)
    QTest.mouseRelease(slider, Qt.LeftButton, Qt.NoModifier, b)


def test_clicking_the_slider_scrubs_and_play_button_plays_on(qtbot, window):
    from PySide6.QtCore import Qt

    bar = window.timeline_bar
    tl = window.doc.timeline
    pb = window.play_walk(n_steps=2)
    motion = pb.motion
    qtbot.mouseClick(bar.buttons["play"], Qt.LeftButton)  # pause
    assert not tl.playing and window.playback is None and not window.play_timer.isActive()
    _click_slider(qtbot, bar.slider, 60)
    assert abs(tl.frame - 60) <= 1 and bar.slider.value() == tl.frame
    np.testing.assert_array_equal(window.doc.q, np.clip(motion.q[tl.frame], window.doc.skeleton.lower,
                                                        window.doc.skeleton.upper))
    assert window.doc.history.undo_text.startswith("Scrub")
    qtbot.mouseClick(bar.buttons["play"], Qt.LeftButton)  # play on from there
    assert tl.playing and window.play_timer.isActive()
    wait_for(qtbot, lambda: tl.frame > 70)
    qtbot.mouseClick(bar.buttons["loop"], Qt.LeftButton)
    assert tl.loop
    wait_for(qtbot, lambda: tl.frame < 30)  # started over instead of ending
    assert tl.playing
    qtbot.mouseClick(bar.buttons["stop"], Qt.LeftButton)
    assert not tl.playing and tl.frame == 0
    qtbot.mouseClick(bar.buttons["discard"], Qt.LeftButton)
    assert tl.clip is None and bar.slider.maximum() == 0


def test_keys_from_the_bar_play_interpolated_and_move_by_dragging_their_mark(qtbot, window):
    from PySide6.QtCore import Qt

    bar, doc, tl = window.timeline_bar, window.doc, window.doc.timeline
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)  # key 0: standing
    hand = np.array(doc.targets["left_hand"].position)
    tl.frame = 30  # the slider's range ends at the last key: put the next key past it
    doc.move_target("left_hand", hand + [0.0, 0.3, 0.35])
    window.settle()
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)
    assert sorted(tl.keys) == [0, 30] and bar.slider.maximum() == 30 and bar.slider.keys == [0, 30]
    _click_slider(qtbot, bar.slider, 15)
    got = doc.effector_poses()["left_hand"][:3, 3]
    want = hand + [0.0, 0.15, 0.175]  # half way (smoothstep of 0.5 is 0.5)
    assert abs(tl.frame - 15) <= 1
    assert np.linalg.norm(got - want) < 0.03
    # Drag the second key's mark (lower half of the slider) from 30 to 20.
    _drag_slider(qtbot, bar.slider, 30, 20, bar.slider.height() - 7)
    assert sorted(tl.keys) == [0, 20] or sorted(tl.keys) == [0, 21]
    last = max(tl.keys)
    _click_slider(qtbot, bar.slider, last)
    assert tl.frame == last
    qtbot.mouseClick(bar.buttons["delete_key"], Qt.LeftButton)
    assert sorted(tl.keys) == [0]


def test_key_button_refuses_while_a_clip_is_loaded(qtbot, window):
    window.play_walk(n_steps=1)
    window.stop_playback()
    assert not window.timeline_bar.buttons["key"].isEnabled()


def test_timeline_screenshot(qtbot, window, tmp_path):
    window.play_walk(n_steps=2)
    qtbot.wait(700)
    window.stop_playback()
    path = tmp_path / "timeline.png"
    assert window.save_screenshot(str(path))
    from PySide6 import QtGui

    img = QtGui.QImage(str(path))
    bar = window.timeline_bar
    top_left = bar.mapTo(window, bar.rect().topLeft())
    assert img.height() >= top_left.y() + bar.height() > img.height() - 200  # the bar sits at the bottom
