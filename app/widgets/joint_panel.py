"""The selected-joint panel: type a joint's angles, choose whether the targets follow a turned limb."""

from __future__ import annotations

import math

from PySide6 import QtCore, QtWidgets

from gsik_studio.model.joints import JointEditor
from gsik_studio.widgets import hint, nice
from gsik_studio.widgets.selected import AXIS_COLORS

MAX_DOFS = 3  # a joint turns about at most three axes


class JointPanel(QtWidgets.QGroupBox):
    """The "Selected joint" group bound to a :class:`JointEditor`: one angle editor per rotation, in degrees."""

    def __init__(self, editor: JointEditor):
        super().__init__("Selected joint")
        self.editor = editor
        form = QtWidgets.QFormLayout(self)
        self.label = QtWidgets.QLabel()
        form.addRow(self.label)
        self.axis_labels: list[QtWidgets.QLabel] = []
        self.angles: list[QtWidgets.QDoubleSpinBox] = []
        for k in range(MAX_DOFS):
            spin = QtWidgets.QDoubleSpinBox()
            spin.setDecimals(1)
            spin.setSuffix(" °")
            spin.setKeyboardTracking(False)  # one turn per finished entry
            spin.valueChanged.connect(lambda deg, k=k: self._set_angle(k, deg))
            label = QtWidgets.QLabel()
            form.addRow(label, spin)
            self.axis_labels.append(label)
            self.angles.append(spin)
        self.follow = QtWidgets.QCheckBox("Targets follow the turned limb")
        self.follow.setToolTip("On: the targets move with the limb, so the pose holds as turned.\n"
                               "Off: the targets stay; the solver brings the effectors back to them.")
        self.follow.setChecked(editor.targets_follow)
        self.follow.toggled.connect(lambda on: setattr(editor, "targets_follow", bool(on)))
        form.addRow(self.follow)
        form.addRow(hint("Click a joint to select it; drag one of its rings "
                         "(x red, y green, z blue) to turn it within its limits."))
        editor.selection_changed.connect(lambda _name: self.show_joint())
        self.show_joint()

    def _set_angle(self, k: int, degrees: float) -> None:
        dofs = self.editor.dofs()
        if k < len(dofs):
            self.editor.set_angle(dofs[k].index, math.radians(degrees))

    def show_joint(self) -> None:
        """Show the selected joint's rotations: limits as the editors' ranges, angles now."""
        dofs = self.editor.dofs()
        name = self.editor.selected
        self.label.setText(f"<b>{nice(name)}</b>" if name else "none (click a joint)")
        for k, (label, spin) in enumerate(zip(self.axis_labels, self.angles)):
            shown = k < len(dofs)
            label.setVisible(shown)
            spin.setVisible(shown)
            if shown:
                d = dofs[k]
                label.setText(f"<b style='color:{AXIS_COLORS[d.axis]}'>{d.axis}</b> {nice(d.name.split('.')[0])}")
                with QtCore.QSignalBlocker(spin):
                    spin.setRange(math.degrees(d.lower), math.degrees(d.upper))
        self.show_angles()

    def show_angles(self) -> None:
        """The selected joint's angles now, in degrees (signals blocked: showing never turns the joint)."""
        for d, spin in zip(self.editor.dofs(), self.angles):
            if spin.hasFocus():
                continue  # the artist is typing here
            with QtCore.QSignalBlocker(spin):
                spin.setValue(math.degrees(self.editor.angle(d.index)))
