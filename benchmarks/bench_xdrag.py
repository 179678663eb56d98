"""Frame rate of the studio under a drag made of real X mouse events (xdotool), as a person's drag arrives.

    xvfb-run -a -s "-screen 0 1600x1100x24" python benchmarks/bench_xdrag.py [--moves 300] [--rate 60]
        [--character character.glb]

Opens the real window (its own timers running, natural posture on as it starts), then
``xdotool`` (Debian package ``xdotool``), a separate process, presses on the left hand's
target sphere and moves the pointer round a circle at ``--rate`` moves per second, through
the X server, Qt and VTK's interactor and sphere widget. Prints renders per second of the
3D view during the drag, pointer moves sent per second, and the solver frames run, with
the window size and load. With ``--character``, the same drag on that skinned glTF character's left hand
in the same window and run, and the ratio of the frame rates. Compare with ``bench_app.py``'s QTest-driven figures.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_app import _app  # noqa: E402  (one place sets up Qt and PyVista for the benchmarks)


def _screen_point(window, world) -> tuple[int, int]:
    """Screen pixel (x, y) of a world point in the window's 3D view."""
    from PySide6 import QtCore

    pl = window.plotter
    ren = pl.renderer
    ren.SetWorldPoint(*world, 1.0)
    ren.WorldToDisplay()
    x, y, _ = ren.GetDisplayPoint()
    ratio = pl.devicePixelRatioF()
    p = pl.mapToGlobal(QtCore.QPoint(int(round(x / ratio)), int(round(pl.height() - y / ratio - 1))))
    return p.x(), p.y()


def _xdotool_drag(x: int, y: int, moves: int, rate: float, radius: int = 60) -> list[str]:
    """One xdotool command line: press at (x, y), ``moves`` moves round a circle, release."""
    cmd = ["xdotool", "mousemove", str(x), str(y), "sleep", "0.3", "mousedown", "1", "sleep", "0.2"]
    for i in range(1, moves + 1):
        a = 2 * np.pi * i / moves
        cmd += ["mousemove", str(int(round(x + radius * np.sin(a)))), str(int(round(y - radius * (1 - np.cos(a))))),
                "sleep", f"{1.0 / rate:.4f}"]
    return cmd + ["mouseup", "1"]


def _measure(app, w, target: str, moves: int, rate: float) -> tuple[float, float, int]:
    """Drag ``target`` round a circle with xdotool: (renders per second, farthest the target went [m], renders)."""
    from PySide6 import QtCore

    end = time.perf_counter() + 3.0
    while time.perf_counter() < end:  # shown, settled, idle
        app.processEvents()
    renders = []
    tag = w.plotter.render_window.AddObserver("EndEvent", lambda *_: renders.append(time.perf_counter()))
    start = np.array(w.doc.targets[target].position)
    x, y = _screen_point(w, start)
    drag = subprocess.Popen(_xdotool_drag(x, y, moves, rate))
    t0 = time.perf_counter()
    reach = 0.0  # farthest the target went from where it started [m]: the drag really moved it
    while drag.poll() is None:
        app.processEvents(QtCore.QEventLoop.AllEvents, 5)
        reach = max(reach, float(np.linalg.norm(w.doc.targets[target].position - start)))
    t1 = time.perf_counter()
    for _ in range(20):
        app.processEvents()
    w.plotter.render_window.RemoveObserver(tag)
    during = [t for t in renders if t0 + 0.5 <= t <= t1]  # from the press on (the first 0.5 s is move + press)
    return len(during) / (t1 - (t0 + 0.5)), reach, len(during)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=300)
    ap.add_argument("--rate", type=float, default=60.0, help="pointer moves per second sent")
    ap.add_argument("--character", help="also drag a skinned glTF character's hand in the same window (.glb)")
    args = ap.parse_args()
    if not os.environ.get("DISPLAY") or shutil.which("xdotool") is None:
        sys.exit("bench_xdrag needs an X display (xvfb-run) and xdotool")
    from PySide6 import QtCore

    from gsik_studio.window import MainWindow

    app = _app()
    scratch = tempfile.TemporaryDirectory()
    settings = QtCore.QSettings(os.path.join(scratch.name, "bench.ini"), QtCore.QSettings.IniFormat)
    w = MainWindow(settings=settings)
    w.resize(1280, 800)
    w.show()
    load = os.getloadavg()[0]
    fps, reach, n = _measure(app, w, "left_hand", args.moves, args.rate)
    print(f"studio under an xdotool drag: window 1280x800 (3D view {w.plotter.width()}x{w.plotter.height()}), "
          f"{args.moves} X pointer moves at {args.rate:.0f}/s, load {load:.1f} to {os.getloadavg()[0]:.1f}")
    print(f"  biped (mannequin): {fps:.1f} renders of the 3D view per second ({n} renders for {args.moves} moves); "
          f"the target went up to {100 * reach:.1f} cm from its start, {len(w.doc.history.commands)} undo step(s)")
    if args.character:
        from gsik_studio.model.characters import character_of

        w.doc.history.set_clean()
        if w.files.import_skeleton_path(args.character, confirm=False) is not True:
            sys.exit(f"could not open {args.character}")
        character = character_of(w.doc.skeleton)
        fps_c, reach, n = _measure(app, w, character.effectors["left_hand"], args.moves, args.rate)
        print(f"  character {os.path.basename(args.character)} ({w.body.mannequin.n_vertices:,} skinned vertices, "
              f"{w.doc.skeleton.n_dofs} DOFs): {fps_c:.1f} renders per second ({n} renders); the target went up "
              f"to {100 * reach:.1f} cm; character / biped: {fps_c / fps:.2f}")
    w.doc.history.set_clean()
    w.close()


if __name__ == "__main__":
    main()
