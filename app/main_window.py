"""The main window of gsik-studio: toolbar, 3D viewport, side panel, status bar.

The window owns a :class:`gsik_studio.model.Document` and a :class:`gsik_studio.viewport.Viewport`.
Widgets only show the document and forward input to its commands; when the
document changes, widgets are updated inside ``QSignalBlocker`` so that
showing a value never writes it back.

A ``QTimer`` steps the solver once per frame while the targets and the pose
disagree and stops when the solver reports converged or best reach (stalled).
"""

from __future__ import annotations

import collections
import math
import os
import time

import numpy as np
from PySide6 import QtCore, QtGui, QtWidgets
from PySide6.QtCore import Qt

import gsik
from gsik_studio.model import Document, Playback
from gsik_studio.qt_compat import protect_none

FRAME_INTERVAL_MS = 16  # ~60 Hz
READOUT_INTERVAL_S = 0.25  # panel and status texts refresh at most this often
MAX_RECENT = 8
ROTATE_STEP_DEG = 15.0

STATUS_TEXT = {
    gsik.Status.CONVERGED: "converged",
    gsik.Status.STALLED: "best reach",
    gsik.Status.BUDGET_EXHAUSTED: "solving",
}

POSE_FILTER = "gsik poses (*.yaml *.yml);;All files (*)"


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


def _nice(name: str) -> str:
    return name.replace("_", " ")


class EffectorRow:
    """The side panel's widgets for one effector."""

    def __init__(self, name: str):
        self.name = name
        self.button = QtWidgets.QPushButton(_nice(name))
        self.button.setCheckable(True)
        self.button.setToolTip(f"Select the {_nice(name)} target (its rotate box appears in the view)")
        self.button.setStyleSheet("QPushButton { text-align: left; padding: 2px 6px; }"
                                  "QPushButton:checked { background: #3d6db3; color: white; font-weight: bold; }")
        self.enabled = QtWidgets.QCheckBox()
        self.enabled.setToolTip("Enabled: the solver pulls this effector to its target")
        self.weight = QtWidgets.QDoubleSpinBox()
        self.weight.setRange(0.0, 100.0)
        self.weight.setDecimals(2)
        self.weight.setSingleStep(0.1)
        self.weight.setToolTip("Weight: relative importance in the least-squares solve")
        self.weight.setKeyboardTracking(False)
        self.weight.setMaximumWidth(74)
        self.position_only = QtWidgets.QCheckBox()
        self.position_only.setToolTip("Position only: ignore the target's orientation")
        self.position_error = QtWidgets.QLabel("–")
        self.orientation_error = QtWidgets.QLabel("–")
        for label in (self.position_error, self.orientation_error):
            label.setAlignment(Qt.AlignRight | Qt.AlignVCenter)
            label.setMinimumWidth(46)
            label.setFont(QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont))

    def widgets(self):
        return (self.button, self.enabled, self.weight, self.position_only, self.position_error,
                self.orientation_error)


