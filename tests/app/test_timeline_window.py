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
    assert tl.clip is None and bar.slider.maximum() == tl.key_length - 1  # the keys' timeline again


def test_keys_from_the_bar_play_interpolated_and_move_by_dragging_their_mark(qtbot, window):
    from PySide6.QtCore import Qt

    bar, doc, tl = window.timeline_bar, window.doc, window.doc.timeline
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)  # key 0: standing
    hand = np.array(doc.targets["left_hand"].position)
    _click_slider(qtbot, bar.slider, 30)
    doc.move_target("left_hand", hand + [0.0, 0.3, 0.35])
    window.settle()
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)
    second = tl.frame
    assert abs(second - 30) <= 1 and sorted(tl.keys) == [0, second] and bar.slider.keys == [0, second]
    _click_slider(qtbot, bar.slider, 15)
    got = doc.effector_poses()["left_hand"][:3, 3]
    want = hand + [0.0, 0.15, 0.175]  # half way (smoothstep of 0.5 is 0.5)
    assert abs(tl.frame - 15) <= 1
    assert np.linalg.norm(got - want) < 0.03
    # Drag the second key's mark (lower half of the slider) to 20.
    _drag_slider(qtbot, bar.slider, second, 20, bar.slider.height() - 7)
    assert len(tl.keys) == 2 and min(tl.keys) == 0 and abs(max(tl.keys) - 20) <= 1
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


def _type_into(qtbot, spin, text):
    """Click into a spin box, replace its text by typing, press Return (real mouse and key events)."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    qtbot.mouseClick(spin.lineEdit(), Qt.LeftButton)
    QTest.keyClick(spin.lineEdit(), Qt.Key_A, Qt.ControlModifier)
    QTest.keyClicks(spin.lineEdit(), text)
    QTest.keyClick(spin.lineEdit(), Qt.Key_Return)


def test_with_no_clip_keys_go_anywhere_on_a_timeline_of_typed_length_stepped_by_keys_and_buttons(
        qtbot, window, tmp_path):
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    bar, doc, tl = window.timeline_bar, window.doc, window.doc.timeline
    assert bar.slider.maximum() == tl.n_frames - 1 > 0 and bar.length.isEnabled()
    _type_into(qtbot, bar.length, "120")
    _type_into(qtbot, bar.fps, "24")
    assert (tl.n_frames, tl.frame_time, bar.slider.maximum()) == (120, 1 / 24, 119)
    _click_slider(qtbot, bar.slider, 10)
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)
    assert sorted(tl.keys) == [tl.frame] and abs(tl.frame - 10) <= 1
    first = tl.frame
    hand = np.array(doc.targets["left_hand"].position)
    _click_slider(qtbot, bar.slider, 60)
    doc.move_target("left_hand", hand + [0.0, 0.3, 0.35])
    window.settle()
    window.plotter.setFocus()  # the pointer over the 3D view gives it the keyboard
    QTest.keyClick(window.plotter, Qt.Key_K)  # key the pose here
    second = tl.frame
    assert sorted(tl.keys) == [first, second] and bar.slider.keys == [first, second]
    for key, modifier, want in ((Qt.Key_Right, Qt.NoModifier, second + 1), (Qt.Key_Left, Qt.NoModifier, second),
                                (Qt.Key_Left, Qt.ShiftModifier, first), (Qt.Key_Right, Qt.ShiftModifier, second)):
        QTest.keyClick(window.plotter, key, modifier)
        assert tl.frame == want and bar.slider.value() == want
    qtbot.mouseClick(bar.buttons["previous_key"], Qt.LeftButton)
    for _ in range(3):
        qtbot.mouseClick(bar.buttons["next_frame"], Qt.LeftButton)
    assert tl.frame == first + 3
    # Scrubbing between the keys shows the solved in-between poses: the hand half way at the middle frame.
    middle = (first + second) // 2
    _click_slider(qtbot, bar.slider, middle)
    assert tl.frame == middle
    s = (middle - first) / (second - first)
    want = hand + (3 - 2 * s) * s * s * np.array([0.0, 0.3, 0.35])  # eased (smoothstep)
    assert np.linalg.norm(doc.effector_poses()["left_hand"][:3, 3] - want) < 0.03
    window.save_screenshot(str(tmp_path / "keys.png"))
    # A clip on the timeline has its own frames; discarding it gives back the keys' timeline.
    window.play_walk(n_steps=1)
    window.stop_playback()
    assert not bar.length.isEnabled() and tl.n_frames != 120
    qtbot.mouseClick(bar.buttons["discard"], Qt.LeftButton)
    assert (tl.n_frames, bar.slider.maximum(), bar.slider.keys, bar.length.value()) == (120, 119, [first, second], 120)
