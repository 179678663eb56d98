"""The studio window in a real X server (Xvfb, started by conftest.py), driven with pytest-qt."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import gsik
from waiting import wait_for

pytestmark = pytest.mark.gui

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _ticks(qtbot, window, until):
    """Let the real frame timer run until ``until()`` holds."""
    wait_for(qtbot, until)


def _drag(window, start_world, delta_px, steps=8):
    """Press on a world point, move by delta_px (display pixels), release: real Qt mouse events."""
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    plotter = window.plotter
    x, y = window.viewport.world_to_display(start_world)
    ratio = plotter.devicePixelRatioF()
    h = plotter.height()

    def qpoint(px, py):
        return QtCore.QPoint(int(round(px / ratio)), int(round(h - py / ratio - 1)))

    QTest.mouseMove(plotter, qpoint(x, y))
    QTest.mousePress(plotter, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, qpoint(x, y))
    for k in range(1, steps + 1):
        QTest.mouseMove(plotter, qpoint(x + delta_px[0] * k / steps, y + delta_px[1] * k / steps))
    QTest.mouseRelease(plotter, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier,
                       qpoint(x + delta_px[0], y + delta_px[1]))


def _effector(window, name):
    return window.doc.effector_poses()[name][:3, 3].copy()


def test_window_opens_with_the_biped_standing(window):
    doc = window.doc
    assert doc.skeleton.name == "biped" and doc.root == "right_foot"
    assert window.windowTitle().startswith("Untitled")
    assert window.act_root_right.isChecked() and not window.act_root_left.isChecked()
    assert not window.act_undo.isEnabled()
    # One sphere widget per effector site; the root's is hidden.
    on = {n: bool(w.GetEnabled()) for n, w in zip(doc.skeleton.effector_sites, window.viewport.target_widgets)}
    assert on == {"head": True, "pelvis": True, "left_hand": True, "right_hand": True, "left_foot": True,
                  "right_foot": False}
    # Standing pose: the solver has converged, so the frame timer idles.
    assert doc.last_result.status is gsik.Status.CONVERGED
    assert not window.timer.isActive()
    assert "converged" in window.status_labels["status"].text()


def test_dragging_a_target_gizmo_moves_it_and_the_effector_follows(qtbot, window):
    name = "left_hand"
    doc = window.doc
    start_target = np.array(doc.targets[name].position)
    start_hand = _effector(window, name)
    _drag(window, start_target, (60, 70))
    moved = np.array(doc.targets[name].position)
    assert np.linalg.norm(moved - start_target) > 0.05, "the drag did not move the target"
    assert doc.history.undo_text == f"Move {name.replace('_', ' ')}" and len(doc.history.commands) == 1
    assert window.viewport.selected == name
    # The frame timer runs the solver: after a few ticks the hand has moved toward the target.
    _ticks(qtbot, window, lambda: np.linalg.norm(_effector(window, name) - moved)
           < 0.5 * np.linalg.norm(start_hand - moved))
    assert window.act_undo.isEnabled() and window.isWindowModified()
    # The widget followed the document: its centre is the target.
    w = window.viewport.target_widgets[doc.skeleton.effector_sites.index(name)]
    np.testing.assert_allclose(w.GetCenter(), moved, atol=1e-9)


def test_undo_shortcut_puts_a_dragged_target_back_exactly(qtbot, window):
    from PySide6 import QtCore

    before = window.doc.pose()
    _drag(window, window.doc.targets["head"].position, (-50, 30))
    assert window.doc.pose() != before
    qtbot.wait(100)
    qtbot.keyClick(window, QtCore.Qt.Key_Z, QtCore.Qt.ControlModifier)
    assert window.doc.pose() == before
    head = window.viewport.target_widgets[window.doc.skeleton.effector_sites.index("head")]
    np.testing.assert_allclose(head.GetCenter(), before.targets["head"].position, atol=1e-12)
    qtbot.keyClick(window, QtCore.Qt.Key_Y, QtCore.Qt.ControlModifier)
    assert window.doc.pose() != before and window.doc.history.undo_text == "Move head"


def test_toolbar_root_switch_keeps_the_pose_still(qtbot, window):
    from PySide6 import QtCore

    # No posture: a posture (natural by default) goes on turning what the targets leave free whenever the
    # solver wakes, a root switch included (about 1.6 mm here).
    window.doc.controls.set_posture_strength(0.0)
    window.doc.random_pose(seed=4)
    _ticks(qtbot, window, lambda: not window.timer.isActive())
    P = window.doc.solver.world_positions()
    button = window.toolbar.widgetForAction(window.act_root_left)
    qtbot.mouseClick(button, QtCore.Qt.LeftButton)
    assert window.doc.root == "left_foot"
    assert window.act_root_left.isChecked() and not window.act_root_right.isChecked()
    np.testing.assert_allclose(window.doc.solver.world_positions(), P, atol=1e-12)
    qtbot.wait(300)  # let the timer run: nothing may drift
    np.testing.assert_allclose(window.doc.solver.world_positions(), P, atol=1e-6)
    assert "left foot" in window.status_labels["root"].text()


def test_save_then_open_through_the_ui(qtbot, window, boxes, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QFileDialog

    path = str(tmp_path / "my pose.yaml")
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: (path, "")))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", staticmethod(lambda *a, **k: (path, "")))
    window.doc.random_pose(seed=8)
    window.act_root_left.trigger()
    _ticks(qtbot, window, lambda: not window.timer.isActive())
    saved = window.doc.pose()
    window.act_save.trigger()  # no file yet: Save goes through Save As
    assert os.path.exists(path) and boxes["critical"] == []
    assert window.doc.path == path and not window.isWindowModified()
    assert window.windowTitle().startswith("my pose.yaml")
    assert window.recent_files()[0] == os.path.abspath(path)

    window.act_reset.trigger()
    assert window.doc.dirty
    window.act_open.trigger()
    assert len(boxes["question"]) == 1  # unsaved changes: asked first (answered Discard)
    assert window.doc.pose() == saved
    assert window.doc.root == "left_foot" and window.act_root_left.isChecked()
    assert not window.doc.dirty and not window.doc.history.can_undo


def test_corrupt_pose_file_shows_an_error_and_changes_nothing(qtbot, window, boxes, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QFileDialog

    window.doc.random_pose(seed=12)
    window.doc.history.set_clean()
    bad = tmp_path / "corrupt.yaml"
    bad.write_text("format: 1\nskeleton: biped\nroot: right_foot\njoints:\n  waist.x: 0.1\n   waist.y: [\n")
    monkeypatch.setattr(QFileDialog, "getOpenFileName", staticmethod(lambda *a, **k: (str(bad), "")))
    before, title = window.doc.pose(), window.windowTitle()
    window.act_open.trigger()
    assert len(boxes["critical"]) == 1
    _title, text = boxes["critical"][0]
    assert "corrupt.yaml:6" in text and "nothing was changed" in text
    assert "corrupt.yaml" in window.statusBar().currentMessage()
    assert window.doc.pose() == before and window.windowTitle() == title and window.doc.path is None


def test_failed_save_reports_and_keeps_the_old_file(qtbot, window, boxes, tmp_path, monkeypatch):
    path = tmp_path / "pose.yaml"
    assert window.save_to(str(path))
    old = path.read_bytes()
    window.doc.random_pose(seed=1)

    def full_disk(*_a, **_k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", full_disk)
    assert not window.act_save.trigger() and boxes["critical"]
    assert "No space left" in boxes["critical"][0][1]
    assert path.read_bytes() == old and window.isWindowModified()


def test_close_with_unsaved_changes_asks_first(qtbot, window, boxes):
    from PySide6.QtWidgets import QMessageBox

    window.doc.random_pose(seed=2)
    boxes["answer"] = QMessageBox.Cancel
    window.close()
    assert window.isVisible() and len(boxes["question"]) == 1
    boxes["answer"] = QMessageBox.Discard
    window.close()
    assert not window.isVisible()


def test_pause_stops_solving_and_resume_continues(qtbot, window):
    window.act_pause.trigger()
    assert window.paused and window.act_pause.text() == "Resume"
    q = window.doc.q
    window.doc.move_target("right_hand", np.array(window.doc.targets["right_hand"].position) + [0.2, 0.2, 0.2])
    qtbot.wait(200)
    np.testing.assert_array_equal(window.doc.q, q)
    assert not window.timer.isActive() and "paused" in window.status_labels["status"].text()
    window.act_pause.trigger()
    _ticks(qtbot, window, lambda: not np.array_equal(window.doc.q, q))


def test_panel_weight_and_enable_go_through_undoable_commands(qtbot, window):
    row = window.rows["pelvis"]
    row.weight.setValue(3.0)
    assert window.doc.targets["pelvis"].weight == 3.0
    row.enabled.setChecked(False)
    assert not window.doc.targets["pelvis"].enabled
    assert not window.viewport.target_widgets[window.doc.skeleton.effector_sites.index("pelvis")].GetEnabled()
    window.act_undo.trigger()
    assert window.doc.targets["pelvis"].enabled and row.enabled.isChecked()
    window.act_undo.trigger()
    assert window.doc.targets["pelvis"].weight == 1.0 and row.weight.value() == 1.0


def test_rotate_buttons_turn_the_selected_target(qtbot, window):
    from PySide6 import QtCore

    window.viewport.select("head")
    R0 = window.doc.targets["head"].rotation
    qtbot.mouseClick(window.rotate_buttons[("z", 1)], QtCore.Qt.LeftButton)
    R1 = window.doc.targets["head"].rotation
    angle = np.degrees(np.arccos(np.clip((np.trace(R0.T @ R1) - 1) / 2, -1, 1)))
    assert abs(angle - 15.0) < 1e-6
    assert window.doc.history.undo_text == "Rotate head about z"


def _colour_counts(image) -> dict[str, int]:
    from PySide6 import QtGui

    img = image.convertToFormat(QtGui.QImage.Format_RGB888)
    a = np.frombuffer(img.constBits(), np.uint8).reshape(img.height(), img.bytesPerLine())[:, :img.width() * 3]
    a = a.reshape(img.height(), img.width(), 3).astype(int)
    r, g, b = a[..., 0], a[..., 1], a[..., 2]
    return {
        "red": int(np.sum((r > 150) & (g < 90) & (b < 90))),
        "green": int(np.sum((g > 140) & (r < 120) & (b < 120))),
        "blue": int(np.sum((b > 170) & (r < 120) & (g < 170))),
    }


def test_screenshot_shows_red_targets_green_effectors_and_axis_colours(qtbot, window):
    doc = window.doc
    # Pull the hands' targets away so targets and effectors stand apart.
    doc.move_target("left_hand", np.array(doc.targets["left_hand"].position) + [-0.3, 0.3, 0.5])
    doc.move_target("right_hand", np.array(doc.targets["right_hand"].position) + [0.3, 0.3, 0.5])
    window.settle()
    full = _colour_counts(window.grab_window())
    assert full["red"] > 400 and full["green"] > 200 and full["blue"] > 100, full

    vp = window.viewport
    vp.set_targets_visible(False)
    no_targets = _colour_counts(window.grab_window())
    vp.set_targets_visible(True)
    vp.actors["effectors"].SetVisibility(False)
    no_effectors = _colour_counts(window.grab_window())
    vp.actors["effectors"].SetVisibility(True)
    vp.actors["gizmos"].SetVisibility(False)
    vp.actors["triads"].SetVisibility(False)
    no_axes = _colour_counts(window.grab_window())
    vp.actors["gizmos"].SetVisibility(True)
    vp.actors["triads"].SetVisibility(True)

    assert full["red"] - no_targets["red"] > 300, (full, no_targets)  # the targets are red
    assert full["green"] - no_effectors["green"] > 80, (full, no_effectors)  # the effectors are green
    for colour in ("red", "green", "blue"):  # the axis rings and triads are red, green and blue
        assert full[colour] - no_axes[colour] > 50, (colour, full, no_axes)


def test_joints_on_a_limit_are_highlighted(qtbot, window):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    from gsik_studio.scene import rgb8 as _rgb8
    from gsik_studio.viewport import LIMIT_COLOR

    sk = window.doc.skeleton
    q = sk.rest.copy()
    q[sk.dof_index("left_elbow.x")] = sk.upper[sk.dof_index("left_elbow.x")]
    window.doc.set_angles(q)
    window.viewport.refresh()
    colors = vtk_to_numpy(window.viewport._joints.GetPointData().GetArray("colors"))
    elbow = sk.joint_names.index("left_elbow")
    np.testing.assert_array_equal(colors[elbow], _rgb8(LIMIT_COLOR))
    assert not np.array_equal(colors[sk.joint_names.index("right_elbow")], _rgb8(LIMIT_COLOR))


def test_screenshot_command_line_renders_a_png_and_exits(qapp, x_display, tmp_path):
    out = tmp_path / "shot.png"
    env = dict(os.environ, DISPLAY=x_display, QT_QPA_PLATFORM="xcb")
    r = subprocess.run([sys.executable, "-m", "app", "--screenshot", str(out), "--size", "960x640"],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=180)
    assert r.returncode == 0, r.stderr[-2000:]
    from PySide6 import QtGui

    img = QtGui.QImage(str(out))
    assert (img.width(), img.height()) == (960, 640)


def test_screenshot_command_line_reports_a_bad_pose(qapp, x_display, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("format: 1\nskeleton: robot\n")
    out = tmp_path / "shot.png"
    env = dict(os.environ, DISPLAY=x_display, QT_QPA_PLATFORM="xcb")
    r = subprocess.run([sys.executable, "-m", "app", "--screenshot", str(out), str(bad)],
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=180)
    assert r.returncode == 1 and "bad.yaml" in r.stderr and not out.exists()


def test_many_qt_calls_do_not_exhaust_none(qapp, x_display):
    """PySide6 6.12 on Python 3.11 drops a reference to None per void call; the app guards against it."""
    code = ("import sys; from gsik_studio.qt_compat import protect_none; assert protect_none(); "
            "from PySide6 import QtWidgets; app = QtWidgets.QApplication([]); w = QtWidgets.QLabel(); "
            "[w.setText('x') or app.processEvents() for _ in range(30000)]; print('alive')")
    env = dict(os.environ, DISPLAY=x_display, QT_QPA_PLATFORM="xcb")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "alive" in r.stdout, r.stderr[-1000:]


def test_walk_button_plays_a_walk_as_one_undo_step(qtbot, window):
    pytest.importorskip("gsik.anim.gait")
    if window.act_walk is None:
        pytest.skip("gsik.anim.gait has no walk()")
    before = window.doc.pose()
    pelvis = window.doc.solver.world_positions()[window.doc.skeleton.frame_of("pelvis")]
    roots = set()
    window.doc.events.pose.connect(lambda: roots.add(window.doc.root))
    pb = window.play_walk(n_steps=1)
    assert pb is not None and window.play_timer.isActive()
    window.play_timer.setInterval(1)  # play as fast as it draws
    wait_for(qtbot, lambda: window.playback is None)  # render-bound: 0.3 s a frame at load 13
    assert roots >= {"left_foot", "right_foot"}  # the root swapped between the feet
    moved = window.doc.solver.world_positions()[window.doc.skeleton.frame_of("pelvis")] - pelvis
    assert moved[1] > 0.15  # walked forward (+y)
    assert window.doc.history.undo_text == "Walk"
    window.act_undo.trigger()
    assert window.doc.pose() == before


def test_scenario_menu_loads_targets_and_the_solver_settles_them(qtbot, window):
    scenarios = pytest.importorskip("gsik.anim.scenarios")
    if window.act_scenarios is None:
        pytest.skip("gsik.anim.scenarios lacks the functions the app uses")
    names = [a.text() for a in window.scenario_menu.actions()]
    assert "kneel" in names and "wave" in names
    sc = scenarios.builtin_scenario(window.doc.skeleton, "kneel")
    pelvis_before = window.doc.solver.world_positions()[window.doc.skeleton.frame_of("pelvis")][2]
    window.scenario_menu.actions()[names.index("kneel")].trigger()
    assert window.doc.history.undo_text == "Scenario kneel"
    j = sc.effectors.index("pelvis")
    np.testing.assert_allclose(window.doc.targets["pelvis"].position, sc.positions[-1, j], atol=1e-12)
    wait_for(qtbot, lambda: not window.timer.isActive())
    pelvis = window.doc.solver.world_positions()[window.doc.skeleton.frame_of("pelvis")]
    assert pelvis[2] < pelvis_before - 0.1  # kneeling: the pelvis went down
    assert np.linalg.norm(pelvis - sc.positions[-1, j]) < 0.02


def test_animated_scenario_plays_its_frames(qtbot, window):
    pytest.importorskip("gsik.anim.scenarios")
    if window.act_scenarios is None:
        pytest.skip("gsik.anim.scenarios lacks the functions the app uses")
    names = [a.text() for a in window.scenario_menu.actions()]
    window.scenario_menu.actions()[names.index("wave")].trigger()
    assert window.playback is not None and window.playback.n_frames > 1
    window.play_timer.setInterval(1)  # play as fast as it draws
    wait_for(qtbot, lambda: window.playback is None)  # render-bound: 0.3 s a frame at load 13
    assert window.doc.history.undo_text == "Scenario wave (animated)"
    hand = window.doc.solver.world_positions()[window.doc.skeleton.frame_of("right_hand")]
    head = window.doc.solver.world_positions()[window.doc.skeleton.frame_of("head")]
    assert hand[2] > head[2] - 0.2  # the waving hand is up near the head or above it


def test_dragging_a_face_of_the_rotate_box_turns_the_selected_target(qtbot, window):
    doc = window.doc
    window.viewport.select("pelvis")
    t0 = doc.targets["pelvis"]
    from gsik_studio.viewport import BOX_SIZE

    # A point on the box's front face (+y, towards the camera), off the sphere in the middle.
    corner = np.array(t0.position) + t0.rotation @ [0.3 * BOX_SIZE, 0.5 * BOX_SIZE, -0.3 * BOX_SIZE]
    _drag(window, corner, (60, 25))
    t1 = doc.targets["pelvis"]
    np.testing.assert_allclose(t1.position, t0.position, atol=1e-12)  # turned, not moved
    angle = np.degrees(np.arccos(np.clip((np.trace(t0.rotation.T @ t1.rotation) - 1) / 2, -1, 1)))
    assert angle > 5.0
    assert doc.history.undo_text == "Rotate pelvis" and len(doc.history.commands) == 1


def test_view_presets_and_frame_all(qtbot, window):
    from PySide6 import QtCore

    window.act_views["front"].trigger()
    cam = window.plotter.camera
    d = np.array(cam.position) - np.array(cam.focal_point)
    assert d[1] > 0 and abs(d[0]) < 1e-9  # in front of the character (it faces +y)
    window.act_views["top"].trigger()
    d = np.array(cam.position) - np.array(cam.focal_point)
    assert d[2] > 0 and np.hypot(d[0], d[1]) < 1e-9
    cam.position = np.array(cam.focal_point) + 50 * d / np.linalg.norm(d)  # zoomed far out
    qtbot.keyClick(window, QtCore.Qt.Key_F)
    assert np.linalg.norm(np.array(cam.position) - np.array(cam.focal_point)) < 10


def test_window_geometry_and_solver_settings_are_remembered(qtbot, studio_settings):
    from gsik_studio.window import MainWindow

    w = MainWindow(settings=studio_settings)
    w.resize(1111, 777)
    w.show()
    qtbot.waitExposed(w)
    w.sweeps.setValue(17)
    assert w.doc.settings.sweeps == 17
    w.close()
    w2 = MainWindow(settings=studio_settings)
    try:
        assert (w2.width(), w2.height()) == (1111, 777)
        assert w2.doc.settings.sweeps == 17 and w2.sweeps.value() == 17
    finally:
        w2.close()


def test_rotate_box_follows_the_selected_target_after_a_drag(qtbot, window):
    import vtk

    name = "left_hand"
    window.viewport.select(name)
    _drag(window, window.doc.targets[name].position, (40, 40))
    t = vtk.vtkTransform()
    window.viewport.box_widget.GetTransform(t)
    centre = [t.GetMatrix().GetElement(i, 3) for i in range(3)]
    np.testing.assert_allclose(centre, window.doc.targets[name].position, atol=1e-9)
