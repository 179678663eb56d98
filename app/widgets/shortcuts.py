"""Help → Shortcuts: a table of every action's keys (read from the actions themselves) and the mouse controls."""

from __future__ import annotations

from collections.abc import Iterable

from PySide6 import QtGui, QtWidgets

#: (control, what it does) for the mouse in the 3D view.
MOUSE = (
    ("Left-drag a red target", "move the target (a click a few pixels off still grabs it)"),
    ("Left-drag a face of the box", "turn the selected target"),
    ("Left-drag elsewhere", "orbit (turntable: z stays up; View → Trackball orbit to roll freely)"),
    ("Shift + left-drag, middle-drag", "pan"),
    ("Wheel, right-drag", "zoom"),
)
NOTE = ("Single keys (F, 1, 3, 5, 7, Space, …) act on the 3D view: moving the pointer over it gives it the "
        "keyboard, so they never type into a field of the side panel.")


def shortcut_rows(actions: Iterable[QtGui.QAction]) -> list[tuple[str, str]]:
    """``[(keys, action text)]`` for every action with a shortcut, in the order given, without duplicates."""
    rows, seen = [], set()
    for a in actions:
        keys = ", ".join(s.toString(QtGui.QKeySequence.NativeText) for s in a.shortcuts())
        text = a.text().replace("&", "").rstrip("…")
        if keys and (keys, text) not in seen:
            seen.add((keys, text))
            rows.append((keys, text))
    return rows


class ShortcutsDialog(QtWidgets.QDialog):
    """The list of keys and mouse controls; non-modal, so it can stay open while working."""

    def __init__(self, parent: QtWidgets.QWidget, actions: Iterable[QtGui.QAction]):
        super().__init__(parent)
        self.setWindowTitle("Shortcuts — gsik studio")
        rows = shortcut_rows(actions) + list(MOUSE)
        self.table = QtWidgets.QTableWidget(len(rows), 2, self)
        self.table.setHorizontalHeaderLabels(["Key or mouse", "Does"])
        for r, (keys, text) in enumerate(rows):
            for c, value in enumerate((keys, text)):
                self.table.setItem(r, c, QtWidgets.QTableWidgetItem(value))
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.NoEditTriggers)
        self.table.verticalHeader().hide()
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.resizeColumnsToContents()
        note = QtWidgets.QLabel(NOTE)
        note.setWordWrap(True)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(self.table)
        layout.addWidget(note)
        self.resize(620, 560)

    def texts(self) -> list[tuple[str, str]]:
        """Every row as shown (for tests)."""
        return [(self.table.item(r, 0).text(), self.table.item(r, 1).text()) for r in range(self.table.rowCount())]
