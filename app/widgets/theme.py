"""The studio's dark Fusion theme."""

from __future__ import annotations

from PySide6 import QtGui, QtWidgets


def apply_dark_theme(app: QtWidgets.QApplication) -> None:
    """Fusion style with a dark palette, matching the 3D view."""
    app.setStyle("Fusion")
    p = QtGui.QPalette()
    C = QtGui.QColor
    roles = {
        QtGui.QPalette.Window: C(45, 47, 52), QtGui.QPalette.WindowText: C(222, 224, 228),
        QtGui.QPalette.Base: C(32, 34, 38), QtGui.QPalette.AlternateBase: C(50, 52, 58),
        QtGui.QPalette.ToolTipBase: C(60, 62, 68), QtGui.QPalette.ToolTipText: C(230, 230, 230),
        QtGui.QPalette.Text: C(222, 224, 228), QtGui.QPalette.Button: C(56, 59, 65),
        QtGui.QPalette.ButtonText: C(222, 224, 228), QtGui.QPalette.BrightText: C(255, 90, 90),
        QtGui.QPalette.Highlight: C(64, 120, 200), QtGui.QPalette.HighlightedText: C(255, 255, 255),
        QtGui.QPalette.Link: C(110, 160, 240), QtGui.QPalette.PlaceholderText: C(140, 142, 148),
    }
    for role, color in roles.items():
        p.setColor(role, color)
    for role in (QtGui.QPalette.WindowText, QtGui.QPalette.Text, QtGui.QPalette.ButtonText):
        p.setColor(QtGui.QPalette.Disabled, role, C(120, 122, 128))
    app.setPalette(p)
