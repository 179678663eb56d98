"""Long work stepped by the event loop under a progress dialog that can be cancelled (the GUI never blocks long)."""

from __future__ import annotations

from PySide6 import QtCore, QtWidgets
from PySide6.QtCore import Qt

from gsik_studio.model.transfer import BvhExport

#: Frames baked per turn of the event loop (about 7 ms of solving unloaded).
CHUNK_FRAMES = 16


def run_export(parent: QtWidgets.QWidget, job: BvhExport) -> bool:
    """Step ``job`` once per turn of the event loop, showing a cancellable progress dialog while keys are baked.

    Returns True once the file is written, False when the user cancelled (nothing written).

    Raises:
        GsikError: the file could not be written (nothing was).
    """
    if job.ready:
        return job.step(0)
    dialog = QtWidgets.QProgressDialog("Baking the keys for export…", "Cancel", 0, job.n_frames, parent)
    dialog.setWindowTitle("Export BVH")
    dialog.setWindowModality(Qt.WindowModal)
    dialog.setMinimumDuration(0)
    dialog.setAutoClose(False)
    dialog.setAutoReset(False)
    loop, errors = QtCore.QEventLoop(), []

    def cancel() -> None:
        job.cancel()
        loop.quit()

    def turn() -> None:
        if dialog.wasCanceled():  # closed or cancelled without the button's signal
            cancel()
            return
        try:
            written = job.step(CHUNK_FRAMES)
        except Exception as exc:  # re-raised below, outside Qt's slot
            errors.append(exc)
            written = True
        dialog.setValue(job.baked)
        dialog.setLabelText(f"Baking the keys for export: frame {job.baked:,} of {job.n_frames:,}")
        if written:
            loop.quit()

    timer = QtCore.QTimer(dialog)
    timer.timeout.connect(turn)
    dialog.canceled.connect(cancel)
    timer.start(0)
    dialog.show()
    loop.exec()
    timer.stop()
    dialog.close()
    dialog.deleteLater()
    if errors:
        raise errors[0]
    return job.finished
