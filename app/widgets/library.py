"""The pose library panel: a list of the document's named poses with add, rename, duplicate, delete and apply."""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtCore, QtWidgets

import gsik
from gsik_studio.model import Document

#: (name, label, tooltip)
BUTTONS = (
    ("add", "Add", "Add the current pose to the library"),
    ("apply", "Apply", "Show the selected pose (double-click does the same)"),
    ("rename", "Rename…", "Rename the selected pose"),
    ("duplicate", "Duplicate", "Copy the selected pose"),
    ("delete", "Delete", "Delete the selected pose"),
)
BUTTONS_PER_ROW = 3


def ask_name(parent: QtWidgets.QWidget, title: str, current: str) -> str | None:
    """A name typed by the user (None when cancelled)."""
    text, ok = QtWidgets.QInputDialog.getText(parent, title, "Name:", text=current)
    return text if ok else None


class LibraryPanel(QtWidgets.QGroupBox):
    """The document's pose library, bound to ``doc.library.changed``.

    Args:
        doc: The document.
        report: ``(text)`` shown when a command is refused (a duplicate name).
        ask: ``(parent, title, current) -> name or None``; tests pass their own.
    """

    def __init__(self, doc: Document, report: Callable[[str], None],
                 ask: Callable[[QtWidgets.QWidget, str, str], str | None] = ask_name):
        super().__init__("Pose library")
        self.doc, self._report, self._ask = doc, report, ask
        layout = QtWidgets.QVBoxLayout(self)
        self.list = QtWidgets.QListWidget()
        self.list.setMinimumHeight(90)
        layout.addWidget(self.list)
        grid = QtWidgets.QGridLayout()  # two rows: five buttons in one would widen the side panel
        self.buttons: dict[str, QtWidgets.QPushButton] = {}
        for i, (name, label, tip) in enumerate(BUTTONS):
            b = QtWidgets.QPushButton(label)
            b.setToolTip(tip)
            grid.addWidget(b, i // BUTTONS_PER_ROW, i % BUTTONS_PER_ROW)
            self.buttons[name] = b
        layout.addLayout(grid)
        lib = doc.library
        self.buttons["add"].clicked.connect(lambda: self._run(lib.add))
        self.buttons["apply"].clicked.connect(lambda: self._on_selected(lib.apply))
        self.buttons["duplicate"].clicked.connect(lambda: self._on_selected(lib.duplicate))
        self.buttons["delete"].clicked.connect(lambda: self._on_selected(lib.delete))
        self.buttons["rename"].clicked.connect(lambda: self._on_selected(self._rename))
        self.list.itemDoubleClicked.connect(lambda item: self._run(lambda: lib.apply(item.text())))
        self.list.currentRowChanged.connect(lambda _row: self._enable())
        lib.changed.connect(self.show_library)
        self.show_library()

    @property
    def selected(self) -> str | None:
        item = self.list.currentItem()
        return item.text() if item is not None else None

    def _run(self, command: Callable[[], object]) -> object:
        try:
            return command()
        except gsik.GsikError as exc:
            self._report(str(exc))
            return None

    def _on_selected(self, command: Callable[[str], object]) -> None:
        if self.selected is not None:
            self._run(lambda: command(self.selected))

    def _rename(self, old: str) -> None:
        new = self._ask(self, "Rename pose", old)
        if new is not None:
            self.doc.library.rename(old, new)

    def show_library(self) -> None:
        current = self.selected
        names = self.doc.library.names
        with QtCore.QSignalBlocker(self.list):
            self.list.clear()
            self.list.addItems(list(names))
            if names:
                self.list.setCurrentRow(names.index(current) if current in names else len(names) - 1)
        self._enable()

    def _enable(self) -> None:
        on = self.selected is not None
        for name in ("apply", "rename", "duplicate", "delete"):
            self.buttons[name].setEnabled(on)
