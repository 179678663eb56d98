"""The "Posture and balance" panel: posture strength (a field row), balance, the centre of mass shown, pole targets."""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtCore, QtWidgets

import gsik
from gsik_studio.model import Document
from gsik_studio.widgets.fields import Field, FieldForm

CONTROL_FIELDS = (
    Field("posture_strength", "Posture strength", float, 0.0, 10.0, decimals=2, step=0.05,
          tip="How much the body prefers its rest pose, below every target (0: off). It never costs accuracy: "
              "it only chooses among the poses that meet the targets."),
)


def balance_panel(doc: Document, settings: QtCore.QSettings, show_support: Callable[[bool], None]) -> FieldForm:
    """The group bound to ``doc.controls``; ``show_support(on)`` shows or hides the centre of mass in the view.

    The posture strength is remembered under ``controls/`` in ``settings``.
    """
    controls = doc.controls
    form = FieldForm("Posture and balance", CONTROL_FIELDS, lambda: controls,
                     lambda changes: controls.set_posture_strength(changes["posture_strength"]), settings, "controls")
    form.balance = QtWidgets.QCheckBox("Balance: keep the centre of mass over the feet")
    form.balance.setToolTip("Holds the centre of mass's ground projection inside the support polygon, "
                            "below pinned targets and above unpinned ones")
    form.show_com = QtWidgets.QCheckBox("Show centre of mass and support polygon")
    form.show_com.setChecked(True)
    for box in (form.balance, form.show_com):
        box.setEnabled(controls.has_masses)
        form.layout().addRow(box)
    form.poles = QtWidgets.QCheckBox("Pole targets for knees and elbows")
    form.poles.setToolTip("Small violet spheres on the knees and elbows: drag one to swing the limb's bend, "
                          "below every other target (a hand or foot never moves for it)")
    form.poles.setEnabled(bool(controls.pole_joints))
    form.poles.toggled.connect(controls.set_poles)
    form.layout().addRow(form.poles)

    def show_poles() -> None:  # undo, redo and opened files turn poles on or off too
        with QtCore.QSignalBlocker(form.poles):
            form.poles.setChecked(bool(controls.poles))

    def set_balance(on: bool) -> None:
        try:
            controls.set_balance(on)
        except gsik.GsikError as exc:
            form.rejected.emit(str(exc))
        with QtCore.QSignalBlocker(form.balance):
            form.balance.setChecked(controls.balance)

    form.balance.toggled.connect(set_balance)
    form.show_com.toggled.connect(show_support)
    controls.changed.connect(form.show_model)
    controls.changed.connect(show_poles)
    show_poles()  # a document opened before the window may have poles on
    return form
