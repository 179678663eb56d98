"""The artist's tools in the real window under Xvfb: the mannequin, joint rings, pins, balance (real Qt mouse events)."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def on_plane(*args):
    from gsik_studio.joint_rings import on_plane

    return on_plane(*args)


@pytest.fixture()
def window(qtbot, studio_settings):
    from gsik_studio.window import MainWindow

    w = MainWindow(settings=studio_settings)
    w.resize(1280, 860)
    w.show()
    qtbot.waitExposed(w)
    w.activateWindow()
    w.set_view("front")
    qtbot.wait(50)
    yield w
    w.doc.history.set_clean()
    w.close()


def _qpoint(window, xy):
    from PySide6 import QtCore

    plotter = window.plotter
    r = plotter.devicePixelRatioF()
    return QtCore.QPoint(int(round(xy[0] / r)), int(round(plotter.height() - xy[1] / r - 1)))


def _press_drag_release(window, start_xy, end_xy, steps=10):
    """A real left-button drag on the 3D view (Qt mouse events, as a person's)."""
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    plotter = window.plotter
    QTest.mouseMove(plotter, _qpoint(window, start_xy))
    QTest.mousePress(plotter, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, _qpoint(window, start_xy))
    for k in range(1, steps + 1):
        QTest.mouseMove(plotter, _qpoint(window, start_xy + (end_xy - start_xy) * k / steps))
    QTest.mouseRelease(plotter, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, _qpoint(window, end_xy))


def _click(window, xy):
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    QTest.mouseMove(window.plotter, _qpoint(window, xy))
    QTest.mouseClick(window.plotter, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, _qpoint(window, xy))


def _settle(qtbot, window):
    qtbot.waitUntil(lambda: not window.doc.needs_solving, timeout=10000)


def _ring_grip(window, dof):
    """A display point on ``dof``'s ring where the ring runs most across the screen, and its screen tangent (px/rad)."""
    rings = window.rings
    axes, centres, pts = rings.ring_world()
    px = rings.project(pts[dof])
    best = None
    for k in range(len(px)):
        g = pts[dof][k] - centres[dof]
        moved = centres[dof] + np.cos(0.05) * g + np.sin(0.05) * np.cross(axes[dof], g)
        t = (rings.project(moved[None])[0] - px[k]) / 0.05
        if best is None or np.linalg.norm(t) > np.linalg.norm(best[1]):
            best = (px[k], t)
    return best


def test_the_mannequin_is_drawn_and_the_stick_view_is_an_option(window, qtbot):
    body = window.body
    assert body.mode == "mannequin" and body.mannequin.visible
    assert not window.viewport.actors["bones"].GetVisibility()
    # The solids sit on the bones: the mannequin's points surround the skeleton's frames.
    pts = np.vstack([m.polydata.points for m in body.mannequin.meshes])
    P = window.doc.world_positions()
    assert np.all(pts.min(axis=0) < P.min(axis=0)) and np.all(pts.max(axis=0) > P.max(axis=0))
    window.act_sticks.trigger()
    assert body.mode == "sticks" and not body.mannequin.visible
    assert window.viewport.actors["bones"].GetVisibility()
    window.act_sticks.trigger()
    assert body.mode == "mannequin"


def test_the_mannequin_follows_the_pose_in_place(window, qtbot):
    mesh = window.body.mannequin.meshes[0]
    points_before = mesh.polydata.GetPoints()
    xyz = mesh.polydata.points.copy()
    window.doc.random_pose(seed=4)
    _settle(qtbot, window)
    window.viewport.refresh()
    assert mesh.polydata.GetPoints() is points_before  # the same VTK points, overwritten
    assert np.abs(mesh.polydata.points - xyz).max() > 0.05


def test_clicking_a_joint_selects_it_and_the_panel_shows_its_angles(window, qtbot):
    doc = window.doc
    sk = doc.skeleton
    knee = doc.world_positions()[sk.joint_frame[sk.joint_names.index("left_knee")]]
    _click(window, window.rings.project(knee[None])[0])
    assert window.joints.selected == "left_knee"
    panel = window.joint_panel
    assert "left knee" in panel.label.text()
    assert panel.angles[0].isVisible() and not panel.angles[1].isVisible()
    i = sk.dof_index("left_knee.x")
    assert panel.angles[0].value() == pytest.approx(np.degrees(doc.q[i]), abs=0.06)


def test_dragging_a_ring_turns_its_joint_within_limits_as_one_undo_step(window, qtbot):
    doc = window.doc
    sk = doc.skeleton
    _settle(qtbot, window)
    i = sk.dof_index("left_shoulder.y")
    q0 = doc.q.copy()
    n = len(doc.history.commands)
    grip, tangent = _ring_grip(window, i)
    end = grip + 40.0 * tangent / np.linalg.norm(tangent)
    axes, centres, _ = window.rings.ring_world()
    grabbed = on_plane(*window.rings._ray(grip), centres[i], axes[i])
    _press_drag_release(window, grip, end)
    assert window.joints.selected == "left_shoulder"
    turned = doc.q[i] - q0[i]
    assert turned > 0.3
    # The grabbed point of the ring, turned with the joint, lies under the pointer's direction from the centre.
    g = grabbed - centres[i]
    a = axes[i]
    moved = centres[i] + np.cos(turned) * g + np.sin(turned) * np.cross(a, g) + (1 - np.cos(turned)) * (a @ g) * a
    c_px, m_px = window.rings.project(np.array([centres[i], moved]))
    u, v = m_px - c_px, end - c_px
    assert np.degrees(np.arccos(u @ v / np.linalg.norm(u) / np.linalg.norm(v))) < 3.0
    assert sk.lower[i] <= doc.q[i] <= sk.upper[i]
    assert len(doc.history.commands) == n + 1 and doc.history.undo_text == "Turn left_shoulder.y"
    _settle(qtbot, window)
    assert doc.q[i] - q0[i] == pytest.approx(turned, abs=1e-3)  # the targets followed: the turn holds
    doc.undo()
    np.testing.assert_array_equal(doc.q, q0)


def test_typing_an_angle_turns_the_joint_and_stays_within_limits(window, qtbot):
    doc = window.doc
    window.joints.select("right_elbow")
    spin = window.joint_panel.angles[0]
    i = doc.skeleton.dof_index("right_elbow.x")
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    spin.setFocus()
    spin.lineEdit().selectAll()
    QTest.keyClicks(spin.lineEdit(), "45")
    QTest.keyClick(spin.lineEdit(), QtCore.Qt.Key_Return)
    assert np.degrees(doc.q[i]) == pytest.approx(45.0, abs=1e-6)
    assert doc.history.undo_text == "Turn right_elbow.x"
    assert spin.minimum() == pytest.approx(np.degrees(doc.skeleton.lower[i]), abs=0.05)
    assert spin.maximum() == pytest.approx(np.degrees(doc.skeleton.upper[i]), abs=0.05)
    spin.lineEdit().selectAll()
    QTest.keyClicks(spin.lineEdit(), "400")  # past the limit: the editor stops at it
    QTest.keyClick(spin.lineEdit(), QtCore.Qt.Key_Return)
    assert doc.q[i] <= doc.skeleton.upper[i]


def test_a_press_on_a_target_still_moves_the_target_not_a_joint(window, qtbot):
    doc = window.doc
    _settle(qtbot, window)
    start = doc.targets["left_hand"].position.copy()
    xy = window.rings.project(start[None])[0]
    _press_drag_release(window, xy, xy + np.array([30.0, 25.0]))
    assert np.linalg.norm(doc.targets["left_hand"].position - start) > 0.02
    assert window.joints.selected is None
