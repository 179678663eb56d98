"""The window's actions, menus and toolbar, from declarative tables; one loop makes them.

A slot takes the window (``slot(window)``), or for a checkable action the
window and the new state (``slot(window, checked)``). This module does not
import the window: the tables only name what the window offers.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from PySide6 import QtCore, QtGui, QtWidgets
from PySide6.QtCore import Qt

S = QtWidgets.QStyle
K = QtGui.QKeySequence


@dataclass(frozen=True)
class ActionSpec:
    """One action: ``name`` (the window's ``act_<name>``), menu text, slot, shortcut(s), tooltip, icon."""

    name: str
    text: str
    slot: Callable
    shortcut: object = None  # a key string, a QKeySequence.StandardKey, or a tuple of strings
    tip: str = ""
    icon: object = None  # a QStyle.StandardPixmap
    checkable: bool = False
    group: str | None = None  # checkable actions of one group are exclusive


def _root(name: str) -> Callable:
    return lambda w, on: w.set_root(name) if on else None


def _view(name: str) -> Callable:
    return lambda w: w.set_view(name)


VIEW_KEYS = (("front", "1"), ("side", "3"), ("top", "7"), ("perspective", "5"))

#: The timeline's keys: (button of the timeline bar, menu text, key).
TIMELINE_KEYS = (("previous_frame", "Previous frame", "Left"), ("next_frame", "Next frame", "Right"),
                 ("previous_key", "Previous key", "Shift+Left"), ("next_key", "Next key", "Shift+Right"),
                 ("key", "Key the pose", "K"), ("delete_key", "Delete key", "Shift+K"))


def _timeline(button: str) -> Callable:
    """Press one of the timeline bar's buttons (a disabled one does nothing)."""
    return lambda w: w.timeline_bar.buttons[button].click()

ACTIONS: tuple[ActionSpec, ...] = (
    ActionSpec("new", "&New", lambda w: w.files.new_pose(), K.New, "Start over from the standing pose"),
    ActionSpec("open", "&Open…", lambda w: w.files.open_dialog(), K.Open, "Open a pose file", S.SP_DialogOpenButton),
    ActionSpec("save", "&Save", lambda w: w.files.save(), K.Save, "Save the pose", S.SP_DialogSaveButton),
    ActionSpec("save_as", "Save &As…", lambda w: w.files.save_as(), "Ctrl+Shift+S", "Save the pose to a new file"),
    ActionSpec("import_clip", "Import BVH &clip…", lambda w: w.files.import_clip_dialog(), None,
               "Import a BVH clip onto the timeline (a clip of another skeleton becomes a new document here)"),
    ActionSpec("import_skeleton", "Import s&keleton…", lambda w: w.files.import_skeleton_dialog(), None,
               "A new document in this window on a skeleton from a YAML or URDF file"),
    ActionSpec("import_skeleton_window", "Import skeleton in new &window…",
               lambda w: w.files.import_skeleton_dialog(new_window=True), None,
               "A new window on a skeleton from a YAML or URDF file (this document stays open here)"),
    ActionSpec("export_bvh", "&Export BVH…", lambda w: w.files.export_bvh_dialog(), None,
               "Export the clip, the keyed sequence or the pose as BVH"),
    ActionSpec("screenshot", "Screens&hot…", lambda w: w.screenshot_dialog(), None, "Save a picture of the window",
               S.SP_DesktopIcon),
    ActionSpec("quit", "&Quit", lambda w: w.close(), K.Quit, "Quit gsik-studio"),
    ActionSpec("undo", "&Undo", lambda w: w.undo(), K.Undo, "Undo the last edit", S.SP_ArrowBack),
    ActionSpec("redo", "&Redo", lambda w: w.redo(), ("Ctrl+Shift+Z", "Ctrl+Y"), "Redo", S.SP_ArrowForward),
    ActionSpec("reset", "Reset", lambda w: w.doc.reset(), None, "Back to the standing pose", S.SP_BrowserReload),
    ActionSpec("random", "Random", lambda w: w.doc.random_pose(), None, "A random pose"),
    ActionSpec("mirror_lr", "Mirror L→R", lambda w: w.doc.mirror("left"), None,
               "Copy the left side's pose, mirrored, onto the right side"),
    ActionSpec("mirror_rl", "Mirror R→L", lambda w: w.doc.mirror("right"), None,
               "Copy the right side's pose, mirrored, onto the left side"),
    ActionSpec("root_left", "Root: left foot", _root("left_foot"), None,
               "Pin the left foot (the IK root); the pose does not move", checkable=True, group="root"),
    ActionSpec("root_right", "Root: right foot", _root("right_foot"), None,
               "Pin the right foot (the IK root); the pose does not move", checkable=True, group="root"),
    ActionSpec("walk", "Walk", lambda w: w.play_walk(), None,
               "Play a walk: the IK root swaps between the feet at every step", S.SP_MediaSeekForward),
    ActionSpec("pause", "Pause", lambda w, on: w.set_paused(on), "Space", "Pause or resume solving", S.SP_MediaPause,
               checkable=True),
    ActionSpec("frame", "Frame all", lambda w: w.frame_all(), ("F", "Home"), "Fit the character in the view"),
    ActionSpec("frame_selected", "Frame selected", lambda w: w.frame_selected(), ("Shift+F", "."),
               "Fit the selected target and its effector in the view"),
    *(ActionSpec(f"view_{n}", n.capitalize(), _view(n), key,
                 f"{n.capitalize()} view" + ("" if n == "perspective" else " (orthographic)"))
      for n, key in VIEW_KEYS),
    ActionSpec("trackball", "Trackball orbit", lambda w, on: w.set_orbit("trackball" if on else "turntable"), None,
               "Orbit freely (the horizon may roll); off: turntable, z stays up", checkable=True),
    ActionSpec("shortcuts", "&Shortcuts", lambda w: w.show_shortcuts(), "F1", "List the keyboard and mouse controls"),
    *(ActionSpec(f"timeline_{n}", text, _timeline(n), key) for n, text, key in TIMELINE_KEYS),
    ActionSpec("sticks", "Stick figure", lambda w, on: w.set_body("sticks" if on else "mannequin"), None,
               "Draw the body as sticks instead of the mannequin", checkable=True),
)

#: Menus: (title, entries); an entry names an action or a submenu, None is a separator.
MENUS = (
    ("&File", ("new", "new_skeleton", "open", "recent", None, "save", "save_as", None, "import_clip", "import_skeleton",
               "import_skeleton_window", "export_bvh", None, "screenshot", None, "quit")),
    ("&Edit", ("undo", "redo")),
    ("&Pose", ("root_left", "root_right", None, "reset", "random", "mirror_lr", "mirror_rl", "walk", "scenarios")),
    ("&View", ("frame", "frame_selected", None, *(f"view_{n}" for n, _ in VIEW_KEYS), None, "trackball", "sticks")),
    ("&Timeline", tuple(f"timeline_{n}" for n, _, _ in TIMELINE_KEYS)),
    ("&Solver", ("pause",)),
    ("&Help", ("shortcuts",)),
)

TOOLBAR = ("open", "save", None, "undo", "redo", None, "root_left", "root_right", None, "reset", "random",
           "mirror_lr", "mirror_rl", None, "walk", "scenarios", None, "pause", "screenshot", None, "frame")


def _set_shortcut(a: QtGui.QAction, shortcut) -> None:
    if shortcut is None:
        return
    keys = shortcut if isinstance(shortcut, tuple) else (shortcut,)
    a.setShortcuts([K(s) for s in keys])
    a.setShortcutContext(Qt.WindowShortcut)


def _set_tip(a: QtGui.QAction, tip: str) -> None:
    if not tip:
        return
    keys = ", ".join(s.toString(K.NativeText) for s in a.shortcuts())
    a.setToolTip(f"{tip} ({keys})" if keys else tip)
    a.setStatusTip(tip)


def make_actions(window: QtWidgets.QMainWindow, specs: Sequence[ActionSpec] = ACTIONS) -> dict[str, QtGui.QAction]:
    """``{name: QAction}`` for every row of ``specs``, connected to ``window``."""
    actions, groups = {}, {}
    for spec in specs:
        a = QtGui.QAction(spec.text, window)
        _set_shortcut(a, spec.shortcut)
        _set_tip(a, spec.tip)
        if spec.icon is not None:
            a.setIcon(window.style().standardIcon(spec.icon))
        a.setCheckable(spec.checkable)
        if spec.checkable:
            a.toggled.connect(lambda on, s=spec: s.slot(window, on))
        else:
            a.triggered.connect(lambda _checked=False, s=spec: s.slot(window))
        if spec.group is not None:
            groups.setdefault(spec.group, QtGui.QActionGroup(window)).addAction(a)
        actions[spec.name] = a
    return actions


def _fill(widget, entries, actions: Mapping[str, QtGui.QAction], menus: Mapping[str, QtWidgets.QMenu]) -> None:
    for entry in entries:
        if entry is None:
            widget.addSeparator()
        elif entry in menus:
            widget.addAction(menus[entry].menuAction())
        else:
            widget.addAction(actions[entry])


def make_menus(window: QtWidgets.QMainWindow, actions: Mapping[str, QtGui.QAction],
               menus: Mapping[str, QtWidgets.QMenu]) -> None:
    """The menu bar from :data:`MENUS` (``menus`` holds the submenus named there)."""
    for title, entries in MENUS:
        _fill(window.menuBar().addMenu(title), entries, actions, menus)


def make_toolbar(window: QtWidgets.QMainWindow, actions: Mapping[str, QtGui.QAction],
                 menus: Mapping[str, QtWidgets.QMenu]) -> QtWidgets.QToolBar:
    """The main toolbar from :data:`TOOLBAR`; a submenu's button opens its menu at once."""
    tb = window.addToolBar("Main")
    tb.setObjectName("main_toolbar")
    tb.setMovable(False)
    tb.setToolButtonStyle(Qt.ToolButtonTextBesideIcon)
    tb.setIconSize(QtCore.QSize(18, 18))
    _fill(tb, TOOLBAR, actions, menus)
    for entry in TOOLBAR:
        if entry in menus:
            button = tb.widgetForAction(menus[entry].menuAction())
            if isinstance(button, QtWidgets.QToolButton):
                button.setPopupMode(QtWidgets.QToolButton.InstantPopup)
    return tb
