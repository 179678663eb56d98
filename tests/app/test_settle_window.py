"""Settling that ends (issue 16, item 3), in the real window: a small edit made with the mouse settles in a
bounded number of solver frames under the studio's default pins and natural posture, and the frame clock stops."""

from __future__ import annotations

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui

#: Solver frames a small edit may take to settle (issue 16: within 60 frames).
FRAMES = 60


def _frames_to_settle(qtbot, window, edit) -> int:
    """Solver frames the window runs after ``edit()`` until its frame clock stops."""
    count = [0]
    window.loop.events.frame.connect(lambda: count.__setitem__(0, count[0] + 1))
    edit()
    wait_for(qtbot, lambda: not window.doc.needs_solving and not window.timer.isActive())
    return count[0]


def test_turning_the_head_target_twice_by_its_buttons_settles_and_the_clock_stops(qtbot, window):
    from PySide6 import QtCore

    wait_for(qtbot, lambda: not window.doc.needs_solving and not window.timer.isActive())
    window.viewport.select("head")
    pins = {n: window.doc.effector_poses()[n][:3, 3].copy() for n in ("pelvis", "left_foot")}
    for k in range(2):
        frames = _frames_to_settle(qtbot, window, lambda: qtbot.mouseClick(window.rotate_buttons[("z", 1)],
                                                                           QtCore.Qt.LeftButton))
        assert 0 < frames <= FRAMES, (k, frames)
    head = window.doc.targets["head"].rotation
    got = window.doc.effector_poses()["head"][:3, :3]
    turned = np.degrees(np.arccos(np.clip((np.trace(head.T @ got) - 1) / 2, -1, 1)))
    assert turned < 1.0  # the head follows its target (30 degrees from the start) to within a degree
    for name, p in pins.items():  # the pinned pelvis and foot stay where they were
        assert np.linalg.norm(window.doc.effector_poses()[name][:3, 3] - p) < 1e-3
    assert not window.timer.isActive()  # settled: nothing spins


def test_a_one_centimetre_nudge_of_a_hand_settles_within_the_bound(qtbot, window):
    wait_for(qtbot, lambda: not window.doc.needs_solving and not window.timer.isActive())
    doc = window.doc
    hand = doc.targets["right_hand"].position + (0.0, 0.0, 0.01)
    frames = _frames_to_settle(qtbot, window, lambda: doc.move_target("right_hand", hand))
    assert 0 < frames <= FRAMES
    assert np.linalg.norm(doc.effector_poses()["right_hand"][:3, 3] - hand) < 1e-3
