"""The artist's tools in the real window under Xvfb: mannequin, joint rings, pins, balance, poles (real Qt events)."""

from __future__ import annotations

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui


def on_plane(*args):
    from gsik_studio.joint_rings import on_plane

    return on_plane(*args)


@pytest.fixture()
def window(window, qtbot):
    """The studio's window (conftest.py), seen from the front."""
    window.set_view("front")
    qtbot.wait(50)
    return window


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
    wait_for(qtbot, lambda: not window.doc.needs_solving)


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
    # No posture: a posture (natural by default) turns what the targets leave free after the turn.
    doc.controls.set_posture_strength(0.0)
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
    assert len(doc.history.commands) == n + 1 and doc.history.undo_text == "Turn left shoulder (y)"
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
    assert doc.history.undo_text == "Turn right elbow (x)"
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


def _click_widget(widget):
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    QTest.mouseClick(widget, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, widget.rect().center())


def _drag_target_far(window, qtbot, name, delta_px=(320.0, 150.0)):
    """Drag a target's sphere with the real mouse, then let the real frame timer run 1.5 s.

    (Not until settled: out of reach with two unpinned targets on one level the prioritised solver
    can keep reporting a budget exhausted, see the report.)"""
    xy = window.rings.project(window.doc.targets[name].position[None])[0]
    _press_drag_release(window, xy, xy + np.array(delta_px), steps=12)
    qtbot.wait(1500)


def test_pinned_pelvis_stays_when_a_hand_is_dragged_out_of_reach_until_unpinned(window, qtbot):
    doc = window.doc
    row = window.rows["pelvis"]
    assert row.pin.isChecked() and not window.rows["left_hand"].pin.isChecked()
    _settle(qtbot, window)
    pelvis = doc.effector_poses()["pelvis"][:3, 3].copy()
    _drag_target_far(window, qtbot, "left_hand")
    hand_error = np.linalg.norm(doc.effector_poses()["left_hand"][:3, 3] - doc.targets["left_hand"].position)
    assert hand_error > 0.1  # out of reach
    assert np.linalg.norm(doc.effector_poses()["pelvis"][:3, 3] - pelvis) < 1e-4
    _click_widget(row.pin)  # unpin: now the pelvis gives way to the hand
    assert not doc.targets["pelvis"].priority == 0 and not row.pin.isChecked()
    qtbot.wait(1500)
    assert np.linalg.norm(doc.effector_poses()["pelvis"][:3, 3] - pelvis) > 0.01


def test_balance_toggle_and_the_centre_of_mass_drawn_over_its_support(window, qtbot):
    doc = window.doc
    panel = window.balance_panel
    view = window.balance_view
    assert view.visible and view.com_actor.GetVisibility()
    _click_widget(panel.balance)
    assert doc.solver.balance and panel.balance.isChecked()
    qtbot.wait(1000)
    window.viewport.refresh()
    s = doc.controls.support()
    np.testing.assert_allclose(view._com.points[0], s.com, atol=1e-9)
    marks = view._marks.points
    assert marks[1][2] == pytest.approx(s.ground + 0.004) and marks[1][:2] == pytest.approx(s.com[:2])
    np.testing.assert_allclose(view._polygon.points[: len(s.polygon), :2], s.polygon)
    assert view.inside
    _click_widget(panel.show_com)
    assert not view.com_actor.GetVisibility()
    spin = panel.editors["posture_strength"]
    spin.setValue(0.5)
    assert doc.controls.posture_strength == 0.5 and doc.solver.posture is not None


