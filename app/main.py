"""``gsik-studio [pose.yaml]`` and ``gsik-studio --screenshot out.png [pose.yaml]``."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="gsik-studio", description="Interactive IK pose authoring (gsik).")
    p.add_argument("pose", nargs="?", help="a pose file (.yaml) to open")
    p.add_argument("--screenshot", metavar="PNG", help="render the window once to this PNG and exit")
    p.add_argument("--size", metavar="WxH", help="window size (default: as last time, else 1440x900)")
    p.add_argument("--view", choices=("perspective", "front", "side", "top"),
                   help="camera preset (default perspective)")
    return p


def _application():
    """The QApplication, themed (the Qt platform is X11 on Linux unless QT_QPA_PLATFORM says otherwise)."""
    os.environ.setdefault("QT_QPA_PLATFORM", "xcb" if sys.platform.startswith("linux") else "")
    if not os.environ["QT_QPA_PLATFORM"]:
        del os.environ["QT_QPA_PLATFORM"]
    from gsik_studio.qt_compat import protect_none

    protect_none()  # PySide6 6.12 on Python 3.11 drops references to None (see gsik_studio.qt_compat)
    from PySide6 import QtWidgets

    from gsik_studio.widgets.theme import apply_dark_theme

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication([sys.argv[0]])
    app.setApplicationName("gsik-studio")
    app.setOrganizationName("gsik")
    apply_dark_theme(app)
    return app


def _screenshot(app, args, size: tuple[int, int]) -> int:
    """A one-shot picture: no remembered geometry, no dialogs."""
    from PySide6 import QtCore

    import gsik
    from gsik_studio.model import Document, transfer
    from gsik_studio.window import MainWindow

    doc = Document()
    if args.pose:
        try:
            doc, warnings = transfer.open_pose(args.pose, doc)  # on the skeleton the file names
        except gsik.GsikError as exc:
            print(f"gsik-studio: {exc}", file=sys.stderr)
            return 1
        for w in warnings:
            print(f"gsik-studio: warning: {w}", file=sys.stderr)
    with tempfile.TemporaryDirectory(prefix="gsik-studio-") as scratch:
        settings = QtCore.QSettings(os.path.join(scratch, "settings.ini"), QtCore.QSettings.IniFormat)
        window = MainWindow(doc, settings=settings)
        window.resize(*size)
        window.show()
        app.processEvents()
        window.settle()
        window.set_view(args.view or "perspective")
        app.processEvents()
        ok = window.save_screenshot(args.screenshot)
        doc.history.set_clean()
        window.close()
    if not ok:
        print(f"gsik-studio: could not write {args.screenshot}", file=sys.stderr)
        return 1
    print(args.screenshot)
    return 0


def main(argv: list[str] | None = None) -> int:
    """Run gsik-studio; returns the exit code."""
    from gsik_studio import preflight

    args = _parser().parse_args(sys.argv[1:] if argv is None else argv)
    try:
        width, height = (int(v) for v in (args.size or "1440x900").lower().split("x"))
    except ValueError:
        print(f"gsik-studio: --size must look like 1440x900, got {args.size!r}", file=sys.stderr)
        return 2
    problem = preflight.check()
    if problem is not None:
        print(problem[1], file=sys.stderr)
        return problem[0]
    app = _application()
    if args.screenshot:
        import pyvista as pv

        pv.global_theme.multi_samples = 0
        return _screenshot(app, args, (width, height))
    window = open_window(app, args, (width, height))
    if args.pose:
        from PySide6 import QtCore

        QtCore.QTimer.singleShot(0, lambda: window.open_path(args.pose, confirm=False))
    return app.exec()


def open_window(app, args: argparse.Namespace, size: tuple[int, int]):
    """The main window, shown: a start window appears at once and says what loads meanwhile.

    ``--size`` and ``--view``, when given, win over the remembered geometry and the default view.
    """
    from gsik_studio.starting import StartWindow, load_document, mark

    mark("python and qt")
    start = StartWindow(size)
    start.show()
    app.processEvents()
    mark("start window")
    doc = load_document(app, start)
    from gsik_studio.window import MainWindow

    window = MainWindow(doc)
    mark("window built")
    if args.size or window.settings.value("window/geometry") is None:
        window.resize(*size)
    window.show()
    start.close()
    app.processEvents()  # the first paint: the 3D view renders once
    mark("first frame")
    if args.view:
        window.set_view(args.view)
    return window


if __name__ == "__main__":
    raise SystemExit(main())
