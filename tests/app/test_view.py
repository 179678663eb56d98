"""The 3D view under real Qt mouse and key events: repaint on framing, turntable orbit, keys, pick tolerance,
start-up options, and the scenario status agreeing with ``gsik scenarios``."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui


def _qpoint(window, x, y):
    """Qt widget coordinates of display pixel (x, y) (origin bottom-left) in the 3D view."""
    from PySide6 import QtCore

    ratio = window.plotter.devicePixelRatioF()
    return QtCore.QPoint(int(round(x / ratio)), int(round(window.plotter.height() - y / ratio - 1)))


def _drag_px(window, start, delta, steps=10):
    """Press at display pixel ``start``, move by ``delta`` in ``steps`` real Qt mouse moves, release."""
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    pl = window.plotter
    QTest.mouseMove(pl, _qpoint(window, *start))
    QTest.mousePress(pl, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, _qpoint(window, *start))
    for k in range(1, steps + 1):
        QTest.mouseMove(pl, _qpoint(window, start[0] + delta[0] * k / steps, start[1] + delta[1] * k / steps))
    QTest.mouseRelease(pl, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier,
                       _qpoint(window, start[0] + delta[0], start[1] + delta[1]))


def _render_count(window):
    """A list that grows by one at every VTK render of the window."""
    renders = []
    window.plotter.render_window.AddObserver("EndEvent", lambda *_: renders.append(1))
    return renders


def _camera(window):
    cam = window.plotter.camera
    return np.array(cam.position), np.array(cam.focal_point), np.array(cam.up)


@pytest.mark.parametrize("how", ["toolbar", "key"])
def test_frame_all_repaints_at_once(qtbot, window, how):
    from PySide6 import QtCore

    cam = window.plotter.camera
    d = np.array(cam.position) - np.array(cam.focal_point)
    cam.position = np.array(cam.focal_point) + 30 * d  # zoomed far out
    qtbot.wait(100)
    renders = _render_count(window)
    if how == "toolbar":
        window.toolbar.widgetForAction(window.act_frame).click()
    else:
        qtbot.mouseMove(window.plotter)
        qtbot.keyClick(window.plotter, QtCore.Qt.Key_F)
    assert np.linalg.norm(np.array(cam.position) - np.array(cam.focal_point)) < 10
    wait_for(qtbot, lambda: len(renders) > 0)  # the new camera is on screen without another event


def test_orbit_keeps_the_horizon_level(qtbot, window):
    """A diagonal drag on empty space orbits as a turntable: the camera's right vector stays horizontal."""
    w, h = window.plotter.width(), window.plotter.height()
    pos0, _, _ = _camera(window)
    _drag_px(window, (0.15 * w, 0.8 * h), (0.25 * w, -0.3 * h), steps=20)
    pos, focal, up = _camera(window)
    assert np.linalg.norm(pos - pos0) > 0.1  # it did orbit
    forward = focal - pos
    right = np.cross(forward, up)
    assert abs(right[2]) / np.linalg.norm(right) < 1e-6
    assert window.doc.history.commands == []  # and moved no target


def test_trackball_is_an_option(qtbot, window):
    window.act_trackball.trigger()
    assert window.settings.value("view/orbit") == "trackball"
    w, h = window.plotter.width(), window.plotter.height()
    _drag_px(window, (0.15 * w, 0.8 * h), (0.25 * w, -0.3 * h), steps=20)
    pos, focal, up = _camera(window)
    right = np.cross(focal - pos, up)
    assert abs(right[2]) / np.linalg.norm(right) > 1e-3  # a trackball rolls
    window.act_trackball.trigger()
    assert window.settings.value("view/orbit") == "turntable"