def test_screenshot_shows_mannequin_pins_and_centre_of_mass(window, qtbot, tmp_path):
    """A picture of the window with the body, a pulled hand and the balance drawn (looked at by hand too)."""
    doc = window.doc
    _click_widget(window.balance_panel.balance)
    _drag_target_far(window, qtbot, "left_hand", (140.0, 60.0))
    window.set_view("perspective")
    img = window.grab_window()
    assert img.width() > 600 and img.height() > 400
    # The mannequin's clay colour and the centre of mass's yellow are both on the picture.
    arr = np.frombuffer(img.constBits(), np.uint8).reshape(img.height(), img.bytesPerLine() // 4, 4)[..., :3]
    rgb = arr[..., ::-1].reshape(-1, 3).astype(int)  # the image is BGRA in memory
    assert np.any(np.all(np.abs(rgb - (255, 242, 89)) < 40, axis=1))  # COM_COLOR lit
    assert doc.controls.support().inside
    path = tmp_path / "artist.png"
    assert img.save(str(path))


def _poles_on_crouched(window, qtbot):
    """Crouch 8 cm (the knees bend), then tick "Pole targets" with the mouse and let the pose settle."""
    doc = window.doc
    doc.move_target("pelvis", doc.targets["pelvis"].position + (0.0, 0.0, -0.08))
    _settle(qtbot, window)
    q = doc.q.copy()
    _click_widget(window.balance_panel.poles)
    assert set(doc.controls.poles) == {"left_knee", "right_knee", "left_elbow", "right_elbow"}
    assert all(w.GetEnabled() for w in window.poles.widgets.values())
    _settle(qtbot, window)
    np.testing.assert_allclose(doc.q, q, atol=1e-3)  # placed where the limbs point already: nothing moved


def _violet_share(window, centre, radius):
    """The share of the 3D view's pixels within 0.6 ``radius`` [m] of world point ``centre`` (3,) on screen that
    are the poles' violet, lit or shaded (the mannequin's clay and the left side's blue-grey are not)."""
    img = window.grab_window()
    cam = window.plotter.camera
    right = np.cross(np.array(cam.GetDirectionOfProjection()), np.array(cam.up))
    c, edge = window.rings.project(np.array([centre, centre + radius * right / np.linalg.norm(right)]))
    r_px = 0.6 * np.linalg.norm(edge - c)
    ratio = img.devicePixelRatio()
    violet = []
    for dx, dy in ((x, y) for x in np.linspace(-1, 1, 5) for y in np.linspace(-1, 1, 5) if x * x + y * y <= 1):
        p = window.plotter.mapTo(window, _qpoint(window, c + r_px * np.array([dx, dy])))
        col = img.pixelColor(int(p.x() * ratio), int(p.y() * ratio))
        violet.append(col.blue() - col.green() > 70 and col.red() - col.green() > 30)
    return float(np.mean(violet))


def test_pole_gizmos_rest_out_in_front_of_the_knees_behind_the_elbows_drawn_over_the_body(window, qtbot):
    from gsik_studio.pole_gizmos import POLE_RADIUS

    doc = window.doc
    _poles_on_crouched(window, qtbot)
    for joint, way in (("left_knee", 1.0), ("right_knee", 1.0), ("left_elbow", -1.0), ("right_elbow", -1.0)):
        out = doc.controls.poles[joint].position - doc.controls.joint_position(joint)
        assert np.linalg.norm(out) > 0.25 and way * out[1] > 0.6 * np.linalg.norm(out)  # the body faces +y
    # Seen from behind, the knees' poles lie behind the legs, the elbows' in front of the body: all are drawn.
    window.set_view("back")
    for joint, pole in doc.controls.poles.items():
        assert _violet_share(window, pole.position, POLE_RADIUS) > 0.6, joint
    # The thigh above the knee is the mannequin's, not violet (the check above can fail).
    thigh = (doc.controls.joint_position("left_knee") + doc.controls.joint_position("left_hip")) / 2
    assert _violet_share(window, thigh, POLE_RADIUS) == 0.0


def test_a_pole_gizmo_dragged_with_the_mouse_swings_the_knee(window, qtbot):
    from gsik_studio.model.pole_places import limb_of, swing_angle

    doc = window.doc
    _poles_on_crouched(window, qtbot)
    P0 = doc.world_positions()
    pole = doc.controls.poles["left_knee"].position.copy()
    pelvis = doc.effector_poses()["pelvis"][:3, 3].copy()
    xy = window.rings.project(pole[None])[0]
    _press_drag_release(window, xy, xy + np.array([80.0, 0.0]))  # front view: +x on screen is the body's left
    assert window.joints.selected is None  # the pole widget took the press, not the rings
    assert doc.controls.poles["left_knee"].position[0] < pole[0] - 0.05
    assert [c.text for c in doc.history.commands][-1] == "Move pole left_knee"  # the drag: one undo step
    # The pole is the lowest level: the knee swings (over a few dozen frames) and the pose settles.
    _settle(qtbot, window)
    P = doc.world_positions()
    swing = np.degrees(swing_angle(limb_of(doc.skeleton, "left_knee"), P0, P))
    assert swing < -10.0  # outwards, about the hip-ankle line (seen from above the hip: clockwise)
    assert np.linalg.norm(doc.effector_poses()["pelvis"][:3, 3] - pelvis) < 1e-3
    for other in ("right_knee", "left_elbow", "right_elbow"):
        assert abs(swing_angle(limb_of(doc.skeleton, other), P0, P)) < np.radians(1.0)


def test_reset_puts_the_poles_back_in_front_of_the_knees_and_the_pose_settles(window, qtbot):
    from gsik_studio.model import Document

    doc = window.doc
    standing = Document()  # the standing pose settled without poles: where Reset must come back to
    while standing.needs_solving:
        standing.step()
    _poles_on_crouched(window, qtbot)
    doc.controls.move_pole("left_knee", doc.controls.poles["left_knee"].position + (-0.3, 0.0, 0.0))
    doc.controls.move_pole("right_elbow", doc.controls.poles["right_elbow"].position + (0.0, 0.3, 0.0))
    _settle(qtbot, window)
    n = len(doc.history.commands)
    _click_widget(window.toolbar.widgetForAction(window.act_reset))
    assert len(doc.history.commands) == n + 1 and doc.history.undo_text == "Reset to standing pose"
    assert window.balance_panel.poles.isChecked()  # still on, back at their rest places
    _settle(qtbot, window)
    sk = doc.skeleton
    for joint in doc.controls.poles:
        out = doc.controls.poles[joint].position - doc.controls.joint_position(joint)
        way = 1.0 if "knee" in joint else -1.0
        assert way * out[1] > 0.9 * np.linalg.norm(out), joint  # straight in front of the knee, behind the elbow
        hinge = sk.joint_dofs[sk.joint_names.index(joint)][0]
        assert abs(doc.q[hinge] - standing.q[hinge]) < np.radians(3.0), joint  # bent as standing: no bent knee
    # The poles hold the knees and elbows straight ahead; the natural posture alone turns them a few degrees.
    np.testing.assert_allclose(doc.world_positions(), standing.world_positions(), atol=0.02)
