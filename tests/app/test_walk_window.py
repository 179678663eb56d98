"""The Walk defects of issue 10 item 11, in the real window under Xvfb: real time, pause, stop, no snap back, in view.

Each test failed on the window before the timeline (see the report of branch ``timeline``).
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui



def _pelvis(window):
    return window.doc.world_positions()[window.doc.skeleton.frame_of("pelvis")].copy()


def _camera(window):
    cam = window.plotter.camera
    return np.array([*cam.position, *cam.focal_point])


def test_walk_plays_in_real_time(qtbot, window):
    pb = window.play_walk(n_steps=4)
    assert pb is not None
    duration = pb.n_frames * pb.frame_time  # 3.6 s of motion
    t0 = time.perf_counter()
    wait_for(qtbot, lambda: window.playback is None)
    elapsed = time.perf_counter() - t0
    assert elapsed < 1.3 * duration + 0.5, f"{elapsed:.1f} s for {duration:.1f} s of motion"


def test_pause_stops_the_walk(qtbot, window):
    window.play_walk(n_steps=4)
    qtbot.wait(400)
    window.act_pause.trigger()  # the toolbar's Pause (Space)
    assert "paused" in window.status_labels["status"].text()
    still = _pelvis(window)
    qtbot.wait(500)
    np.testing.assert_array_equal(_pelvis(window), still)


def test_stop_button_stops_the_walk(qtbot, window):
    from PySide6.QtCore import Qt

    start = _pelvis(window)
    window.play_walk(n_steps=4)
    wait_for(qtbot, lambda: np.linalg.norm(_pelvis(window) - start) > 0.05)  # walking
    qtbot.mouseClick(window.timeline_bar.buttons["stop"], Qt.LeftButton)
    assert window.playback is None and not window.play_timer.isActive()
    np.testing.assert_allclose(_pelvis(window), start, atol=0.02)  # back on the first frame
    qtbot.wait(300)
    np.testing.assert_allclose(_pelvis(window), start, atol=0.02)  # and staying there
    assert window.doc.timeline.clip is not None  # the walk stays on the timeline


def test_walk_stays_in_view_and_ends_where_it_stopped(qtbot, window):
    w, h = window.plotter.window_size
    outside = []

    def check():  # every joint of every frame shown lies inside the 3D view
        for p in window.doc.world_positions():
            x, y = window.viewport.world_to_display(p)
            if not (0 <= x <= w and 0 <= y <= h):
                outside.append((round(x), round(y)))

    window.doc.events.pose.connect(check)
    pb = window.play_walk(n_steps=4)
    motion = pb.motion
    camera = _camera(window)
    wait_for(qtbot, lambda: window.playback is None)
    assert not outside, f"the body left the view at {outside[:3]}"
    np.testing.assert_array_equal(_camera(window), camera)  # the camera did not jump at the end
    np.testing.assert_array_equal(window.doc.q, np.clip(motion.q[-1], window.doc.skeleton.lower,
                                                        window.doc.skeleton.upper))  # the last frame stays
    qtbot.wait(300)
    np.testing.assert_array_equal(_camera(window), camera)
