"""The window's file commands: new, open, save, save as, the unsaved-changes question, recent files."""

from __future__ import annotations

import os
from collections.abc import Callable

from PySide6 import QtCore, QtWidgets

import gsik
from gsik_studio.model import Document, characters, transfer
from gsik_studio.progress import run_export

POSE_FILTER = "gsik poses (*.yaml *.yml);;All files (*)"
BVH_FILTER = "BVH motion (*.bvh);;All files (*)"
SKELETON_FILTER = "Skeletons (*.yaml *.yml *.urdf *.xml *.glb *.gltf);;All files (*)"
CHARACTER_FILTER = "glTF characters (*.glb *.gltf);;All files (*)"
GLTF_FILTER = "glTF binary (*.glb);;glTF (*.gltf)"
MAX_RECENT = 8


class FileActions:
    """File commands with their dialogs and messages, for one document.

    Args:
        parent: The window (dialogs are its children).
        doc: The document.
        settings: Where the recent files are remembered (``recent_files``).
        show_message: ``(text, milliseconds)`` on the status bar.
        stop_playback: Ends a running playback before the document is replaced.
        opened: Called after a file was opened (the window frames the character).
        open_document: Shows a new document in a window of its own (an imported skeleton); returns the window.
        show_document: Shows a new document in this window instead of ``doc`` (an imported skeleton); the
            window sets :attr:`doc` to it.
    """

    def __init__(self, parent: QtWidgets.QWidget, doc: Document | None, settings: QtCore.QSettings,
                 show_message: Callable[[str, int], None], stop_playback: Callable[[], None],
                 opened: Callable[[], None], open_document: Callable[[Document], object] = lambda doc: None,
                 show_document: Callable[[Document], None] = lambda doc: None):
        self.parent, self.doc, self.settings = parent, doc, settings
        self._message, self._stop_playback, self._opened = show_message, stop_playback, opened
        self._open_document, self._show_document = open_document, show_document
        self.recent_menu = QtWidgets.QMenu("Open &Recent", parent)
        self.update_recent_menu()
        self.new_menu = QtWidgets.QMenu("New on s&keleton", parent)  # one entry per bundled skeleton
        for name in gsik.bundled_skeletons():
            a = self.new_menu.addAction(f"{name} ({gsik.load_skeleton(name).n_dofs} DOF)")
            a.setStatusTip(f"A new document on the bundled {name}, standing")
            a.triggered.connect(lambda _c=False, n=name: self.new_on_skeleton(n))

    def confirm_discard(self, action: str) -> bool:
        """Ask before ``action`` throws away unsaved changes; True to go on."""
        if not self.doc.dirty:
            return True
        box = QtWidgets.QMessageBox
        answer = box.question(self.parent, "Unsaved changes", f"The pose “{self.doc.title}” has unsaved changes.\n\n"
                              f"Save them before you {action}?", box.Save | box.Discard | box.Cancel, box.Save)
        if answer == box.Save:
            return self.save()
        return answer == box.Discard

    def start_dir(self) -> str:
        """Where file dialogs open: the current file's folder, else the last recent file's, else home."""
        if self.doc.path:
            return os.path.dirname(self.doc.path)
        recent = self.recent_files()
        return os.path.dirname(recent[0]) if recent else os.path.expanduser("~")

    def new_pose(self) -> None:
        if self.confirm_discard("start a new pose"):
            self._stop_playback()
            self.doc.new()

    def new_on_skeleton(self, name: str) -> bool:
        """A new document on the bundled skeleton ``name`` in this window, standing (asking first about unsaved
        changes); False on a "Cancel"."""
        return self._show_new(transfer.document_for(gsik.load_skeleton(name)), False, "start a new pose") is True

    def open_dialog(self) -> bool:
        if not self.confirm_discard("open another pose"):
            return False
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self.parent, "Open pose", self.start_dir(), POSE_FILTER)
        if not path:
            return False
        return self.open_path(path, confirm=False)

    def open_path(self, path: str, confirm: bool = True) -> bool:
        """Open a pose file on its own skeleton (a new document in this window when it is not this document's);
        on error show it and keep the current document as it was. True on success."""
        if confirm and not self.confirm_discard("open another pose"):
            return False
        self._stop_playback()
        try:
            doc, warnings = transfer.open_pose(path, self.doc)  # a new document is built completely first
        except gsik.GsikError as exc:
            return self._failed(f"Could not open {os.path.basename(path)}: {exc}", "Could not open pose",
                                f"The pose file could not be opened; nothing was changed.\n\n{exc}")
        if doc is not self.doc:
            self._show_document(doc)
        self.add_recent(path)
        if warnings:
            self._message(f"Opened {os.path.basename(path)} with {len(warnings)} warning(s)", 10000)
            QtWidgets.QMessageBox.warning(self.parent, "Pose opened with warnings",
                                          "The pose was opened, with these repairs:\n\n" + "\n".join(warnings))
        else:
            self._message(f"Opened {path}", 5000)
        self._opened()
        return True

    def save(self) -> bool:
        if not self.doc.path:
            return self.save_as()
        return self.save_to(self.doc.path)

    def save_as(self) -> bool:
        start = self.doc.path or os.path.join(self.start_dir(), "pose.yaml")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self.parent, "Save pose", start, POSE_FILTER)
        if not path:
            return False
        if not os.path.splitext(path)[1]:
            path += ".yaml"
        return self.save_to(path)

    def save_to(self, path: str) -> bool:
        """Save atomically; on error show it (an existing file is left untouched). True on success."""
        try:
            self.doc.save(path)
        except gsik.GsikError as exc:
            return self._failed(f"Could not save: {exc}", "Could not save pose",
                                f"The pose was not saved (any existing file is unchanged).\n\n{exc}")
        self.add_recent(path)
        self._message(f"Saved {path}", 5000)
        return True

    # -- import and export ---------------------------------------------------------------
    def _path(self, title: str, filters: str, save_name: str | None = None) -> str:
        if save_name is None:
            return QtWidgets.QFileDialog.getOpenFileName(self.parent, title, self.start_dir(), filters)[0]
        return QtWidgets.QFileDialog.getSaveFileName(self.parent, title, os.path.join(self.start_dir(), save_name),
                                                     filters)[0]

    def import_clip_dialog(self) -> object:
        path = self._path("Import BVH clip", BVH_FILTER)
        return self.import_clip_path(path) if path else False

    def import_clip_path(self, path: str, new_window: bool = False) -> object:
        """Put a BVH clip on the timeline and play it: on this document when it is of this skeleton, else on
        a new document of the clip's skeleton, shown in this window (asking first about unsaved changes; True)
        or with ``new_window`` in a window of its own (returned). False, saying why, on a bad file or a "Cancel"."""
        try:
            imported = transfer.read_clip(path)
        except gsik.GsikError as exc:
            return self._failed(f"Could not import {os.path.basename(path)}: {exc}", "Could not import clip",
                                f"The BVH clip could not be imported; nothing was changed.\n\n{exc}")
        name = os.path.basename(path)
        motion = transfer.motion_on(self.doc.skeleton, imported.motion)
        if motion is None:  # another skeleton: a document of its own, its clip placed on the grid
            doc = transfer.document_for(imported.skeleton)
            doc.timeline.load(transfer.placed_on_grid(imported.motion), name, f"Import {name}")
            shown = self._show_new(doc, new_window, "import a clip of another skeleton")
            if shown is False:
                return False
            doc.timeline.play()
            self._message(f"Imported {name} on its own skeleton ({transfer.describe(imported.skeleton)})",
                          8000)
            return shown
        self._stop_playback()
        self.doc.timeline.load(motion, name, f"Import {name}")
        self.doc.timeline.play()
        self._message(f"Imported {name}: {motion.n_frames} frames on the timeline", 8000)
        return True

    def import_skeleton_dialog(self, new_window: bool = False) -> object:
        if not new_window and not self.confirm_discard("import another skeleton"):
            return False
        path = self._path("Import skeleton", SKELETON_FILTER)
        return self.import_skeleton_path(path, new_window, confirm=False) if path else False

    def import_skeleton_path(self, path: str, new_window: bool = False, confirm: bool = True) -> object:
        """A new document on the skeleton of a YAML or URDF file or a glTF character, shown in this window instead of the current one
        (asking first about unsaved changes unless ``confirm`` is False; True) or with ``new_window`` in a window
        of its own (returned). False, saying why, on a bad file or a "Cancel"."""
        try:
            skeleton = characters.read_skeleton(path)
            doc = transfer.document_for(skeleton)
        except gsik.GsikError as exc:
            return self._failed(f"Could not import {os.path.basename(path)}: {exc}", "Could not import skeleton",
                                f"The skeleton could not be loaded; nothing was changed.\n\n{exc}")
        shown = self._show_new(doc, new_window, "import another skeleton" if confirm else None)
        if shown is not False:
            self._message(f"New document on {transfer.describe(skeleton)}", 8000)
        return shown

    def _show_new(self, doc: Document, new_window: bool, action: str | None) -> object:
        """Show a new document in a window of its own (returned) or in this one (True; False when the question
        about unsaved changes before ``action`` was cancelled; None asks nothing)."""
        if new_window:
            return self._open_document(doc)
        if action is not None and not self.confirm_discard(action):
            return False
        self._stop_playback()
        self._show_document(doc)
        self._opened()
        return True

    def open_character_dialog(self) -> object:
        """File → Open character: a new document in this window on a skinned glTF character."""
        if not self.confirm_discard("open a character"):
            return False
        path = self._path("Open character", CHARACTER_FILTER)
        return self.import_skeleton_path(path, confirm=False) if path else False

    def export_gltf_dialog(self) -> bool:
        path = self._path("Export glTF", GLTF_FILTER, "pose.glb")
        if path and not os.path.splitext(path)[1]:
            path += ".glb"
        return self.export_gltf_path(path) if path else False

    def export_gltf_path(self, path: str) -> bool:
        """Write the clip, else the key sequence, else the pose as glTF; False, saying why, on error."""
        self._stop_playback()
        try:
            what = characters.export_gltf(self.doc, path)
        except gsik.GsikError as exc:
            return self._failed(f"Could not export: {exc}", "Could not export glTF",
                                f"Nothing was written (any existing file is unchanged).\n\n{exc}")
        self._message(f"Exported the {what} to {path}", 6000)
        return True

    def export_bvh_dialog(self) -> bool:
        """Ask the up axis and units (:class:`ExportOptionsDialog`), then the file; export."""
        from gsik_studio.widgets.export_options import ExportOptionsDialog

        dialog = ExportOptionsDialog(self.parent, self.settings)
        if dialog.exec() != QtWidgets.QDialog.Accepted:
            return False
        path = self._path("Export BVH", BVH_FILTER, "motion.bvh")
        if path and not os.path.splitext(path)[1]:
            path += ".bvh"
        return self.export_bvh_path(path, dialog.options()) if path else False

    def export_bvh_path(self, path: str, options: transfer.BvhExportOptions = transfer.BvhExportOptions()) -> bool:
        """Write the clip, else the key sequence, else the pose as BVH; False, saying why, on error."""
        self._stop_playback()
        job = transfer.BvhExport(self.doc, path, options)
        try:
            if not run_export(self.parent, job):  # keys are baked in chunks under a progress dialog
                self._message(f"Export cancelled: nothing was written to {path}", 6000)
                return False
        except gsik.GsikError as exc:
            return self._failed(f"Could not export: {exc}", "Could not export BVH",
                                f"Nothing was written (any existing file is unchanged).\n\n{exc}")
        self._message(f"Exported the {job.what} to {path} ({options.up} up, {options.units})", 6000)
        return True

    def _failed(self, status: str, title: str, text: str) -> bool:
        """Say why a file command failed, on the status bar and in a box; returns False."""
        self._message(status, 10000)
        QtWidgets.QMessageBox.critical(self.parent, title, text)
        return False

    def recent_files(self) -> list[str]:
        value = self.settings.value("recent_files", [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def add_recent(self, path: str) -> None:
        path = os.path.abspath(path)
        files = [p for p in self.recent_files() if p != path]
        files.insert(0, path)
        self.settings.setValue("recent_files", files[:MAX_RECENT])
        self.update_recent_menu()

    def update_recent_menu(self) -> None:
        self.recent_menu.clear()
        files = self.recent_files()
        for i, p in enumerate(files, start=1):
            a = self.recent_menu.addAction(f"&{i} {os.path.basename(p)}")
            a.setToolTip(p)
            a.triggered.connect(lambda _c=False, path=p: self.open_path(path))
        self.recent_menu.setEnabled(bool(files))
