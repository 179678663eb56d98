"""What the studio shows while it starts: a window at once, saying what it loads, while a thread loads it.

Importing VTK and PyVista takes seconds, and the solver's kernels compile on
first use where the install did not compile them (an editable install, or a
cache that no longer matches): tens of seconds. Both run in a background
thread; the GUI thread keeps the start window painted and its text current.
"""

from __future__ import annotations

import os
import sys
import threading
import time

from PySide6 import QtCore, QtWidgets

#: Set to anything to have the studio print when each start-up stage ended (``benchmarks/bench_window.py`` reads it).
TIMES_VARIABLE = "GSIK_STUDIO_TIMES"


def mark(stage: str) -> None:
    """Say on stderr that start-up ``stage`` just ended, as seconds since the epoch, when :data:`TIMES_VARIABLE`
    is set (``gsik-studio-time <stage> <seconds>``); else nothing."""
    if os.environ.get(TIMES_VARIABLE):
        print(f"gsik-studio-time {stage} {time.time():.4f}", file=sys.stderr, flush=True)

STAGES = {
    "view": "Loading the 3D view (VTK, PyVista)…",
    "solver": "Loading the solver…",
    "kernels": "Preparing the solver's kernels (compiled once on first use, then loaded from the cache)…",
    "window": "Building the window…",
}


class StartWindow(QtWidgets.QWidget):
    """A plain window titled like the studio, with the current stage and the seconds spent."""

    def __init__(self, size: tuple[int, int]):
        super().__init__()
        self.setWindowTitle("gsik studio — starting")
        self.label = QtWidgets.QLabel()
        self.label.setAlignment(QtCore.Qt.AlignCenter)
        self.label.setWordWrap(True)
        font = self.label.font()
        font.setPointSizeF(font.pointSizeF() * 1.3)
        self.label.setFont(font)
        QtWidgets.QVBoxLayout(self).addWidget(self.label)
        self.resize(*size)
        self._start = time.perf_counter()
        self.stage = ""

    def show_stage(self, stage: str) -> None:
        self.stage = stage
        seconds = time.perf_counter() - self._start
        self.label.setText(f"gsik studio\n\n{STAGES.get(stage, stage)}\n{seconds:.0f} s")


def _load(out: dict, stage: list) -> None:
    """The slow part of starting, in order: VTK/PyVista, gsik, a document, two solver steps."""
    try:
        stage.append("view")
        import pyvista as pv
        import pyvistaqt  # noqa: F401 (imported here, off the GUI thread)

        import gsik_studio.body_view  # noqa: F401 (the 3D scene's modules and their VTK widgets)
        import gsik_studio.viewport  # noqa: F401

        pv.global_theme.multi_samples = 0
        mark("view")
        stage.append("solver")
        from gsik_studio.model import Document

        doc = Document()
        mark("solver")
        stage.append("kernels")
        for _ in range(2):
            doc.step()
        mark("kernels")
        out["doc"] = doc
    except BaseException as exc:  # shown by the GUI thread
        out["error"] = exc


def load_document(app: QtWidgets.QApplication, start: StartWindow):
    """Load everything the main window needs in a thread while ``start`` stays painted; returns the
    :class:`gsik_studio.model.Document` (re-raises what the thread raised)."""
    out: dict = {}
    stage: list = []
    thread = threading.Thread(target=_load, args=(out, stage), name="gsik-studio-load", daemon=True)
    thread.start()
    while thread.is_alive():
        start.show_stage(stage[-1] if stage else "view")
        app.processEvents(QtCore.QEventLoop.AllEvents, 50)
        thread.join(0.05)
    if "error" in out:
        raise out["error"]
    start.show_stage("window")
    app.processEvents()
    return out["doc"]
