"""One table of fields drives a settings form: creation, model -> widget, widget -> model, persistence.

A :class:`Field` is one row: the model attribute's name, its label, type,
range and :class:`Unit` (how the model's SI value is shown: mm, degrees).
:class:`FieldForm` makes one spin box per row and keeps them and the model in
step; adding a setting is adding a row.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from PySide6 import QtCore, QtWidgets

import gsik


def _same(value):
    return value


@dataclass(frozen=True)
class Unit:
    """How a model value [SI] is shown: ``suffix`` after the number, and the two conversions."""

    suffix: str = ""
    to_display: Callable[[float], float] = _same
    to_model: Callable[[float], float] = _same


PLAIN = Unit()
RADIANS = Unit(" rad")
MILLIMETRES = Unit(" mm", lambda m: m * 1000.0, lambda mm: mm / 1000.0)
DEGREES = Unit(" °", math.degrees, math.radians)


@dataclass(frozen=True)
class Field:
    """One row of a settings table.

    Attributes:
        name: The model's attribute and keyword (``gsik.SolverSettings.<name>``).
        label: Shown before the editor.
        type: ``int`` (a spin box) or ``float`` (a decimal spin box).
        minimum, maximum: The editor's range, in display units.
        unit: Display unit and conversions.
        decimals: Digits after the point (float fields).
        step: Arrow-key step, in display units.
        tip: Tooltip.
    """

    name: str
    label: str
    type: type
    minimum: float
    maximum: float
    unit: Unit = PLAIN
    decimals: int = 3
    step: float = 1.0
    tip: str = ""

    def make_editor(self) -> QtWidgets.QAbstractSpinBox:
        if self.type is int:
            w = QtWidgets.QSpinBox()
            w.setRange(int(self.minimum), int(self.maximum))
        else:
            w = QtWidgets.QDoubleSpinBox()
            w.setDecimals(self.decimals)
            w.setRange(self.minimum, self.maximum)
            w.setSingleStep(self.step)
        w.setSuffix(self.unit.suffix)
        w.setToolTip(self.tip)
        w.setKeyboardTracking(False)  # one model write per finished entry, not per keystroke
        return w

    def to_model(self, shown: float):
        """The model value of a value shown in the editor."""
        return self.type(self.unit.to_model(shown))

    def to_display(self, value: float) -> float:
        return self.unit.to_display(value)


class FieldForm(QtWidgets.QGroupBox):
    """A group box with one editor per :class:`Field`, bound to a model through two callables.

    Args:
        title: The group's title.
        fields: The table.
        read: Returns the model object whose attributes are the fields' names.
        write: Applies ``{name: model value}`` to the model; raises :class:`gsik.GsikError` on a bad value.
        settings: Where values are remembered, under ``group/<name>``.
        group: The QSettings group.

    Signals:
        rejected(str): the model refused a value (the editor shows the model's value again).
    """

    rejected = QtCore.Signal(str)

    def __init__(self, title: str, fields: Sequence[Field], read: Callable[[], object],
                 write: Callable[[Mapping[str, object]], None], settings: QtCore.QSettings, group: str):
        super().__init__(title)
        self.fields = {f.name: f for f in fields}
        self._read, self._write, self._settings, self._group = read, write, settings, group
        self.editors: dict[str, QtWidgets.QAbstractSpinBox] = {}
        form = QtWidgets.QFormLayout(self)
        for f in fields:
            w = self.editors[f.name] = f.make_editor()
            form.addRow(f.label, w)
            w.valueChanged.connect(lambda shown, f=f: self.commit(f.name, shown))

    def show_model(self) -> None:
        """Model -> editors, inside signal blockers, so that showing a value never writes it back."""
        model = self._read()
        for name, w in self.editors.items():
            with QtCore.QSignalBlocker(w):
                w.setValue(self.fields[name].to_display(getattr(model, name)))

    def commit(self, name: str, shown: float) -> None:
        """Editor -> model; remembers the accepted value, or shows the model's again on an error."""
        try:
            self._write({name: self.fields[name].to_model(shown)})
        except gsik.GsikError as exc:
            self.rejected.emit(str(exc))
            self.show_model()
            return
        self._settings.setValue(f"{self._group}/{name}", getattr(self._read(), name))

    def restore(self) -> None:
        """Apply the remembered values (unreadable ones and a refused set are ignored), then show the model."""
        changes = {}
        for name, f in self.fields.items():
            v = self._settings.value(f"{self._group}/{name}")
            if v is None:
                continue
            try:
                changes[name] = f.type(float(v))
            except (TypeError, ValueError):
                continue
        try:
            if changes:
                self._write(changes)
        except gsik.GsikError:
            pass
        self.show_model()


#: The editors whose value the mouse wheel changes (spin boxes, sliders, combo boxes).
WHEEL_EDITORS = (QtWidgets.QAbstractSpinBox, QtWidgets.QAbstractSlider, QtWidgets.QComboBox)


class WheelGuard(QtCore.QObject):
    """Lets the wheel change an editor's value only while the editor has the keyboard focus.

    Without focus the wheel event is ignored and handed on to the parents, so the panel's scroll area scrolls
    under the pointer instead of a spin box turning a joint. :func:`guard_wheel` installs it.
    """

    def eventFilter(self, watched: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802 (Qt's name)
        if event.type() == QtCore.QEvent.Wheel and not watched.hasFocus():
            event.ignore()  # not accepted: Qt offers it to the parent widgets (the scroll area)
            return True
        return False


def guard_wheel(root: QtWidgets.QWidget) -> WheelGuard:
    """Guard every wheel-driven editor inside ``root``: a click or Tab focuses it (``Qt.StrongFocus``, never the
    wheel), and the wheel changes it only while focused. Returns the guard (owned by ``root``)."""
    guard = WheelGuard(root)
    for kind in WHEEL_EDITORS:
        for w in root.findChildren(kind):
            w.setFocusPolicy(QtCore.Qt.StrongFocus)
            w.installEventFilter(guard)
    return guard
