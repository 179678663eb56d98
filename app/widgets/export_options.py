"""The Export BVH options: the file's up axis and length unit (default y-up centimetres, what Blender's BVH
importer expects by default, so the figure comes in standing)."""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets

from gsik_studio.model.transfer import BvhExportOptions

#: (value, text) of each choice, the default first.
UP_AXES = (("y", "y up (Blender's default, Maya, most tools)"), ("z", "z up (gsik's own axes)"))
UNITS = (("cm", "centimetres (Blender's default import scale)"), ("m", "metres"))


class ExportOptionsDialog(QtWidgets.QDialog):
    """Up axis and units for a BVH export, remembered in ``settings`` under ``export/``."""

    def __init__(self, parent: QtWidgets.QWidget | None, settings: QtCore.QSettings):
        super().__init__(parent)
        self.setWindowTitle("Export BVH")
        self.settings = settings
        form = QtWidgets.QFormLayout(self)
        self.up, self.units = QtWidgets.QComboBox(), QtWidgets.QComboBox()
        for combo, choices, key in ((self.up, UP_AXES, "up"), (self.units, UNITS, "units")):
            for value, text in choices:
                combo.addItem(text, value)
            combo.setCurrentIndex(max(combo.findData(str(settings.value(f"export/{key}", choices[0][0]))), 0))
        form.addRow("Up axis", self.up)
        form.addRow("Units", self.units)
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.Ok | QtWidgets.QDialogButtonBox.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form.addRow(buttons)

    def options(self) -> BvhExportOptions:
        """What the dialog shows now."""
        return BvhExportOptions(up=self.up.currentData(), units=self.units.currentData())

    def accept(self) -> None:
        chosen = self.options()
        self.settings.setValue("export/up", chosen.up)
        self.settings.setValue("export/units", chosen.units)
        super().accept()
