"""The selected-target panel: turn the selected target about a world axis, snap it to its effector."""

from __future__ import annotations

import math
from collections.abc import Callable

from PySide6 import QtWidgets

from gsik_studio.model import Document
from gsik_studio.widgets import hint, nice

ROTATE_STEP_DEG = 15.0
AXIS_COLORS = {"x": "#e0463c", "y": "#3cb043", "z": "#4a7cff"}


class SelectedTargetPanel(QtWidgets.QGroupBox):
    """The "Selected target" group; ``selected()`` names the selected target (None: none)."""

    def __init__(self, doc: Document, selected: Callable[[], str | None]):
        super().__init__("Selected target")
        self.doc = doc
        self._selected = selected
        v = QtWidgets.QVBoxLayout(self)
        self.label = QtWidgets.QLabel("none")
        v.addWidget(self.label)
        rot = QtWidgets.QGridLayout()
        self.rotate_buttons: dict[tuple[str, int], QtWidgets.QPushButton] = {}
        for r, axis in enumerate("xyz"):
            rot.addWidget(QtWidgets.QLabel(f"<b style='color:{AXIS_COLORS[axis]}'>{axis}</b>"), r, 0)
            for c, sign in enumerate((-1, 1)):
                text = f"{'−' if sign < 0 else '+'}{ROTATE_STEP_DEG:.0f}°"
                b = QtWidgets.QPushButton(text)
                b.setToolTip(f"Turn the selected target {text} about the world {axis} axis")
                b.clicked.connect(lambda _c=False, a=axis, s=sign: self.rotate(a, s * ROTATE_STEP_DEG))
                rot.addWidget(b, r, c + 1)
                self.rotate_buttons[(axis, sign)] = b
        v.addLayout(rot)
        self.snap_button = QtWidgets.QPushButton("Snap target to effector")
        self.snap_button.clicked.connect(self.snap)
        v.addWidget(self.snap_button)
        v.addWidget(hint("Drag a red sphere to move a target; drag a face of the box around "
                         "the selected target to turn it."))

    def _target(self) -> str | None:
        name = self._selected()
        return name if name is not None and name in self.doc.targets else None

    def rotate(self, axis: str, degrees: float) -> None:
        """Turn the selected target by ``degrees`` about the world ``axis``."""
        name = self._target()
        if name is not None:
            self.doc.rotate_target(name, axis, math.radians(degrees))

    def snap(self) -> None:
        name = self._target()
        if name is not None:
            self.doc.snap_target(name)

    def show_selection(self, name: str | None) -> None:
        has = name is not None and name in self.doc.targets
        self.label.setText(f"<b>{nice(name)}</b>" if has else "none (click a target)")
        for b in self.rotate_buttons.values():
            b.setEnabled(has)
        self.snap_button.setEnabled(has)
