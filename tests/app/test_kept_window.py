"""Keys, pole targets and the library in the real window under Xvfb: a key added with the timeline's button, a pole
dragged with the mouse, both undone and redone from the Edit menu, saved and reopened through the File menu, and a bad
file that ends in one dialog and changes nothing."""

from __future__ import annotations

import numpy as np
import pytest

from test_artist_gui import _click_widget, _press_drag_release, _settle

pytestmark = pytest.mark.gui


@pytest.fixture()
def window(window, qtbot):
    """The studio's window (conftest.py), seen from the front."""
    window.set_view("front")
    qtbot.wait(50)
    return window


def _menu_action(window, menu_title, action):
    """``action`` (a window action) after checking that the menu ``menu_title`` holds it."""
    menu = next(a.menu() for a in window.menuBar().actions() if a.text() == menu_title)
    assert action in menu.actions()
    return action


@pytest.fixture()
def dialogs(monkeypatch, tmp_path):
    """File dialogs answered with ``dialogs["path"]`` (a file in tmp_path)."""
    from PySide6.QtWidgets import QFileDialog

    answer = {"path": str(tmp_path / "kept.yaml")}
    for name in ("getSaveFileName", "getOpenFileName"):
        monkeypatch.setattr(QFileDialog, name, staticmethod(lambda *a, **k: (answer["path"], "")))
    return answer


def _drag_pole(window, qtbot, joint, dx_px):
    """Drag one pole's violet sphere sideways with the real mouse; returns the pole's position before."""
    doc = window.doc
    before = doc.controls.poles[joint].position.copy()
    xy = window.rings.project(before[None])[0]
    _press_drag_release(window, xy, xy + np.array([dx_px, 0.0]))
    assert not np.allclose(doc.controls.poles[joint].position, before)
    return before


def _gizmo_at(window, joint) -> np.ndarray:
    return np.array(window.poles.widgets[joint].GetCenter())


def test_a_key_and_a_dragged_pole_undo_save_reopen_and_undo(qtbot, window, boxes, dialogs):
    from PySide6.QtCore import Qt

    doc, bar, panel = window.doc, window.timeline_bar, window.balance_panel
    doc.move_target("pelvis", doc.targets["pelvis"].position + (0.0, 0.0, -0.08))  # crouch: the knees bend
    _settle(qtbot, window)
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)  # key the crouch at frame 0
    assert sorted(doc.timeline.keys) == [0] and bar.slider.keys == [0]
    _click_widget(panel.poles)
    assert panel.poles.isChecked() and all(w.GetEnabled() for w in window.poles.widgets.values())
    _settle(qtbot, window)
    start = _drag_pole(window, qtbot, "left_knee", 80.0)
    moved = doc.controls.poles["left_knee"].position.copy()
    assert [c.text for c in doc.history.commands][-3:] == ["Add key at frame 0", "Pole targets on",
                                                           "Move pole left_knee"]  # the whole drag: one step
    # Edit → Undo twice: the pole goes back, then the poles go off; the check box and the spheres follow.
    undo, redo = _menu_action(window, "&Edit", window.act_undo), _menu_action(window, "&Edit", window.act_redo)
    undo.trigger()
    np.testing.assert_array_equal(doc.controls.poles["left_knee"].position, start)
    np.testing.assert_allclose(_gizmo_at(window, "left_knee"), start, atol=1e-9)
    undo.trigger()
    assert doc.controls.poles == {} and not panel.poles.isChecked()
    assert not any(w.GetEnabled() for w in window.poles.widgets.values())
    undo.trigger()
    assert doc.timeline.keys == {} and bar.slider.keys == []
    for _ in range(3):
        redo.trigger()
    assert sorted(doc.timeline.keys) == [0] and panel.poles.isChecked()
    np.testing.assert_array_equal(doc.controls.poles["left_knee"].position, moved)
    np.testing.assert_allclose(_gizmo_at(window, "left_knee"), moved, atol=1e-9)
    doc.library.add("crouch")

    _menu_action(window, "&File", window.act_save).trigger()  # no file yet: Save As, answered by `dialogs`
    assert boxes["critical"] == [] and doc.path == dialogs["path"] and not doc.dirty
    keys, library = dict(doc.timeline.keys), doc.library.snapshot()

    # Change all of it with the widgets, then File → Open the saved file (unsaved changes: answered Discard).
    qtbot.mouseClick(bar.buttons["delete_key"], Qt.LeftButton)
    _click_widget(panel.poles)
    assert doc.timeline.keys == {} and doc.controls.poles == {}
    _menu_action(window, "&File", window.act_open).trigger()
    assert len(boxes["question"]) == 1 and boxes["critical"] == []
    assert doc.timeline.keys == keys and bar.slider.keys == [0] and doc.library.snapshot() == library
    assert panel.poles.isChecked() and all(w.GetEnabled() for w in window.poles.widgets.values())
    np.testing.assert_array_equal(doc.controls.poles["left_knee"].position, moved)
    np.testing.assert_allclose(_gizmo_at(window, "left_knee"), moved, atol=1e-9)
    assert not doc.dirty and not doc.history.can_undo
    # The reopened document undoes like any other: a new drag, then Undo puts the pole back where it was saved.
    qtbot.wait(100)  # a few frames of the real timer
    _drag_pole(window, qtbot, "left_knee", -60.0)
    assert doc.dirty
    undo.trigger()
    np.testing.assert_array_equal(doc.controls.poles["left_knee"].position, moved)
    assert not doc.dirty


def test_a_bad_keys_file_gets_one_dialog_and_changes_nothing(qtbot, window, boxes, dialogs, tmp_path):
    from PySide6.QtCore import Qt

    doc = window.doc
    qtbot.mouseClick(window.timeline_bar.buttons["key"], Qt.LeftButton)
    _click_widget(window.balance_panel.poles)
    doc.save(dialogs["path"])
    bad = tmp_path / "bad.yaml"
    bad.write_text(open(dialogs["path"]).read().replace("  fps: 30.0", "  fps: -1.0"))
    dialogs["path"] = str(bad)
    qtbot.mouseClick(window.timeline_bar.buttons["delete_key"], Qt.LeftButton)  # unsaved: keys {}, poles on
    before, history = doc.pose(), list(doc.history.commands)
    poles = doc.controls.pole_snapshot()
    _menu_action(window, "&File", window.act_open).trigger()
    assert len(boxes["critical"]) == 1
    _title, text = boxes["critical"][0]
    assert "bad.yaml" in text and "keys.fps" in text and "nothing was changed" in text
    assert doc.pose() == before and doc.history.commands == history and doc.timeline.keys == {}
    assert doc.controls.pole_snapshot() == poles and window.balance_panel.poles.isChecked()
    assert doc.path != str(bad)


def test_a_window_on_a_document_opened_with_poles_shows_them(qtbot, window, tmp_path):
    from gsik_studio.model import Document

    doc = Document()
    doc.controls.set_poles(True)
    doc.controls.move_pole("left_knee", doc.controls.poles["left_knee"].position + (0.25, -0.1, 0.0))
    doc.save(tmp_path / "poles.yaml")
    opened = Document()
    opened.open(tmp_path / "poles.yaml")  # as `gsik-studio --screenshot out.png poles.yaml` does
    other = window.open_document(opened)
    try:
        qtbot.waitExposed(other)
        assert other.balance_panel.poles.isChecked()
        assert all(w.GetEnabled() for w in other.poles.widgets.values())
        np.testing.assert_allclose(_gizmo_at(other, "left_knee"), opened.controls.poles["left_knee"].position,
                                   atol=1e-9)
    finally:
        other.close()
