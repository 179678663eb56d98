"""Checks before Qt starts, so that a missing display or library gives one clear line instead of Qt's abort.

Without them, Qt's xcb platform plugin aborts the process (a core dump) and
blames ``libxcb-cursor0`` whatever the cause. Only plain ``ctypes`` is used:
nothing here needs Qt.
"""

from __future__ import annotations

import ctypes
import os
import sys

#: Shared libraries Qt's xcb platform plugin and the 3D view load (sonames). The README's set-up command
#: installs their Debian packages (.ci/debs holds that list).
XCB_LIBRARIES = ("libxcb.so.1", "libxcb-cursor.so.0", "libxkbcommon-x11.so.0", "libxcb-icccm.so.4",
                 "libxcb-keysyms.so.1", "libxcb-shape.so.0", "libxcb-randr.so.0", "libxcb-render-util.so.0",
                 "libxcb-image.so.0", "libfontconfig.so.1", "libfreetype.so.6", "libdbus-1.so.3",
                 "libglib-2.0.so.0", "libEGL.so.1", "libGL.so.1")
NO_DISPLAY = 3  # exit code: no display to open a window on
MISSING_LIBRARIES = 4  # exit code: system libraries missing


def missing_libraries(names=XCB_LIBRARIES) -> list[str]:
    """The sonames among ``names`` that cannot be loaded."""
    missing = []
    for name in names:
        try:
            ctypes.CDLL(name)
        except OSError:
            missing.append(name)
    return missing


def display_error(display: str | None) -> str | None:
    """Why no window can open on the X display ``display`` (None: it can)."""
    if not display:
        return "no display (DISPLAY is not set)"
    xcb = ctypes.CDLL("libxcb.so.1")
    xcb.xcb_connect.restype = ctypes.c_void_p
    xcb.xcb_connect.argtypes = (ctypes.c_char_p, ctypes.c_void_p)
    xcb.xcb_connection_has_error.argtypes = (ctypes.c_void_p,)
    xcb.xcb_disconnect.argtypes = (ctypes.c_void_p,)
    conn = xcb.xcb_connect(display.encode(), None)
    try:
        failed = xcb.xcb_connection_has_error(conn)
    finally:
        xcb.xcb_disconnect(conn)
    return f"cannot open display {display!r}" if failed else None


def check(environ=os.environ) -> tuple[int, str] | None:
    """``(exit code, one-line message)`` when the studio cannot open a window here; None when it can.

    Only Linux with Qt's default xcb platform is checked; another ``QT_QPA_PLATFORM`` is left to Qt.
    """
    if not sys.platform.startswith("linux") or environ.get("QT_QPA_PLATFORM", "xcb") != "xcb":
        return None
    missing = missing_libraries()
    if missing:
        return MISSING_LIBRARIES, (f"gsik-studio: missing system libraries {', '.join(missing)}; on Debian or Ubuntu "
                                   "the README's set-up command installs them (bash .ci/debs)")
    why = display_error(environ.get("DISPLAY"))
    if why:
        return NO_DISPLAY, (f"gsik-studio: {why}: run it in a desktop session, over ssh -X, or under "
                            "xvfb-run -a gsik-studio")
    return None