def test_view_keys_over_the_view_never_type_into_a_focused_spin_box(qtbot, window):
    """A weight spin box has the focus; the pointer moves over the view; 1, 5, 7, Space act on the view."""
    from PySide6 import QtCore, QtWidgets
    from PySide6.QtTest import QTest

    spin = window.rows["left_hand"].weight
    spin.setFocus()
    wait_for(qtbot, spin.hasFocus)
    weight = window.doc.targets["left_hand"].weight
    QTest.mouseMove(window.plotter, QtCore.QPoint(300, 300))
    for key in (QtCore.Qt.Key_1, QtCore.Qt.Key_5, QtCore.Qt.Key_7):
        QTest.keyClick(QtWidgets.QApplication.focusWidget(), key)
    assert window.doc.targets["left_hand"].weight == weight and spin.value() == weight
    assert window.plotter.camera.parallel_projection  # 7: the orthographic top view
    QTest.keyClick(QtWidgets.QApplication.focusWidget(), QtCore.Qt.Key_Space)
    assert window.paused
    assert window.doc.targets["left_hand"].weight == weight


def test_front_side_top_are_orthographic_and_perspective_is_not(qtbot, window):
    for name, ortho in (("front", True), ("side", True), ("top", True), ("perspective", False)):
        window.act_views[name].trigger()
        assert bool(window.plotter.camera.parallel_projection) is ortho, name
    window.act_views["front"].trigger()
    # Every frame of the character is inside the orthographic view.
    for p in window.doc.world_positions():
        x, y = window.viewport.world_to_display(p)
        assert 0 <= x <= window.plotter.width() and 0 <= y <= window.plotter.height()


def test_frame_selected_zooms_on_the_selected_target(qtbot, window):
    window.viewport.select("left_hand")
    renders = _render_count(window)
    before = np.linalg.norm(np.subtract(window.plotter.camera.position, window.plotter.camera.focal_point))
    window.act_frame_selected.trigger()
    cam = window.plotter.camera
    assert np.linalg.norm(np.subtract(cam.position, cam.focal_point)) < 0.6 * before
    np.testing.assert_allclose(cam.focal_point, window.doc.targets["left_hand"].position, atol=0.05)
    wait_for(qtbot, lambda: len(renders) > 0)


def test_help_lists_the_shortcuts(qtbot, window):
    window.act_shortcuts.trigger()
    rows = dict((text, keys) for keys, text in window.shortcuts_dialog.texts())
    assert rows["Frame all"].startswith("F") and rows["Front"] == "1" and rows["Pause"] == "Space"
    assert "Frame selected" in rows and "Left-drag elsewhere" in dict(window.shortcuts_dialog.texts())
    window.shortcuts_dialog.close()


def test_a_click_a_few_pixels_off_a_target_grabs_it_instead_of_orbiting(qtbot, window):
    from gsik_studio.viewport import PICK_TOLERANCE_PX, TARGET_RADIUS

    doc, name = window.doc, "right_hand"
    window.viewport.select("head")
    t0 = np.array(doc.targets[name].position)
    cam0 = _camera(window)
    x, y = window.viewport.world_to_display(t0)
    rx, _ = window.viewport.world_to_display(t0 + TARGET_RADIUS * np.array([1.0, 0.0, 0.0]))
    miss = abs(rx - x) + PICK_TOLERANCE_PX / 2  # outside the sphere, inside the tolerance
    _drag_px(window, (x + miss, y), (0, -40))
    assert all(np.allclose(a, b) for a, b in zip(cam0, _camera(window)))  # no orbit
    assert doc.targets[name].position[2] < t0[2] - 0.02  # the target moved down with the mouse
    assert len(doc.history.commands) == 1


def test_each_drag_event_renders_at_most_once(qtbot, window):
    """VTK's widget renders on its own events and the app on its frames: coalesced into one paint per turn."""
    from PySide6 import QtCore, QtWidgets
    from PySide6.QtTest import QTest

    t = window.doc.targets["left_hand"].position
    x, y = window.viewport.world_to_display(t)
    pl = window.plotter
    QTest.mouseMove(pl, _qpoint(window, x, y))
    QTest.mousePress(pl, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, _qpoint(window, x, y))
    renders = _render_count(window)
    n = 20
    for k in range(1, n + 1):
        QTest.mouseMove(pl, _qpoint(window, x + 3 * k, y + 2 * k))
        QtWidgets.QApplication.processEvents()
    QTest.mouseRelease(pl, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, _qpoint(window, x + 3 * n, y + 2 * n))
    assert window.doc.history.commands  # the drag moved the target
    assert len(renders) <= n + 1