class MainWindow(QtWidgets.QMainWindow):
    """The gsik-studio window.

    Args:
        doc: The document to show (default: the bundled biped, standing).
        settings: Where geometry, recent files and solver settings are
            remembered (default: the user's ``QSettings("gsik", "gsik-studio")``).
    """

    def __init__(self, doc: Document | None = None, settings: QtCore.QSettings | None = None,
                 parent: QtWidgets.QWidget | None = None):
        protect_none()  # PySide6 6.12 on Python 3.11 (see gsik_studio.qt_compat)
        super().__init__(parent)
        import pyvista as pv
        from pyvistaqt import QtInteractor

        from gsik_studio.viewport import Viewport

        pv.global_theme.multi_samples = 0  # software GL: multisampling costs 3-5x
        self.settings = settings if settings is not None else QtCore.QSettings("gsik", "gsik-studio")
        self.doc = doc if doc is not None else Document()
        self._restore_solver_settings()
        self.playback: Playback | None = None
        self.paused = False
        self._frame_times: collections.deque[float] = collections.deque(maxlen=120)
        self._last_readout = 0.0
        self.app_time = 0.0  # [s] the window's own work in the last frame (solver + scene update), no render

        self.plotter = QtInteractor(self, auto_update=False, multi_samples=0)
        self.plotter.installEventFilter(self)  # VTK's own key bindings ('e', 'q', 'w', ...) are not wanted
        self.setCentralWidget(self.plotter)
        self.viewport = Viewport(self.plotter, self.doc)

        self._make_actions()
        self._make_menus()
        self._make_toolbar()
        self._make_panel()
        self._make_status_bar()

        self.timer = QtCore.QTimer(self)
        self.timer.setInterval(FRAME_INTERVAL_MS)
        self.timer.timeout.connect(self.tick)
        self.play_timer = QtCore.QTimer(self)
        self.play_timer.timeout.connect(self._play_tick)

        self.doc.changed.connect(self._on_doc_changed)
        self.viewport.selection_changed.connect(self._on_selection_changed)
        self.viewport.drag_finished.connect(lambda _name: self._update_history_actions())

        self.resize(1440, 900)
        geometry = self.settings.value("window/geometry")
        if isinstance(geometry, (QtCore.QByteArray, bytes)):
            self.restoreGeometry(geometry)
        state = self.settings.value("window/state")
        if isinstance(state, (QtCore.QByteArray, bytes)):
            self.restoreState(state)

        for _ in range(2):  # compiles / loads the numba kernels now, not on the first drag
            self.doc.step()
        self.viewport.select("left_hand" if "left_hand" in self.doc.targets else None)
        self._sync_all()
        self._ensure_running()

    # -- construction -----------------------------------------------------------
    def _action(self, text: str, slot, shortcut=None, tip: str = "", icon=None, checkable=False) -> QtGui.QAction:
        a = QtGui.QAction(text, self)
        if shortcut is not None:
            if isinstance(shortcut, (list, tuple)):
                a.setShortcuts([QtGui.QKeySequence(s) for s in shortcut])
            else:
                a.setShortcut(QtGui.QKeySequence(shortcut))
            a.setShortcutContext(Qt.WindowShortcut)
        if tip:
            keys = ", ".join(s.toString(QtGui.QKeySequence.NativeText) for s in a.shortcuts())
            a.setToolTip(f"{tip} ({keys})" if keys else tip)
            a.setStatusTip(tip)
        if icon is not None:
            a.setIcon(self.style().standardIcon(icon))
        a.setCheckable(checkable)
        if checkable:
            a.toggled.connect(slot)
        else:
            a.triggered.connect(lambda _checked=False: slot())
        return a

    def _make_actions(self) -> None:
        S = QtWidgets.QStyle
        K = QtGui.QKeySequence
        self.act_new = self._action("&New", self.new_pose, K.New, "Start over from the standing pose")
        self.act_open = self._action("&Open…", self.open_dialog, K.Open, "Open a pose file",
                                     S.SP_DialogOpenButton)
        self.act_save = self._action("&Save", self.save, K.Save, "Save the pose", S.SP_DialogSaveButton)
        self.act_save_as = self._action("Save &As…", self.save_as, "Ctrl+Shift+S", "Save the pose to a new file")
        self.act_screenshot = self._action("Screens&hot…", self.screenshot_dialog, None,
                                           "Save a picture of the window", S.SP_DesktopIcon)
        self.act_quit = self._action("&Quit", self.close, K.Quit, "Quit gsik-studio")
        self.act_undo = self._action("&Undo", self.undo, K.Undo, "Undo the last edit", S.SP_ArrowBack)
        self.act_redo = self._action("&Redo", self.redo, ["Ctrl+Shift+Z", "Ctrl+Y"], "Redo", S.SP_ArrowForward)
        self.act_reset = self._action("Reset", self.doc.reset, None, "Back to the standing pose",
                                      S.SP_BrowserReload)
        self.act_random = self._action("Random", lambda: self.doc.random_pose(), None, "A random pose")
        self.act_mirror_lr = self._action("Mirror L→R", lambda: self.doc.mirror("left"), None,
                                          "Copy the left side's pose, mirrored, onto the right side")
        self.act_mirror_rl = self._action("Mirror R→L", lambda: self.doc.mirror("right"), None,
                                          "Copy the right side's pose, mirrored, onto the left side")
        self.act_root_left = QtGui.QAction("Root: left foot", self, checkable=True)
        self.act_root_left.setToolTip("Pin the left foot (the IK root); the pose does not move")
        self.act_root_right = QtGui.QAction("Root: right foot", self, checkable=True)
        self.act_root_right.setToolTip("Pin the right foot (the IK root); the pose does not move")
        self.root_group = QtGui.QActionGroup(self)
        self.root_group.setExclusive(True)
        for a, name in ((self.act_root_left, "left_foot"), (self.act_root_right, "right_foot")):
            self.root_group.addAction(a)
            a.triggered.connect(lambda _checked=False, n=name: self.set_root(n))
        self.act_pause = self._action("Pause", self.set_paused, "Space", "Pause or resume solving",
                                      S.SP_MediaPause, checkable=True)
        self.act_frame = self._action("Frame all", self.viewport.frame_all, "F", "Fit the character in the view")
        self.act_views = {}
        for name, key in (("front", "1"), ("side", "3"), ("top", "7"), ("perspective", "5")):
            self.act_views[name] = self._action(name.capitalize(), lambda n=name: self.set_view(n), key,
                                                f"{name.capitalize()} view")
        # Animations (issue 4): offered when gsik has them.
        self.act_walk = None
        self.act_scenarios = None
        try:
            from gsik.anim import gait
        except ImportError:
            gait = None
        if gait is not None and hasattr(gait, "walk") and hasattr(gait, "WalkParameters"):
            self.act_walk = self._action("Walk", self.play_walk, None,
                                         "Play a walk: the IK root swaps between the feet at every step",
                                         S.SP_MediaSeekForward)
        try:
            from gsik.anim import scenarios
        except ImportError:
            scenarios = None
        if scenarios is not None and all(hasattr(scenarios, n) for n in ("SCENARIO_NAMES", "builtin_scenario",
                                                                          "scenario_pose")):
            self.scenario_menu = QtWidgets.QMenu("Scenarios", self)
            self.scenario_menu.setToolTipsVisible(True)
            for name in scenarios.SCENARIO_NAMES:
                a = self.scenario_menu.addAction(_nice(name))
                try:
                    a.setToolTip(scenarios.builtin_scenario(self.doc.skeleton, name).description)
                except gsik.GsikError as exc:  # a skeleton the built-in scenarios do not fit
                    a.setEnabled(False)
                    a.setToolTip(str(exc))
                a.triggered.connect(lambda _c=False, n=name: self.play_scenario(n))
            self.act_scenarios = self.scenario_menu.menuAction()
            self.act_scenarios.setIcon(self.style().standardIcon(S.SP_FileDialogDetailedView))
            self.act_scenarios.setToolTip("Load a test scenario (targets from the paper's poses) and watch it solve")

    def _make_menus(self) -> None:
        mb = self.menuBar()
        m = mb.addMenu("&File")
        for a in (self.act_new, self.act_open):
            m.addAction(a)
        self.recent_menu = m.addMenu("Open &Recent")
        m.addSeparator()
        for a in (self.act_save, self.act_save_as):
            m.addAction(a)
        m.addSeparator()
        m.addAction(self.act_screenshot)
        m.addSeparator()
        m.addAction(self.act_quit)
        m = mb.addMenu("&Edit")
        m.addAction(self.act_undo)
        m.addAction(self.act_redo)
        m = mb.addMenu("&Pose")
        for a in (self.act_root_left, self.act_root_right):
            m.addAction(a)
        m.addSeparator()
        for a in (self.act_reset, self.act_random, self.act_mirror_lr, self.act_mirror_rl):
            m.addAction(a)
        for a in (self.act_walk, self.act_scenarios):
            if a is not None:
                m.addAction(a)
        self.pose_menu = m
        m = mb.addMenu("&View")
        m.addAction(self.act_frame)
        for a in self.act_views.values():
            m.addAction(a)
        m = mb.addMenu("&Solver")
        m.addAction(self.act_pause)
        self._update_recent_menu()

    def _make_toolbar(self) -> None:
        tb = self.addToolBar("Main")
        tb.setObjectName("main_toolbar")
        tb.setMovable(False)
        tb.setToolButtonStyle(Qt.ToolButtonTextBesideIcon)
        tb.setIconSize(QtCore.QSize(18, 18))
        for a in (self.act_open, self.act_save, None, self.act_undo, self.act_redo, None, self.act_root_left,
                  self.act_root_right, None, self.act_reset, self.act_random, self.act_mirror_lr, self.act_mirror_rl,
                  None, self.act_walk or False, self.act_scenarios or False, None, self.act_pause,
                  self.act_screenshot, None,
                  self.act_frame):
            if a is None:
                tb.addSeparator()
            elif a is not False:
                tb.addAction(a)
        if self.act_scenarios is not None:
            button = tb.widgetForAction(self.act_scenarios)
            if isinstance(button, QtWidgets.QToolButton):
                button.setPopupMode(QtWidgets.QToolButton.InstantPopup)
        self.toolbar = tb

    def _make_panel(self) -> None:
        panel = QtWidgets.QWidget()
        layout = QtWidgets.QVBoxLayout(panel)
        layout.setContentsMargins(8, 8, 8, 8)
        layout.setSpacing(10)

        # Effectors.
        box = QtWidgets.QGroupBox("Effectors")
        grid = QtWidgets.QGridLayout(box)
        grid.setHorizontalSpacing(8)
        grid.setVerticalSpacing(4)
        for col, (text, tip) in enumerate((("", ""), ("on", "Enabled"), ("weight", "Weight"),
                                           ("pos only", "Position only"), ("pos err", "Position error [mm]"),
                                           ("rot err", "Orientation error [deg]"))):
            head = QtWidgets.QLabel(f"<small><b>{text}</b></small>")
            head.setToolTip(tip)
            grid.addWidget(head, 0, col, Qt.AlignCenter if col else Qt.AlignLeft)
        self.rows: dict[str, EffectorRow] = {}
        self.select_group = QtWidgets.QButtonGroup(self)
        self.select_group.setExclusive(True)
        for r, name in enumerate(self.doc.skeleton.effector_sites, start=1):
            row = EffectorRow(name)
            self.rows[name] = row
            self.select_group.addButton(row.button)
            for col, w in enumerate(row.widgets()):
                grid.addWidget(w, r, col, Qt.AlignCenter if col in (1, 3) else Qt.Alignment())
            row.button.clicked.connect(lambda _c=False, n=name: self.viewport.select(n))
            row.enabled.toggled.connect(lambda v, n=name: self._set_option(n, enabled=v))
            row.weight.valueChanged.connect(lambda v, n=name: self._set_option(n, weight=v))
            row.position_only.toggled.connect(lambda v, n=name: self._set_option(n, position_only=v))
        units = QtWidgets.QLabel("<small>errors: position [mm], orientation [deg]</small>")
        units.setStyleSheet("color: gray")
        grid.addWidget(units, len(self.rows) + 1, 0, 1, 6)
        layout.addWidget(box)

        # Selected target: rotate buttons.
        box = QtWidgets.QGroupBox("Selected target")
        v = QtWidgets.QVBoxLayout(box)
        self.selected_label = QtWidgets.QLabel("none")
        v.addWidget(self.selected_label)
        rot = QtWidgets.QGridLayout()
        self.rotate_buttons = {}
        colors = {"x": "#e0463c", "y": "#3cb043", "z": "#4a7cff"}
        for r, axis in enumerate("xyz"):
            lab = QtWidgets.QLabel(f"<b style='color:{colors[axis]}'>{axis}</b>")
            rot.addWidget(lab, r, 0)
            for c, sign in enumerate((-1, 1)):
                b = QtWidgets.QPushButton(f"{'−' if sign < 0 else '+'}{ROTATE_STEP_DEG:.0f}°")
                b.setToolTip(f"Turn the selected target {'−' if sign < 0 else '+'}{ROTATE_STEP_DEG:.0f}° "
                             f"about the world {axis} axis")
                b.clicked.connect(lambda _c=False, a=axis, s=sign: self.rotate_selected(a, s * ROTATE_STEP_DEG))
                rot.addWidget(b, r, c + 1)
                self.rotate_buttons[(axis, sign)] = b
        v.addLayout(rot)
        self.snap_button = QtWidgets.QPushButton("Snap target to effector")
        self.snap_button.clicked.connect(self._snap_selected)
        v.addWidget(self.snap_button)
        hint = QtWidgets.QLabel("<small>Drag a red sphere to move a target; drag a face of the box around "
                                "the selected target to turn it.</small>")
        hint.setWordWrap(True)
        hint.setStyleSheet("color: gray")
        v.addWidget(hint)
        layout.addWidget(box)

        # Solver settings.
        box = QtWidgets.QGroupBox("Solver")
        form = QtWidgets.QFormLayout(box)
        self.sweeps = QtWidgets.QSpinBox()
        self.sweeps.setRange(1, 500)
        self.sweeps.setToolTip("Gauss-Seidel sweeps per frame")
        self.damping = QtWidgets.QDoubleSpinBox()
        self.damping.setDecimals(6)
        self.damping.setRange(1e-6, 10.0)
        self.damping.setSingleStep(0.001)
        self.damping.setToolTip("Damping δ added to the diagonal of JᵀWJ")
        self.pos_tol = QtWidgets.QDoubleSpinBox()
        self.pos_tol.setDecimals(3)
        self.pos_tol.setRange(0.001, 100.0)
        self.pos_tol.setSuffix(" mm")
        self.pos_tol.setToolTip("Converged when every position error is below this")
        self.ori_tol = QtWidgets.QDoubleSpinBox()
        self.ori_tol.setDecimals(3)
        self.ori_tol.setRange(0.001, 90.0)
        self.ori_tol.setSuffix(" °")
        self.ori_tol.setToolTip("Converged when every orientation error is below this")
        self.max_step = QtWidgets.QDoubleSpinBox()
        self.max_step.setDecimals(3)
        self.max_step.setRange(0.0, 3.2)
        self.max_step.setSuffix(" rad")
        self.max_step.setToolTip("Largest change of one angle per frame (0: none)")
        for w in (self.sweeps, self.damping, self.pos_tol, self.ori_tol, self.max_step):
            w.setKeyboardTracking(False)
        form.addRow("Sweeps / frame", self.sweeps)
        form.addRow("Damping δ", self.damping)
        form.addRow("Position tolerance", self.pos_tol)
        form.addRow("Orientation tolerance", self.ori_tol)
        form.addRow("Max step", self.max_step)
        self.sweeps.valueChanged.connect(lambda v: self._configure(sweeps=int(v)))
        self.damping.valueChanged.connect(lambda v: self._configure(damping=float(v)))
        self.pos_tol.valueChanged.connect(lambda v: self._configure(position_tolerance=v / 1000.0))
        self.ori_tol.valueChanged.connect(lambda v: self._configure(orientation_tolerance=math.radians(v)))
        self.max_step.valueChanged.connect(lambda v: self._configure(max_step=float(v)))
        layout.addWidget(box)

        self.animation_box = QtWidgets.QGroupBox("Animation")
        self.animation_layout = QtWidgets.QVBoxLayout(self.animation_box)
        self.animation_box.setVisible(False)
        layout.addWidget(self.animation_box)
        layout.addStretch(1)

        scroll = QtWidgets.QScrollArea()
        scroll.setWidget(panel)
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QtWidgets.QFrame.NoFrame)
        dock = QtWidgets.QDockWidget("Pose", self)
        dock.setObjectName("pose_panel")
        dock.setWidget(scroll)
        dock.setFeatures(QtWidgets.QDockWidget.DockWidgetMovable | QtWidgets.QDockWidget.DockWidgetFloatable)
        dock.setMinimumWidth(440)
        self.addDockWidget(Qt.RightDockWidgetArea, dock)
        self.panel = dock

    def _make_status_bar(self) -> None:
        sb = self.statusBar()
        mono = QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont)
        self.status_labels = {}
        for key, width in (("root", 130), ("status", 130), ("iterations", 95), ("residual", 150),
                           ("time", 120), ("fps", 80)):
            lab = QtWidgets.QLabel()
            lab.setFont(mono)
            lab.setMinimumWidth(width)
            sb.addPermanentWidget(lab)
            self.status_labels[key] = lab

    # -- keep VTK's key bindings out -------------------------------------------------
    def eventFilter(self, obj, event):  # noqa: N802 (Qt's name)
        if obj is self.plotter and event.type() in (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease):
            return True
        return super().eventFilter(obj, event)

    # -- the frame loop -----------------------------------------------------------------
    def _ensure_running(self) -> None:
        if self.playback is None and not self.paused and self.doc.needs_solving and not self.timer.isActive():
            self.timer.start()

    def tick(self) -> None:
        """One frame: step the solver, update the scene in place, render once."""
        if self.paused or self.playback is not None or not self.doc.needs_solving:
            self.timer.stop()
            self._update_readouts(force=True)
            return
        t0 = time.perf_counter()
        self.doc.step()
        self.viewport.refresh()
        self.app_time = time.perf_counter() - t0
        self._update_readouts()
        self.viewport.render()
        self._frame_times.append(time.perf_counter())
        if not self.doc.needs_solving:
            self.timer.stop()
            self._update_readouts(force=True)

    @property
    def fps(self) -> float:
        """Frames drawn per second over the last second."""
        now = time.perf_counter()
        recent = [t for t in self._frame_times if now - t <= 1.0]
        if len(recent) < 2:
            return 0.0
        return (len(recent) - 1) / max(recent[-1] - recent[0], 1e-9)

    def _update_readouts(self, force: bool = False) -> None:
        now = time.perf_counter()
        if not force and now - self._last_readout < READOUT_INTERVAL_S:
            return
        self._last_readout = now
        doc = self.doc
        r = doc.last_result
        L = self.status_labels
        L["root"].setText(f"root: {_nice(doc.root)}")
        if self.paused:
            status = "paused"
        elif self.playback is not None:
            status = "playing"
        else:
            status = STATUS_TEXT[r.status] if r is not None else "—"
        L["status"].setText(f"● {status}")
        color = {"converged": "#3cb043", "best reach": "#e0a030", "solving": "#4a9cff"}.get(status, "gray")
        L["status"].setStyleSheet(f"color: {color}; font-weight: bold")
        L["iterations"].setText(f"iter: {r.iterations if r else 0}")
        L["residual"].setText(f"residual: {r.residual:.2e}" if r else "residual: —")
        L["time"].setText(f"solve: {doc.last_solve_time * 1e6:.0f} µs")
        L["fps"].setText(f"{self.fps:.0f} fps" if self.timer.isActive() or self.play_timer.isActive() else "idle")
        errors = r.errors() if r is not None else {}
        for name, row in self.rows.items():
            if name in errors and doc.targets.get(name) is not None and doc.targets[name].enabled:
                p, o = errors[name]
                row.position_error.setText(f"{p * 1000:.1f}")
                uses_o = not doc.targets[name].position_only
                row.orientation_error.setText(f"{math.degrees(o):.1f}" if uses_o else "–")
            else:
                row.position_error.setText("–")
                row.orientation_error.setText("–")

    # -- document -> widgets ----------------------------------------------------------------
    def _on_doc_changed(self, kind: str) -> None:
        if kind in ("pose", "targets", "options"):
            self.viewport.sync_targets()
            if kind != "targets":
                self._sync_rows()
                self._sync_root()
            self._ensure_running()
            if not self.timer.isActive():  # otherwise the next tick redraws
                self.viewport.refresh()
                self.viewport.render()
        elif kind == "settings":
            self._sync_settings()
            self._ensure_running()
        elif kind == "history":
            self._update_history_actions()
        elif kind == "file":
            self._update_title()

    def _sync_all(self) -> None:
        self._sync_rows()
        self._sync_root()
        self._sync_settings()
        self._update_history_actions()
        self._update_title()
        self._on_selection_changed(self.viewport.selected)
        self._update_readouts(force=True)

    def _sync_rows(self) -> None:
        targets = self.doc.targets
        for name, row in self.rows.items():
            t = targets.get(name)
            is_root = name == self.doc.root
            blockers = [QtCore.QSignalBlocker(w) for w in (row.enabled, row.weight, row.position_only)]
            row.enabled.setEnabled(t is not None)
            row.weight.setEnabled(t is not None and t.enabled)
            row.position_only.setEnabled(t is not None and t.enabled)
            row.button.setEnabled(t is not None)
            row.button.setText(f"{_nice(name)}  (root)" if is_root else _nice(name))
            if t is not None:
                row.enabled.setChecked(t.enabled)
                row.weight.setValue(t.weight)
                row.position_only.setChecked(t.position_only)
            del blockers

    def _sync_root(self) -> None:
        root = self.doc.root
        for a, name in ((self.act_root_left, "left_foot"), (self.act_root_right, "right_foot")):
            with QtCore.QSignalBlocker(a):
                a.setChecked(root == name)
        self.status_labels["root"].setText(f"root: {_nice(root)}")

    def _sync_settings(self) -> None:
        s = self.doc.settings
        for w, v in ((self.sweeps, s.sweeps), (self.damping, s.damping), (self.pos_tol, s.position_tolerance * 1000),
                     (self.ori_tol, math.degrees(s.orientation_tolerance)), (self.max_step, s.max_step)):
            with QtCore.QSignalBlocker(w):
                w.setValue(v)

    def _update_history_actions(self) -> None:
        h = self.doc.history
        state = (h.can_undo, h.can_redo, h.undo_text, h.redo_text)
        if state == getattr(self, "_history_state", None):
            return
        self._history_state = state
        self.act_undo.setEnabled(h.can_undo)
        self.act_redo.setEnabled(h.can_redo)
        self.act_undo.setText(f"&Undo {h.undo_text}" if h.can_undo else "&Undo")
        self.act_redo.setText(f"&Redo {h.redo_text}" if h.can_redo else "&Redo")
        self.act_undo.setIconText("Undo")
        self.act_redo.setIconText("Redo")

    def _update_title(self) -> None:
        state = (self.doc.title, self.doc.dirty)
        if state == getattr(self, "_title_state", None):
            return
        self._title_state = state
        self.setWindowTitle(f"{self.doc.title}[*] — gsik studio")
        self.setWindowModified(self.doc.dirty)

    def _on_selection_changed(self, name: str | None) -> None:
        for n, row in self.rows.items():
            with QtCore.QSignalBlocker(row.button):
                row.button.setChecked(n == name)
        has = name is not None and name in self.doc.targets
        self.selected_label.setText(f"<b>{_nice(name)}</b>" if has else "none (click a target)")
        for b in self.rotate_buttons.values():
            b.setEnabled(has)
        self.snap_button.setEnabled(has)
        self.viewport.render()

    # -- widgets -> document ----------------------------------------------------------------
    def _set_option(self, name: str, **option) -> None:
        if name in self.doc.targets:
            self.doc.set_target_options(name, **option)

    def _configure(self, **changes) -> None:
        try:
            self.doc.configure(**changes)
        except gsik.GsikError as exc:
            self.statusBar().showMessage(str(exc), 5000)
            self._sync_settings()
            return
        s = self.doc.settings
        for k, v in changes.items():
            self.settings.setValue(f"solver/{k}", getattr(s, k))

    def _restore_solver_settings(self) -> None:
        s = self.doc.settings
        changes = {}
        for name in ("sweeps", "damping", "position_tolerance", "orientation_tolerance", "max_step"):
            v = self.settings.value(f"solver/{name}")
            if v is None:
                continue
            try:
                changes[name] = type(getattr(s, name))(float(v))
            except (TypeError, ValueError):
                continue
        try:
            if changes:
                self.doc.configure(**changes)
        except gsik.GsikError:
            pass

    def rotate_selected(self, axis: str, degrees: float) -> None:
        name = self.viewport.selected
        if name is not None and name in self.doc.targets:
            self.doc.rotate_target(name, axis, math.radians(degrees))

    def _snap_selected(self) -> None:
        name = self.viewport.selected
        if name is not None and name in self.doc.targets:
            self.doc.snap_target(name)

    def set_root(self, name: str) -> None:
        self.doc.set_root(name)
        self.statusBar().showMessage(f"IK root is now the {_nice(name)}; the pose stays where it is", 4000)

    def set_paused(self, paused: bool) -> None:
        self.paused = bool(paused)
        with QtCore.QSignalBlocker(self.act_pause):
            self.act_pause.setChecked(self.paused)
        self.act_pause.setText("Resume" if self.paused else "Pause")
        self.act_pause.setIcon(self.style().standardIcon(
            QtWidgets.QStyle.SP_MediaPlay if self.paused else QtWidgets.QStyle.SP_MediaPause))
        if self.paused:
            self.timer.stop()
        else:
            self._ensure_running()
        self._update_readouts(force=True)

    def set_view(self, name: str) -> None:
        self.viewport.set_view(name)
        self.viewport.render()

    def undo(self) -> None:
        if self.doc.undo():
            self.statusBar().showMessage(f"Undone: {self.doc.history.redo_text}", 3000)

    def redo(self) -> None:
        if self.doc.redo():
            self.statusBar().showMessage(f"Redone: {self.doc.history.undo_text}", 3000)

    # -- playback -----------------------------------------------------------------------------
    def play(self, frames, text: str = "Play", frame_time: float = 1 / 30) -> Playback:
        """Play a :class:`gsik.anim.motion.Motion` or a sequence of target dicts in the view."""
        self.stop_playback()
        self.playback = self.doc.playback(frames, text, frame_time)
        self.timer.stop()
        self.play_timer.setInterval(max(1, int(round(self.playback.frame_time * 1000))))
        self.play_timer.start()
        self._update_readouts(force=True)
        return self.playback

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
        """Load a built-in scenario of :mod:`gsik.anim.scenarios`: the rest pose with the scenario's targets.

        The solver then settles it live, as it does after a drag; an animated
        scenario (the wave) plays its target frames first.
        """
        from gsik.anim import scenarios

        try:
            sc = scenarios.builtin_scenario(self.doc.skeleton, name)
            first = scenarios.scenario_pose(sc)
        except gsik.GsikError as exc:
            self.statusBar().showMessage(f"Could not load scenario {name}: {exc}", 8000)
            return None
        self.stop_playback()
        if sc.n_frames > 1:  # start at the first frame's targets, then play the rest
            t0 = sc.targets_at(0)
            first = first.replace(targets={n: t0.get(n, t) for n, t in first.targets.items()})
        self.doc.set_pose(first, f"Scenario {_nice(name)}")
        self.viewport.frame_all()
        self.statusBar().showMessage(f"Scenario {_nice(name)}: {sc.description}", 8000)
        if sc.n_frames > 1:
            return self.play([sc.targets_at(i) for i in range(1, sc.n_frames)], f"Scenario {_nice(name)} (animated)",
                             sc.frame_time)
        return None

    def _play_tick(self) -> None:
        pb = self.playback
        try:
            more = pb is not None and not pb.finished and pb.advance()
        except gsik.GsikError as exc:
            self.statusBar().showMessage(f"Playback stopped: {exc}", 8000)
            more = False
        if not more:
            self.stop_playback()
            return
        self._frame_times.append(time.perf_counter())
        self._update_readouts()

    def stop_playback(self) -> None:
        pb, self.playback = self.playback, None
        self.play_timer.stop()
        if pb is not None:
            pb.stop()
            self.viewport.frame_all()
            self.viewport.render()
        self._ensure_running()

    # -- files --------------------------------------------------------------------------------------
    def _confirm_discard(self, action: str) -> bool:
        """Ask before ``action`` throws away unsaved changes; True to go on."""
        if not self.doc.dirty:
            return True
        answer = QtWidgets.QMessageBox.question(
            self, "Unsaved changes", f"The pose “{self.doc.title}” has unsaved changes.\n\n"
            f"Save them before you {action}?",
            QtWidgets.QMessageBox.Save | QtWidgets.QMessageBox.Discard | QtWidgets.QMessageBox.Cancel,
            QtWidgets.QMessageBox.Save)
        if answer == QtWidgets.QMessageBox.Save:
            return self.save()
        return answer == QtWidgets.QMessageBox.Discard

    def _start_dir(self) -> str:
        if self.doc.path:
            return os.path.dirname(self.doc.path)
        recent = self.recent_files()
        return os.path.dirname(recent[0]) if recent else os.path.expanduser("~")

    def new_pose(self) -> None:
        if self._confirm_discard("start a new pose"):
            self.stop_playback()
            self.doc.new()

    def open_dialog(self) -> bool:
        if not self._confirm_discard("open another pose"):
            return False
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Open pose", self._start_dir(), POSE_FILTER)
        if not path:
            return False
        return self.open_path(path, confirm=False)

    def open_path(self, path: str, confirm: bool = True) -> bool:
        """Open a pose file; on error show it and keep the current pose. True on success."""
        if confirm and not self._confirm_discard("open another pose"):
            return False
        self.stop_playback()
        try:
            warnings = self.doc.open(path)
        except gsik.GsikError as exc:
            self.statusBar().showMessage(f"Could not open {os.path.basename(path)}: {exc}", 10000)
            QtWidgets.QMessageBox.critical(self, "Could not open pose",
                                           f"The pose file could not be opened; nothing was changed.\n\n{exc}")
            return False
        self._add_recent(path)
        if warnings:
            text = "\n".join(warnings)
            self.statusBar().showMessage(f"Opened {os.path.basename(path)} with {len(warnings)} warning(s)", 10000)
            QtWidgets.QMessageBox.warning(self, "Pose opened with warnings",
                                          f"The pose was opened, with these repairs:\n\n{text}")
        else:
            self.statusBar().showMessage(f"Opened {path}", 5000)
        self.viewport.frame_all()
        self.viewport.render()
        return True

    def save(self) -> bool:
        if not self.doc.path:
            return self.save_as()
        return self.save_to(self.doc.path)

    def save_as(self) -> bool:
        start = self.doc.path or os.path.join(self._start_dir(), "pose.yaml")
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save pose", start, POSE_FILTER)
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
            self.statusBar().showMessage(f"Could not save: {exc}", 10000)
            QtWidgets.QMessageBox.critical(self, "Could not save pose",
                                           f"The pose was not saved (any existing file is unchanged).\n\n{exc}")
            return False
        self._add_recent(path)
        self.statusBar().showMessage(f"Saved {path}", 5000)
        return True

    def recent_files(self) -> list[str]:
        value = self.settings.value("recent_files", [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def _add_recent(self, path: str) -> None:
        path = os.path.abspath(path)
        files = [p for p in self.recent_files() if p != path]
        files.insert(0, path)
        self.settings.setValue("recent_files", files[:MAX_RECENT])
        self._update_recent_menu()

    def _update_recent_menu(self) -> None:
        self.recent_menu.clear()
        files = self.recent_files()
        for i, p in enumerate(files, start=1):
            a = self.recent_menu.addAction(f"&{i} {os.path.basename(p)}")
            a.setToolTip(p)
            a.triggered.connect(lambda _c=False, path=p: self.open_path(path))
        self.recent_menu.setEnabled(bool(files))

    def grab_window(self) -> QtGui.QImage:
        """A picture of the whole window, the 3D view freshly rendered."""
        self.viewport.refresh()
        self.plotter.render()
        QtWidgets.QApplication.processEvents()
        return self.grab().toImage()

    def screenshot_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save screenshot",
                                                        os.path.join(self._start_dir(), "gsik-studio.png"),
                                                        "PNG images (*.png)")
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
        self._update_readouts(force=True)
        return self.doc.last_result

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:  # noqa: N802 (Qt's name)
        if not self._confirm_discard("quit"):
            event.ignore()
            return
        self.timer.stop()
        self.play_timer.stop()
        self.settings.setValue("window/geometry", self.saveGeometry())
        self.settings.setValue("window/state", self.saveState())
        self.settings.sync()
        self.plotter.close()
        event.accept()
