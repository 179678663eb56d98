"""The status bar's read-outs: root, solver status, iterations, residual, solve time, frame rate."""

from __future__ import annotations

from PySide6 import QtGui, QtWidgets

import gsik
from gsik_studio.model import Document, FrameLoop
from gsik_studio.widgets import nice

STATUS_TEXT = {
    gsik.Status.CONVERGED: "converged",
    gsik.Status.STALLED: "best reach",
    gsik.Status.BUDGET_EXHAUSTED: "solving",
}
STATUS_COLOR = {"converged": "#3cb043", "best reach": "#e0a030", "solving": "#4a9cff"}
#: (label key, minimum width [px]) in the order shown.
LABELS = (("root", 130), ("status", 130), ("iterations", 95), ("residual", 150), ("time", 120), ("fps", 80))


def status_text(doc: Document, loop: FrameLoop) -> str:
    """"paused", "playing", the last solver status, or "—" before any step."""
    if loop.paused:
        return "paused"
    if loop.playback is not None:
        return "playing"
    r = doc.last_result
    return STATUS_TEXT[r.status] if r is not None else "—"


class StatusReadouts:
    """Permanent labels in a status bar, refreshed on the frame loop's ``readouts`` and the document's ``pose``."""

    def __init__(self, status_bar: QtWidgets.QStatusBar, doc: Document, loop: FrameLoop):
        self.doc, self.loop, self._bar = doc, loop, status_bar
        mono = QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont)
        self.labels: dict[str, QtWidgets.QLabel] = {}
        for key, width in LABELS:
            lab = QtWidgets.QLabel()
            lab.setFont(mono)
            lab.setMinimumWidth(width)
            status_bar.addPermanentWidget(lab)
            self.labels[key] = lab
        doc.events.pose.connect(self.show_root)
        loop.events.readouts.connect(self.update)

    def remove(self) -> None:
        """Take the labels off the status bar (another document's read-outs replace them)."""
        for lab in self.labels.values():
            self._bar.removeWidget(lab)
            lab.deleteLater()

    def show_root(self) -> None:
        self.labels["root"].setText(f"root: {nice(self.doc.root)}")

    def update(self) -> None:
        doc, L = self.doc, self.labels
        r = doc.last_result
        self.show_root()
        status = status_text(doc, self.loop)
        L["status"].setText(f"● {status}")
        L["status"].setStyleSheet(f"color: {STATUS_COLOR.get(status, 'gray')}; font-weight: bold")
        L["iterations"].setText(f"iter: {r.iterations if r else 0}")
        L["residual"].setText(f"residual: {r.residual:.2e}" if r else "residual: —")
        L["time"].setText(f"solve: {doc.last_solve_time * 1e6:.0f} µs")
        L["fps"].setText(f"{self.loop.fps:.0f} fps" if self.loop.running else "idle")