def test_crouch_ends_as_gsik_scenarios_says(qtbot, window):
    from gsik.anim.scenario_run import run_scenario
    from gsik.anim.scenarios import builtin_scenario

    names = [a.text() for a in window.scenario_menu.actions()]
    window.scenario_menu.actions()[names.index("crouch")].trigger()
    wait_for(qtbot, lambda: not window.timer.isActive())
    report = run_scenario(builtin_scenario(window.doc.skeleton, "crouch"))
    assert report.status.label == "converged"
    assert window.doc.last_result.status is report.status
    assert "converged" in window.status_labels["status"].text()


def test_size_and_view_options_apply_to_the_window(qapp, x_display, tmp_path, monkeypatch):
    """gsik-studio --size 900x700 --view top: both win over the remembered geometry and the default view."""
    from PySide6 import QtCore, QtWidgets

    from gsik_studio import main as studio_main
    from gsik_studio.window import MainWindow

    QtCore.QSettings.setPath(QtCore.QSettings.NativeFormat, QtCore.QSettings.UserScope, str(tmp_path))
    QtCore.QSettings.setPath(QtCore.QSettings.IniFormat, QtCore.QSettings.UserScope, str(tmp_path))
    old = MainWindow(settings=QtCore.QSettings("gsik", "gsik-studio"))  # remembers a 1300x950 window
    old.resize(1300, 950)
    old.show()
    old.close()
    shown = {}

    def fake_exec():
        w = next(w for w in QtWidgets.QApplication.topLevelWidgets() if isinstance(w, MainWindow) and w.isVisible())
        cam = w.plotter.camera
        shown.update(size=(w.width(), w.height()), back=np.subtract(cam.position, cam.focal_point))
        w.doc.history.set_clean()
        w.close()
        return 0

    monkeypatch.setattr(QtWidgets.QApplication, "exec", staticmethod(fake_exec))
    assert studio_main.main(["--size", "900x700", "--view", "top"]) == 0
    assert shown["size"] == (900, 700)
    back = shown["back"] / np.linalg.norm(shown["back"])
    assert back[2] > 0.999  # looking down


def test_no_display_gives_one_line_and_an_exit_code(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM")}
    done = subprocess.run([sys.executable, "-m", "gsik_studio"], env=env, capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert done.returncode == 3, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "no display" in lines[0] and "xvfb-run" in lines[0]


def test_the_floor_shows_one_colour_from_every_view(window, qtbot):
    """The floor is drawn unlit in the colour it had lit (a quarter of a software render saved, same picture)."""
    from gsik_studio.scene import rgb8
    from gsik_studio.viewport import FLOOR_COLOR

    window.set_body("sticks")  # nothing in front of the floor but thin sticks
    window.set_view("perspective")
    seen = []
    for azimuth, elevation in ((0, 0), (70, 25), (150, -10)):  # turned about the body, higher, lower
        cam = window.plotter.camera
        cam.Azimuth(azimuth)
        cam.Elevation(elevation)
        cam.OrthogonalizeViewUp()
        image = window.plotter.screenshot(None)
        h, w = image.shape[:2]
        for corner in ((-0.62, -0.62), (0.62, -0.62), (-0.62, 0.62), (0.62, 0.62)):  # inside grid cells
            x, y = (int(round(c)) for c in window.viewport.world_to_display((*corner, 0.0)))
            if 0 <= x < w and 0 <= y < h:
                seen.append(image[h - 1 - y, x, :3].astype(int))
                break
    assert len(seen) == 3  # a floor point in every picture
    np.testing.assert_allclose(np.array(seen), np.tile(rgb8(FLOOR_COLOR), (3, 1)), atol=2)
