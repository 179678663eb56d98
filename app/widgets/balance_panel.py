"""The "Posture and balance" panel: posture strength (a field row), balance, the centre of mass shown, pole targets."""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtCore, QtWidgets

import gsik
from gsik_studio.model import Document
from gsik_studio.widgets.fields import Field, FieldForm

CONTROL_FIELDS = (
    Field("posture_strength", "Posture strength", float, 0.0, 10.0, decimals=2, step=0.05,
          tip="How much the body prefers its posture (natural or rest), below every target (0: off). It never costs "
              "accuracy: it only chooses among the poses that meet the targets."),
)


def balance_panel(doc: Document, settings: QtCore.QSettings, show_support: Callable[[bool], None]) -> FieldForm:
    """The group bound to ``doc.controls``; ``show_support(on)`` shows or hides the centre of mass in the view.

    The posture strength and the natural toggle are remembered under ``controls/`` in ``settings``.
    """
    controls = doc.controls
    form = FieldForm("Posture and balance", CONTROL_FIELDS, lambda: controls,
                     lambda changes: controls.set_posture_strength(changes["posture_strength"]), settings, "controls")
    form.natural = _natural_box(controls, settings)
    form.layout().addRow(form.natural)
    form.balance = QtWidgets.QCheckBox("Balance: keep the centre of mass over the feet")
    form.balance.setToolTip("Holds the centre of mass's ground projection inside the support polygon, "
                            "below pinned targets and above unpinned ones")
    form.show_com = QtWidgets.QCheckBox("Show centre of mass and support polygon")
    form.show_com.setChecked(True)
    for box in (form.balance, form.show_com):
        box.setEnabled(controls.has_masses)
        form.layout().addRow(box)
    form.poles = QtWidgets.QCheckBox("Pole targets for knees and elbows")
    form.poles.setToolTip("Violet spheres in front of the knees and behind the elbows: drag one to swing the limb's bend, "
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
    controls.changed.connect(lambda: _show_natural(form.natural, controls))
    controls.changed.connect(show_poles)
    show_poles()  # a document opened before the window may have poles on
    return form


def _natural_box(controls, settings: QtCore.QSettings) -> QtWidgets.QCheckBox:
    """The "natural posture" check box: the learned pose prior, or the plain rest pose (remembered)."""
    box = QtWidgets.QCheckBox("Natural posture (learned from motion capture)")
    box.setToolTip("On: the body prefers the likeliest human pose among those that meet the targets (a pose prior "
                   "learned from motion capture). Off: it prefers the rest pose.")
    box.setEnabled(controls.posture.can_be_natural)
    if not box.isEnabled():
        box.setToolTip("No pose prior is bundled for this skeleton: its posture is the rest pose")
    else:  # remembered, else the model's default (gsik_studio.model.posture.NATURAL_BY_DEFAULT)
        remembered = str(settings.value("controls/natural", controls.natural)).lower() == "true"
        if remembered != controls.natural:
            controls.set_natural(remembered)

    def toggled(on: bool) -> None:
        controls.set_natural(on)
        settings.setValue("controls/natural", controls.natural)

    box.toggled.connect(toggled)
    _show_natural(box, controls)
    return box


def _show_natural(box: QtWidgets.QCheckBox, controls) -> None:
    with QtCore.QSignalBlocker(box):
        box.setChecked(controls.natural)
