"""The main window of gsik-studio: the assembly of viewport, panels, actions, file commands and read-outs.

The window owns a :class:`gsik_studio.model.Document`, the :class:`gsik_studio.model.FrameLoop`
that steps it and a :class:`gsik_studio.viewport.Viewport` that draws it; :meth:`MainWindow.show_document`
rebuilds them, the panels and the read-outs around another document (an imported skeleton). Each
panel binds itself to the document's typed events and shows values inside
signal blockers, so that showing a value never writes it back.

Two ``QTimer`` drive the frame loop: ``timer`` steps the solver once per
frame while the targets and the pose disagree (it stops when the solver
reports converged or best reach), ``play_timer`` runs while the document's
timeline plays and shows the frame its clock says (frames are dropped when
drawing is slow; the motion never slows down).
"""

from __future__ import annotations

import os

from PySide6 import QtCore, QtGui, QtWidgets
from PySide6.QtCore import Qt

import gsik
from gsik.anim.motion import Motion
from gsik_studio import animations
from gsik_studio.actions import VIEW_KEYS, make_actions, make_menus, make_toolbar
from gsik_studio.camera import body_extent
from gsik_studio.files import FileActions
from gsik_studio.model import Document, FrameLoop, Playback
from gsik_studio.model.joints import JointEditor
from gsik_studio.qt_compat import protect_none
from gsik_studio.widgets import nice
from gsik_studio.widgets.side_panel import SidePanel
from gsik_studio.widgets.status import StatusReadouts
from gsik_studio.widgets.timeline_bar import TimelineBar

FRAME_INTERVAL_MS = 16  # ~60 Hz


