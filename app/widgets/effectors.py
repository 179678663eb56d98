"""The effectors panel: per effector a select button, enabled / pin / weight / position-only, and its errors."""

from __future__ import annotations

import math
from collections.abc import Callable

from PySide6 import QtCore, QtGui, QtWidgets
from PySide6.QtCore import Qt

from gsik_studio.model import Document
from gsik_studio.model.pins import is_pinned, pin_level
from gsik_studio.widgets import nice

COLUMNS = (("", ""), ("on", "Enabled"), ("pin", "Pinned: a higher priority level than unpinned targets"),
           ("weight", "Weight"), ("pos<br>only", "Position only"),
           ("pos err", "Position error [mm]"), ("rot err", "Orientation error [deg]"))


class EffectorRow:
    """The panel's widgets for one effector."""

    def __init__(self, name: str):
        self.name = name
        self.button = QtWidgets.QPushButton(nice(name))
        self.button.setCheckable(True)
        self.button.setToolTip(f"Select the {nice(name)} target (its rotate box appears in the view)")
        self.button.setStyleSheet("QPushButton { text-align: left; padding: 2px 6px; }"
                                  "QPushButton:checked { background: #3d6db3; color: white; font-weight: bold; }")
        self.enabled = QtWidgets.QCheckBox()
        self.enabled.setToolTip("Enabled: the solver pulls this effector to its target")
        self.pin = QtWidgets.QCheckBox()
        self.pin.setToolTip("Pinned: met first; pulling an unpinned target never moves a pinned one")
        self.weight = QtWidgets.QDoubleSpinBox()
        self.weight.setRange(0.0, 100.0)
        self.weight.setDecimals(2)
        self.weight.setSingleStep(0.1)
        self.weight.setToolTip("Weight: relative importance in the least-squares solve")
        self.weight.setKeyboardTracking(False)
        self.weight.setMaximumWidth(68)
        self.position_only = QtWidgets.QCheckBox()
        self.position_only.setToolTip("Position only: ignore the target's orientation")
        self.position_error = QtWidgets.QLabel("–")
        self.orientation_error = QtWidgets.QLabel("–")
        for label in (self.position_error, self.orientation_error):
            label.setAlignment(Qt.AlignRight | Qt.AlignVCenter)
            label.setMinimumWidth(42)
            label.setFont(QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont))

    def widgets(self):
        return (self.button, self.enabled, self.pin, self.weight, self.position_only, self.position_error,
                self.orientation_error)

    def show_target(self, target, is_root: bool) -> None:
        """Show a target's flags (``None``: no target, the effector is the root), signals blocked."""
        blockers = [QtCore.QSignalBlocker(w) for w in (self.enabled, self.pin, self.weight, self.position_only)]
        on = target is not None and target.enabled
        self.enabled.setEnabled(target is not None)
        self.weight.setEnabled(on)
        self.position_only.setEnabled(on)
        self.pin.setEnabled(on)
        self.button.setEnabled(target is not None)
        self.button.setText(f"{nice(self.name)}  (root)" if is_root else nice(self.name))
        if target is not None:
            self.enabled.setChecked(target.enabled)
            self.weight.setValue(target.weight)
            self.position_only.setChecked(target.position_only)
            self.pin.setChecked(is_pinned(target))
        del blockers

    def show_errors(self, target, errors: tuple[float, float] | None) -> None:
        """Position error [m] shown in mm, orientation error [rad] in degrees ("–" where not solved for)."""
        if errors is None or target is None or not target.enabled:
            self.position_error.setText("–")
            self.orientation_error.setText("–")
            return
        p, o = errors
        self.position_error.setText(f"{p * 1000:.1f}")
        self.orientation_error.setText("–" if target.position_only else f"{math.degrees(o):.1f}")


class EffectorsPanel(QtWidgets.QGroupBox):
    """The "Effectors" group bound to a document; ``select(name)`` is called when a row's button is clicked."""

    def __init__(self, doc: Document, select: Callable[[str], None]):
        super().__init__("Effectors")
        self.doc = doc
        grid = QtWidgets.QGridLayout(self)
        grid.setHorizontalSpacing(8)
        grid.setVerticalSpacing(4)
        for col, (text, tip) in enumerate(COLUMNS):
            head = QtWidgets.QLabel(f"<small><b>{text}</b></small>")
            head.setToolTip(tip)
            grid.addWidget(head, 0, col, Qt.AlignCenter if col else Qt.AlignLeft)
        self.rows: dict[str, EffectorRow] = {}
        self.select_group = QtWidgets.QButtonGroup(self)
        self.select_group.setExclusive(True)
        for r, name in enumerate(doc.skeleton.effector_sites, start=1):
            row = self.rows[name] = EffectorRow(name)
            self.select_group.addButton(row.button)
            for col, w in enumerate(row.widgets()):
                grid.addWidget(w, r, col, Qt.AlignCenter if col in (1, 2, 4) else Qt.Alignment())
            row.button.clicked.connect(lambda _c=False, n=name: select(n))
            row.enabled.toggled.connect(lambda v, n=name: self._set_option(n, enabled=v))
            row.pin.toggled.connect(lambda v, n=name: self._set_option(n, priority=pin_level(v)))
            row.weight.valueChanged.connect(lambda v, n=name: self._set_option(n, weight=v))
            row.position_only.toggled.connect(lambda v, n=name: self._set_option(n, position_only=v))
        units = QtWidgets.QLabel("<small>errors: position [mm], orientation [deg]</small>")
        units.setStyleSheet("color: gray")
        grid.addWidget(units, len(self.rows) + 1, 0, 1, len(COLUMNS))
        doc.events.pose.connect(self.show_targets)
        doc.events.options.connect(self.show_targets)
        self.show_targets()

    def _set_option(self, name: str, **option) -> None:
        if name in self.doc.targets:
            self.doc.set_target_options(name, **option)

    def show_targets(self) -> None:
        targets = self.doc.targets
        for name, row in self.rows.items():
            row.show_target(targets.get(name), name == self.doc.root)

    def show_selection(self, name: str | None) -> None:
        for n, row in self.rows.items():
            with QtCore.QSignalBlocker(row.button):
                row.button.setChecked(n == name)

    def show_errors(self) -> None:
        targets, errors = self.doc.targets, self.doc.effector_errors()
        for name, row in self.rows.items():
            row.show_errors(targets.get(name), errors.get(name))
