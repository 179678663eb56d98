"""The selected joint's highlight, the natural posture toggle, the effector panel's fit and importing a skeleton
into the current window, in the real window under Xvfb (real Qt events)."""

from __future__ import annotations

import numpy as np
import pytest
from test_artist_gui import _click, _click_widget

pytestmark = pytest.mark.gui


def _joint_position(doc, joint):
    sk = doc.skeleton
    return doc.world_positions()[sk.joint_frame[sk.joint_names.index(joint)]]


def _window_pixel_colors(window, xy, radius=3):
    """RGB (k, 3) of a grabbed picture of the window around the 3D view's display point ``xy``."""
    from PySide6 import QtCore

    img = window.grab_window()
    pl = window.plotter
    p = pl.mapTo(window, QtCore.QPoint(int(round(xy[0])), int(round(pl.height() - xy[1] - 1))))
    return np.array([img.pixelColor(p.x() + dx, p.y() + dy).getRgb()[:3]
                     for dx in range(-radius, radius + 1) for dy in range(-radius, radius + 1)])


def test_the_joint_selected_for_rotation_is_highlighted_and_the_highlight_follows(window, qtbot):
    from gsik_studio.joint_highlight import HIGHLIGHT_COLOR

    window.set_view("front")
    qtbot.wait(50)
    doc, hl = window.doc, window.joint_highlight
    assert hl.position is None and not hl.actor.GetVisibility()
    knee = _joint_position(doc, "left_knee")
    _click(window, window.rings.project(knee[None])[0])
    assert window.joints.selected == "left_knee"
    np.testing.assert_allclose(hl.position, knee)
    cyan = np.round(np.array(HIGHLIGHT_COLOR) * 255)
    colors = _window_pixel_colors(window, window.rings.project(knee[None])[0])
    assert np.any(np.all(np.abs(colors - cyan) < 30, axis=1))  # drawn over the mannequin
    elbow = _joint_position(doc, "right_elbow")
    _click(window, window.rings.project(elbow[None])[0])
    assert window.joints.selected == "right_elbow"
    np.testing.assert_allclose(hl.position, elbow)
    colors = _window_pixel_colors(window, window.rings.project(knee[None])[0])
    assert not np.any(np.all(np.abs(colors - cyan) < 30, axis=1))  # the knee is no longer highlighted
    doc.random_pose(seed=3)  # the pose moves: the highlight stays on the elbow
    window.viewport.refresh()
    np.testing.assert_allclose(hl.position, _joint_position(doc, "right_elbow"))
    window.joints.select(None)
    assert hl.position is None


def test_the_natural_posture_toggle_switches_between_the_prior_and_the_rest_pose(window, qtbot, studio_settings):
    from gsik.prior import bundled_prior
    from gsik_studio.model import Document
    from gsik_studio.widgets.balance_panel import balance_panel

    doc, panel = window.doc, window.balance_panel
    box = panel.natural
    assert box.isEnabled() and box.isChecked() and doc.controls.natural
    mean = np.clip(bundled_prior("biped").mean, doc.skeleton.lower, doc.skeleton.upper)
    np.testing.assert_allclose(doc.solver.posture.reference, mean)
    _click_widget(box)
    assert not box.isChecked() and not doc.controls.natural
    np.testing.assert_allclose(doc.solver.posture.reference, doc.skeleton.rest)
    assert str(studio_settings.value("controls/natural")).lower() == "false"
    again = Document()  # the next window's panel starts on the rest pose, as left
    balance_panel(again, studio_settings, lambda _on: None)
    assert not again.controls.natural
    _click_widget(box)
    assert box.isChecked() and doc.controls.natural
    np.testing.assert_allclose(doc.solver.posture.reference, mean)
    doc.controls.set_natural(False)  # the model says: the box shows it
    assert not box.isChecked()


def test_the_side_panel_fits_its_dock_at_1280x800_without_scrolling_sideways(window, qtbot):
    from PySide6 import QtCore, QtWidgets

    window.resize(1280, 800)
    qtbot.wait(100)
    scroll = window.effectors.parentWidget().parentWidget().parentWidget()
    assert isinstance(scroll, QtWidgets.QScrollArea)
    view = scroll.viewport()
    assert scroll.widget().minimumSizeHint().width() <= view.width()
    assert scroll.widget().width() <= view.width()
    for row in window.rows.values():  # every column, the errors last, lies inside what the dock shows
        for w in row.widgets():
            right = w.mapTo(view, QtCore.QPoint(w.width() - 1, 0)).x()
            assert 0 <= w.mapTo(view, QtCore.QPoint(0, 0)).x() and right < view.width()
    assert window.plotter.width() >= 700  # the 3D view keeps most of the window
