"""A long key sequence (keys at frames 0 and 9,999) in the real window: Play and Export BVH never block the event
loop for the whole bake; Export shows a progress dialog, can be cancelled (nothing written) and writes a file
gsik reads back."""

from __future__ import annotations

import numpy as np
import pytest

from gsik.io.bvh import read_bvh
from gsik_studio.model import Document
from waiting import wait_for

pytestmark = pytest.mark.gui

LAST_KEY = 9_999


def _write_long_pose(path) -> None:
    """A pose file keyed at frame 0 (standing) and frame 9,999 (the left hand reached out)."""
    doc = Document()
    doc.timeline.add_key(0)
    doc.move_target("left_hand", np.array(doc.targets["left_hand"].position) + [0.0, 0.25, 0.3])
    for _ in range(200):
        doc.step()
        if not doc.needs_solving:
            break
    doc.timeline.add_key(LAST_KEY)
    doc.save(str(path))


def _answer_export_dialogs(window, monkeypatch, path, on_progress):
    """Accept the export options as they are, save to ``path``, and call ``on_progress(dialog)`` each time a
    progress dialog is seen (a poll on the event loop: it runs only when the loop turns)."""
    from PySide6 import QtCore, QtWidgets

    from gsik_studio.widgets.export_options import ExportOptionsDialog

    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: (str(path), "")))

    def poll():
        for w in QtWidgets.QApplication.topLevelWidgets():
            if isinstance(w, ExportOptionsDialog) and w.isVisible():
                w.accept()
            elif isinstance(w, QtWidgets.QProgressDialog) and w.isVisible():
                on_progress(w)

    timer = QtCore.QTimer(window)
    timer.timeout.connect(poll)
    timer.start(20)
    return timer


def _click_cancel(dialog) -> None:
    from PySide6 import QtWidgets

    dialog.findChild(QtWidgets.QPushButton).click()


def test_play_and_export_of_keys_at_frames_0_and_9999_keep_the_event_loop_turning(qtbot, window, monkeypatch,
                                                                                  tmp_path):
    from PySide6 import QtCore
    from PySide6.QtCore import Qt

    pose = tmp_path / "long.yaml"
    _write_long_pose(pose)
    assert window.files.open_path(str(pose), confirm=False)
    tl, bar = window.doc.timeline, window.timeline_bar
    assert sorted(tl.keys) == [0, LAST_KEY] and tl.n_frames == LAST_KEY + 1
    # Play: a single shot posted right after pressing Play fires while the keys are far from baked.
    fired = []
    qtbot.mouseClick(bar.buttons["play"], Qt.LeftButton)
    QtCore.QTimer.singleShot(0, lambda: fired.append((tl.playing, tl.bake.solved)))
    wait_for(qtbot, lambda: bool(fired) and tl.frame >= 3)
    playing, solved = fired[0]
    assert playing and solved < tl.n_frames
    qtbot.mouseClick(bar.buttons["play"], Qt.LeftButton)
    assert not tl.playing and not tl.bake.done
    # Export, cancelled from its progress dialog: nothing written, the bake done so far kept.
    out = tmp_path / "long.bvh"
    seen = []
    poll = _answer_export_dialogs(window, monkeypatch, out, lambda d: (seen.append(d.value()), _click_cancel(d)))
    assert window.act_export_bvh.trigger() is None and seen and not out.exists()
    assert "cancelled" in window.statusBar().currentMessage()
    poll.stop()
    # Export to the end: the progress dialog shows frames baked while the loop turns, then the file is written.
    values = []
    poll = _answer_export_dialogs(window, monkeypatch, out, lambda d: values.append((d.value(), d.maximum())))
    window.act_export_bvh.trigger()
    poll.stop()
    assert out.is_file() and "Exported the keys" in window.statusBar().currentMessage()
    assert values and values[0][1] == LAST_KEY + 1 and min(v for v, _ in values) < LAST_KEY + 1
    assert len({v for v, _ in values}) > 1  # the dialog moved on between turns of the loop
    assert read_bvh(str(out)).n_frames == LAST_KEY + 1
