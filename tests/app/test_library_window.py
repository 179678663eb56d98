"""The pose library panel in the real window under Xvfb: real clicks on its buttons and list."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui



def _click(qtbot, button):
    from PySide6.QtCore import Qt

    assert button.isEnabled()
    qtbot.mouseClick(button, Qt.LeftButton)


def _select(qtbot, panel, name):
    from PySide6.QtCore import Qt

    item = panel.list.findItems(name, Qt.MatchExactly)[0]
    rect = panel.list.visualItemRect(item)
    qtbot.mouseClick(panel.list.viewport(), Qt.LeftButton, pos=rect.center())
    assert panel.selected == name


def test_library_panel_add_apply_rename_duplicate_delete_and_undo(qtbot, window):
    panel, doc = window.library_panel, window.doc
    standing = doc.pose()
    _click(qtbot, panel.buttons["add"])
    window.act_random.trigger()
    window.settle()
    random = doc.pose()
    _click(qtbot, panel.buttons["add"])
    assert [panel.list.item(i).text() for i in range(panel.list.count())] == ["pose 1", "pose 2"]
    _select(qtbot, panel, "pose 1")
    _click(qtbot, panel.buttons["apply"])
    assert doc.pose() == standing and doc.history.undo_text == "Apply pose pose 1"
    panel._ask = lambda parent, title, current: "wild"
    _select(qtbot, panel, "pose 2")
    _click(qtbot, panel.buttons["rename"])
    _click(qtbot, panel.buttons["duplicate"])
    assert doc.library.names == ("pose 1", "wild", "wild copy")
    _select(qtbot, panel, "pose 1")
    _click(qtbot, panel.buttons["delete"])
    assert [panel.list.item(i).text() for i in range(panel.list.count())] == ["wild", "wild copy"]
    # Double-click applies.
    from PySide6.QtCore import Qt

    item = panel.list.findItems("wild copy", Qt.MatchExactly)[0]
    at = panel.list.visualItemRect(item).center()
    qtbot.mouseClick(panel.list.viewport(), Qt.LeftButton, pos=at)  # a person's double-click starts with a click
    qtbot.mouseDClick(panel.list.viewport(), Qt.LeftButton, pos=at)
    assert doc.pose() == random
    for _ in range(2):
        window.act_undo.trigger()  # apply, then delete undone
    assert [panel.list.item(i).text() for i in range(panel.list.count())] == ["pose 1", "wild", "wild copy"]


def test_a_duplicate_name_is_reported_and_nothing_changes(qtbot, window):
    panel = window.library_panel
    _click(qtbot, panel.buttons["add"])
    _click(qtbot, panel.buttons["add"])
    panel._ask = lambda parent, title, current: "pose 1"
    _select(qtbot, panel, "pose 2")
    _click(qtbot, panel.buttons["rename"])
    assert window.doc.library.names == ("pose 1", "pose 2")
    assert "already has a pose named 'pose 1'" in window.statusBar().currentMessage()