class MainWindow(QtWidgets.QMainWindow):
    """The gsik-studio window.

    Args:
        doc: The document to show (default: the bundled biped, standing).
        settings: Where geometry, recent files and solver settings are
            remembered (default: the user's ``QSettings("gsik", "gsik-studio")``).
        run_timers: False leaves driving :attr:`loop` to the caller (the app benchmark calls
            ``loop.solve_frame()`` itself); the solver timer then never starts.
    """

    def __init__(self, doc: Document | None = None, settings: QtCore.QSettings | None = None,
                 parent: QtWidgets.QWidget | None = None, run_timers: bool = True):
        protect_none()  # PySide6 6.12 on Python 3.11 (see gsik_studio.qt_compat)
        super().__init__(parent)
        import pyvista as pv

        pv.global_theme.multi_samples = 0  # software GL: multisampling costs 3-5x
        self.settings = settings if settings is not None else QtCore.QSettings("gsik", "gsik-studio")
        self.run_timers = run_timers
        self.others: list[MainWindow] = []  # windows of documents imported from this one
        self.plotter = self.status = None
        self.timer = QtCore.QTimer(self)
        self.timer.setInterval(FRAME_INTERVAL_MS)
        self.timer.timeout.connect(self.tick)
        self.play_timer = QtCore.QTimer(self)
        self.play_timer.setInterval(FRAME_INTERVAL_MS)
        self.play_timer.timeout.connect(self._play_tick)
        self.files = FileActions(self, None, self.settings, self.statusBar().showMessage, self.stop_playback,
                                 self._show_opened, self.open_document, self.show_document)
        self.scenario_menu = QtWidgets.QMenu("Scenarios", self)
        self._make_actions()
        self.pose_dock = self._dock("Pose", "pose_panel", Qt.RightDockWidgetArea)
        self.timeline_dock = self._dock("Timeline", "timeline_panel", Qt.BottomDockWidgetArea)
        self.show_document(doc if doc is not None else Document())
        self._restore_geometry()

    def show_document(self, doc: Document) -> None:
        """Show ``doc`` in this window: the scene, panels, timeline and read-outs are built for its skeleton.

        The document shown before is dropped (its file commands ask about unsaved changes first).
        """
        from gsik_studio.balance_view import BalanceView
        from gsik_studio.body_view import BodyView
        from gsik_studio.joint_highlight import JointHighlight
        from gsik_studio.joint_rings import JointRings
        from gsik_studio.pole_gizmos import PoleGizmos
        from gsik_studio.view_widget import ViewWidget
        from gsik_studio.viewport import Viewport

        self.timer.stop()
        self.play_timer.stop()
        if self.plotter is not None:
            self.doc.timeline.pause()
            self.plotter.close()
        self.doc = self.files.doc = doc
        self.loop = FrameLoop(doc)
        self.plotter = ViewWidget(self, auto_update=False, multi_samples=0)
        self.plotter.installEventFilter(self)  # VTK's own key bindings ('e', 'q', 'w', ...) are not wanted
        self.setCentralWidget(self.plotter)
        self.viewport = Viewport(self.plotter, doc)
        self.plotter.snap_press = self.viewport.snap_offset  # a click a few pixels off a target grabs it
        self.body = BodyView(self.viewport)
        self.balance_view = BalanceView(doc, self.body.overlay)
        self.viewport.layers.append(self.balance_view)
        self.poles = PoleGizmos(self.viewport, self.body.overlay)
        self.joints = JointEditor(doc)
        self.rings = JointRings(self.viewport, self.joints)
        self.joint_highlight = JointHighlight(self.viewport, self.joints, self.body.overlay)
        self.body.set_mode("sticks" if self.act_sticks.isChecked() else "mannequin")  # the view's options stay
        self.viewport.extents.append(lambda: body_extent(self.body.mannequin))
        self.viewport.frame_all()  # the whole body in view, head and feet (the skeleton's joints stop short)
        self.loop.set_paused(self.act_pause.isChecked())
        self.set_orbit(str(self.settings.value("view/orbit", "turntable")))
        animations.fill_scenario_menu(self.scenario_menu, doc.skeleton, self.play_scenario)
        self._make_panel()
        self._make_timeline_bar()
        if self.status is not None:
            self.status.remove()
        self.status = StatusReadouts(self.statusBar(), doc, self.loop)
        self._connect()
        for _ in range(2):  # compiles / loads the numba kernels now, not on the first drag
            doc.step()
        self.viewport.select("left_hand" if "left_hand" in doc.targets else None)
        self._show_all()
        self.loop.wake()

    # -- assembly -----------------------------------------------------------------------
    def _make_actions(self) -> None:
        actions = make_actions(self)
        for name, action in actions.items():  # act_open, act_undo, ... (the names of actions.ACTIONS)
            setattr(self, f"act_{name}", action)
        self.act_views = {n: actions[f"view_{n}"] for n, _ in VIEW_KEYS}
        self.act_scenarios = animations.scenarios_action(self.scenario_menu)
        menus = {"recent": self.files.recent_menu, "scenarios": self.scenario_menu, "new_skeleton": self.files.new_menu}
        make_menus(self, actions, menus)
        self.toolbar = make_toolbar(self, actions, menus)

    def _dock(self, title: str, name: str, area: Qt.DockWidgetArea) -> QtWidgets.QDockWidget:
        dock = QtWidgets.QDockWidget(title, self)
        dock.setObjectName(name)
        dock.setFeatures(QtWidgets.QDockWidget.DockWidgetMovable | QtWidgets.QDockWidget.DockWidgetFloatable)
        self.addDockWidget(area, dock)
        return dock

    def _set_dock_widget(self, dock: QtWidgets.QDockWidget, widget: QtWidgets.QWidget) -> None:
        old = dock.widget()
        dock.setWidget(widget)
        if old is not None:
            old.deleteLater()

    def _make_panel(self) -> None:
        message = self.statusBar().showMessage
        side = SidePanel(self.doc, self.joints, self.settings, self.viewport.select, lambda: self.viewport.selected,
                         self.show_support, message)
        for name in SidePanel.PARTS:  # self.effectors, self.balance_panel, ...
            setattr(self, name, getattr(side, name))
        self._set_dock_widget(self.pose_dock, side)
        self.pose_dock.setMinimumWidth(side.dock_width())

    def _make_timeline_bar(self) -> None:
        self.timeline_bar = TimelineBar(self.doc.timeline, lambda text: self.statusBar().showMessage(text, 6000))
        self._set_dock_widget(self.timeline_dock, self.timeline_bar)

    def _connect(self) -> None:
        ev = self.doc.events
        self.doc.timeline.events.state.connect(self._timeline_state)
        self.doc.timeline.events.content.connect(self._frame_timeline)
        ev.pose.connect(self._show_root)
        for signal in (ev.pose, ev.targets, ev.options):
            signal.connect(self._show_targets)
        ev.history.connect(self._show_history)
        ev.file.connect(self._show_title)
        self.loop.events.wake.connect(self._start_timer)
        self.loop.events.frame.connect(self._show_frame)
        self.loop.events.readouts.connect(self.effectors.show_errors)
        self.loop.events.readouts.connect(self.joint_panel.show_angles)
        ev.pose.connect(self.joint_panel.show_angles)
        self.joints.selection_changed.connect(lambda _name: self.viewport.render())
        self.doc.controls.changed.connect(self.loop.wake)
        self.loop.events.message.connect(lambda text: self.statusBar().showMessage(text, 8000))
        self.viewport.selection_changed.connect(self._show_selection)
        self.viewport.drag_finished.connect(lambda _name: self._show_history())

    def _restore_geometry(self) -> None:
        self.resize(1440, 900)
        geometry = self.settings.value("window/geometry")
        if isinstance(geometry, (QtCore.QByteArray, bytes)):
            self.restoreGeometry(geometry)
        state = self.settings.value("window/state")
        if isinstance(state, (QtCore.QByteArray, bytes)):
            self.restoreState(state)

    # -- for tests and scripts ------------------------------------------------------------
    @property
    def rows(self):
        """The effectors panel's rows, ``{effector: EffectorRow}``."""
        return self.effectors.rows

    @property
    def rotate_buttons(self):
        return self.selected.rotate_buttons

    @property
    def status_labels(self) -> dict[str, QtWidgets.QLabel]:
        return self.status.labels

    @property
    def sweeps(self) -> QtWidgets.QSpinBox:
        """The solver panel's sweeps editor."""
        return self.solver_panel.editors["sweeps"]

    @property
    def paused(self) -> bool:
        return self.loop.paused

    @property
    def playback(self) -> Playback | None:
        return self.loop.playback

    def recent_files(self) -> list[str]:
        return self.files.recent_files()

    def open_path(self, path: str, confirm: bool = True) -> bool:
        return self.files.open_path(path, confirm)

    def save_to(self, path: str) -> bool:
        return self.files.save_to(path)

    # -- keep VTK's key bindings out -------------------------------------------------
    def eventFilter(self, obj, event):  # noqa: N802 (Qt's name)
        if obj is self.plotter and event.type() in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
            return True
        return super().eventFilter(obj, event)

    # -- the frame loop's clock -------------------------------------------------------------
    def _start_timer(self) -> None:
        if self.run_timers and not self.timer.isActive():
            self.timer.start()

    def tick(self) -> None:
        """One solver frame (the timer's slot); the timer stops when the pose is settled."""
        if not self.loop.solve_frame():
            self.timer.stop()

    def _show_frame(self) -> None:
        self.viewport.refresh()
        self.viewport.render()

    # -- document -> widgets ----------------------------------------------------------------
    def _show_targets(self) -> None:
        self.viewport.sync_targets()
        if not self.timer.isActive():  # otherwise the next tick redraws
            self._show_frame()

    def _show_root(self) -> None:
        root = self.doc.root
        for a, name in ((self.act_root_left, "left_foot"), (self.act_root_right, "right_foot")):
            a.setEnabled(name in self.doc.skeleton.frame_names)  # an imported skeleton may have no feet
            with QtCore.QSignalBlocker(a):
                a.setChecked(root == name)

    def _show_history(self) -> None:
        h = self.doc.history
        self.act_undo.setEnabled(h.can_undo)
        self.act_redo.setEnabled(h.can_redo)
        self.act_undo.setText(f"&Undo {h.undo_text}" if h.can_undo else "&Undo")
        self.act_redo.setText(f"&Redo {h.redo_text}" if h.can_redo else "&Redo")
        self.act_undo.setIconText("Undo")
        self.act_redo.setIconText("Redo")

    def _show_title(self) -> None:
        self.setWindowTitle(f"{self.doc.title}[*] — {self.doc.skeleton.name} — gsik studio")
        self.setWindowModified(self.doc.dirty)

    def _show_selection(self, name: str | None) -> None:
        self.effectors.show_selection(name)
        self.selected.show_selection(name)
        self.viewport.render()

    def _show_all(self) -> None:
        self._show_root()
        self.status.show_root()
        self._show_history()
        self._show_title()
        self._show_selection(self.viewport.selected)
        self.loop.readouts_now()

    def _show_opened(self) -> None:
        self.viewport.frame_all()
        self.viewport.render()

    # -- commands -----------------------------------------------------------------------------
    def open_document(self, doc: Document) -> MainWindow:
        """Show ``doc`` (an imported skeleton) in a new window like this one; returns it."""
        window = type(self)(doc, settings=self.settings, run_timers=self.run_timers)
        window.resize(self.size())
        window.show()
        self.others.append(window)  # kept alive with this window
        return window

    def set_root(self, name: str) -> None:
        self.doc.set_root(name)
        self.statusBar().showMessage(f"IK root is now the {nice(name)}; the pose stays where it is", 4000)

    def set_paused(self, paused: bool) -> None:
        with QtCore.QSignalBlocker(self.act_pause):
            self.act_pause.setChecked(bool(paused))
        self.act_pause.setText("Resume" if paused else "Pause")
        self.act_pause.setIcon(self.style().standardIcon(
            QtWidgets.QStyle.SP_MediaPlay if paused else QtWidgets.QStyle.SP_MediaPause))
        if paused:
            self.timer.stop()
            self.doc.timeline.pause()  # Pause stops everything that moves
        self.loop.set_paused(paused)

    def set_body(self, mode: str) -> None:
        """Draw the body as ``"mannequin"`` or ``"sticks"``."""
        self.body.set_mode(mode)
        with QtCore.QSignalBlocker(self.act_sticks):
            self.act_sticks.setChecked(mode == "sticks")
        self.viewport.render()

    def show_support(self, on: bool) -> None:
        """Show or hide the centre of mass and the support polygon."""
        self.balance_view.set_visible(on)
        self.viewport.render()

    def set_view(self, name: str) -> None:
        self.viewport.set_view(name)
        self.viewport.render()

    def frame_all(self) -> None:
        self.viewport.frame_all()
        self.viewport.render()

    def frame_selected(self) -> None:
        self.viewport.frame_selected()
        self.viewport.render()

    def set_orbit(self, orbit: str) -> None:
        """``"turntable"`` (z up, the default) or ``"trackball"``; remembered."""
        from gsik_studio import camera

        if orbit not in camera.ORBITS:
            orbit = "turntable"
        camera.set_orbit(self.plotter, orbit)
        with QtCore.QSignalBlocker(self.act_trackball):
            self.act_trackball.setChecked(orbit == "trackball")
        self.settings.setValue("view/orbit", orbit)

    def show_shortcuts(self) -> None:
        """Help → Shortcuts: every key of the action tables and the mouse controls (a non-modal dialog)."""
        from gsik_studio.widgets.shortcuts import ShortcutsDialog

        if getattr(self, "shortcuts_dialog", None) is None:
            self.shortcuts_dialog = ShortcutsDialog(self, self.findChildren(QtGui.QAction))
        self.shortcuts_dialog.show()
        self.shortcuts_dialog.raise_()

    def undo(self) -> None:
        if self.doc.undo():
            self.statusBar().showMessage(f"Undone: {self.doc.history.redo_text}", 3000)

    def redo(self) -> None:
        if self.doc.redo():
            self.statusBar().showMessage(f"Redone: {self.doc.history.undo_text}", 3000)

    # -- playback -----------------------------------------------------------------------------
    def play(self, frames, text: str = "Play", frame_time: float = 1 / 30) -> Playback | None:
        """Put a :class:`gsik.anim.motion.Motion` or a sequence of target dicts on the timeline and play it.

        Returns the playback showing its frames (None, saying why, when the frames cannot be solved).
        """
        self.stop_playback()
        tl = self.doc.timeline
        try:
            if isinstance(frames, Motion):
                tl.load(frames, text)
            else:
                tl.load_target_frames(frames, text, frame_time)
        except gsik.GsikError as exc:
            self.statusBar().showMessage(f"Could not play {text}: {exc}", 8000)
            return None
        tl.play()
        return self.doc.playing

    def play_walk(self, n_steps: int = 4) -> Playback | None:
        """Solve a walk with :func:`gsik.anim.gait.walk` from the standing pose and play it."""
        from gsik.anim import gait

        QtWidgets.QApplication.setOverrideCursor(Qt.WaitCursor)
        try:
            result = gait.walk(self.doc.skeleton, gait.WalkParameters(n_steps=n_steps))
        except gsik.GsikError as exc:
            self.statusBar().showMessage(f"Could not make a walk: {exc}", 8000)
            return None
        finally:
            QtWidgets.QApplication.restoreOverrideCursor()
        self.statusBar().showMessage(f"Walking: {result.motion.n_frames} frames, root swapping at every step", 5000)
        return self.play(result.motion, "Walk")

    def play_scenario(self, name: str) -> Playback | None:
        """Load a built-in scenario: the rest pose with its targets, settled live; an animated one plays first."""
        try:
            sc, first = animations.scenario_start(self.doc.skeleton, name)
        except gsik.GsikError as exc:
            self.statusBar().showMessage(f"Could not load scenario {name}: {exc}", 8000)
            return None
        self.stop_playback()
        self.doc.set_pose(first, f"Scenario {nice(name)}")
        self.viewport.frame_all()
        self.statusBar().showMessage(f"Scenario {nice(name)}: {sc.description}", 8000)
        if sc.n_frames > 1:
            return self.play(animations.scenario_frames(sc), f"Scenario {nice(name)} (animated)", sc.frame_time)
        return None

    def _play_tick(self) -> None:
        self.doc.timeline.tick()  # the document's pose event draws the frame; the end says events.state

    def _timeline_state(self) -> None:
        """Run the play clock exactly while the timeline plays; the camera stays where it is at the end."""
        if self.doc.timeline.playing:
            self.timer.stop()
            self.play_timer.start()
        else:
            self.play_timer.stop()
            self.loop.wake()
        self.loop.readouts_now()

    def _frame_timeline(self) -> None:
        """A new clip: frame every pose it will show, so it plays in view without the camera moving."""
        m = self.doc.timeline.clip
        if m is not None:
            self.viewport.frame_all(extra=m.positions().reshape(-1, 3))
            self.viewport.render()

    def stop_playback(self) -> None:
        """Pause the timeline here (what played stays, as one undo step)."""
        self.doc.timeline.pause()

    # -- pictures -------------------------------------------------------------------------------
    def grab_window(self) -> QtGui.QImage:
        """A picture of the whole window, the 3D view freshly rendered."""
        self.viewport.refresh()
        self.plotter.render()
        QtWidgets.QApplication.processEvents()
        return self.grab().toImage()

    def screenshot_dialog(self) -> None:
        start = os.path.join(self.files.start_dir(), "gsik-studio.png")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save screenshot", start, "PNG images (*.png)")
        if path:
            self.save_screenshot(path)

    def save_screenshot(self, path: str) -> bool:
        ok = self.grab_window().save(path)
        if ok:
            self.statusBar().showMessage(f"Saved screenshot {path}", 5000)
        else:
            QtWidgets.QMessageBox.critical(self, "Could not save screenshot", f"Could not write {path}")
        return ok

    def settle(self, max_frames: int = 400) -> gsik.SolveResult | None:
        """Step the solver until it idles (for scripted pictures), then redraw."""
        for _ in range(max_frames):
            if not self.doc.needs_solving:
                break
            self.doc.step()
        self.viewport.refresh()
        self.loop.readouts_now()
        return self.doc.last_result

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:  # noqa: N802 (Qt's name)
        if not self.files.confirm_discard("quit"):
            event.ignore()
            return
        self.timer.stop()
        self.play_timer.stop()
        self.settings.setValue("window/geometry", self.saveGeometry())
        self.settings.setValue("window/state", self.saveState())
        self.settings.sync()
        self.plotter.close()
        event.accept()
