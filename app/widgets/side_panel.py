"""The "Pose" dock's content for one document: effectors, selected target and joint, posture and balance,
pose library and solver settings, stacked in a scroll area that never scrolls sideways."""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtCore, QtWidgets
from PySide6.QtCore import Qt

from gsik_studio.model import Document
from gsik_studio.model.joints import JointEditor
from gsik_studio.widgets.balance_panel import balance_panel
from gsik_studio.widgets.effectors import EffectorsPanel
from gsik_studio.widgets.fields import guard_wheel
from gsik_studio.widgets.joint_panel import JointPanel
from gsik_studio.widgets.library import LibraryPanel
from gsik_studio.widgets.selected import SelectedTargetPanel
from gsik_studio.widgets.solver_panel import solver_panel

#: Least width of the dock [px].
MIN_WIDTH = 440


class SidePanel(QtWidgets.QScrollArea):
    """The panels bound to one document, top to bottom (the names of :attr:`PARTS` are its attributes).

    Args:
        doc: The document.
        joints: Its joint editor (the selected joint's panel).
        settings: Where the solver settings and the posture controls are remembered.
        select: Selects a target by name (the effectors' buttons).
        selected: Returns the selected target's name.
        show_support: Shows or hides the centre of mass in the view.
        message: ``(text, milliseconds)`` on the status bar.
    """

    PARTS = ("effectors", "selected", "joint_panel", "balance_panel", "library_panel", "solver_panel")

    def __init__(self, doc: Document, joints: JointEditor, settings: QtCore.QSettings,
                 select: Callable[[str], None], selected: Callable[[], str | None],
                 show_support: Callable[[bool], None], message: Callable[[str, int], None]):
        super().__init__()
        self.effectors = EffectorsPanel(doc, select)
        self.selected = SelectedTargetPanel(doc, selected)
        self.joint_panel = JointPanel(joints)
        self.solver_panel = solver_panel(doc, settings)
        self.balance_panel = balance_panel(doc, settings, show_support)
        for form in (self.solver_panel, self.balance_panel):
            form.rejected.connect(lambda text: message(text, 5000))
            form.restore()
        self.library_panel = LibraryPanel(doc, lambda text: message(text, 6000))
        panel = QtWidgets.QWidget()
        layout = QtWidgets.QVBoxLayout(panel)
        layout.setContentsMargins(8, 8, 8, 8)
        layout.setSpacing(10)
        for name in self.PARTS:
            layout.addWidget(getattr(self, name))
        layout.addStretch(1)
        self.setWidget(panel)
        self.setWidgetResizable(True)
        self.setFrameShape(QtWidgets.QFrame.NoFrame)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)  # the dock is as wide as the panels need
        self.wheel_guard = guard_wheel(panel)  # the wheel scrolls the panel; it edits only a focused field

    def dock_width(self) -> int:
        """The least dock width [px] that shows every panel whole beside the vertical scroll bar."""
        return max(MIN_WIDTH, self.widget().minimumSizeHint().width() + self.verticalScrollBar().sizeHint().width())
