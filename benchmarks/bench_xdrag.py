"""Frame rate of the studio under a drag made of real X mouse events (xdotool), as a person's drag arrives.

    xvfb-run -a -s "-screen 0 1600x1100x24" python benchmarks/bench_xdrag.py [--moves 300] [--rate 60]
        [--character character.glb] [--rounds 3] [--before CHECKOUT]

Opens the real window (its own timers running, natural posture on as it starts), then
``xdotool`` (Debian package ``xdotool``), a separate process, presses on the left hand's
target sphere and moves the pointer round a circle at ``--rate`` moves per second, through
the X server, Qt and VTK's interactor and sphere widget. Prints renders per second of the
3D view during the drag, the process's CPU time per render (all its threads, Mesa's included:
steadier than the rate under a varying load), the window size, OpenGL renderer and load.

With ``--character``, each round drags the biped's hand and then that skinned glTF character's hand, in the
same window, ``--rounds`` times alternately, and prints the ratio of the frame rates. With ``--before``, each
round first drags the biped's hand in a window running another checkout's ``gsik`` and studio (its ``gsik/``
and ``app/`` folders; a subprocess, the same display), so the biped's frame rate is compared with that code's
in the same sequence. Compare with ``bench_app.py``'s QTest-driven figures.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_app import _app  # noqa: E402  (one place sets up Qt and PyVista for the benchmarks)

#: Set (by ``--before``) to a checkout whose gsik and studio this process runs instead of the installed ones.
CHECKOUT_ENV = "GSIK_BENCH_CHECKOUT"


class Drag(NamedTuple):
    """One measured drag: renders per second, CPU [s] per render, farthest the target went [m], renders."""

    fps: float
    cpu_per_render: float
    reach: float
    renders: int


def _use_checkout(path: str) -> None:
    """Import ``gsik`` from ``path/gsik`` and the studio (``gsik_studio``) from ``path/app``."""
    import importlib.util

    sys.path.insert(0, os.path.abspath(path))
    app = os.path.join(os.path.abspath(path), "app")
    spec = importlib.util.spec_from_file_location("gsik_studio", os.path.join(app, "__init__.py"),
                                                  submodule_search_locations=[app])
    module = importlib.util.module_from_spec(spec)
    sys.modules["gsik_studio"] = module
    spec.loader.exec_module(module)


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


def _measure(app, w, target: str, moves: int, rate: float) -> Drag:
    """Drag ``target`` round a circle with xdotool, the window's event loop running as in the app (it sleeps
    between events; a polling loop here would take the CPU the renders need)."""
    from PySide6 import QtCore

    loop = QtCore.QEventLoop()
    QtCore.QTimer.singleShot(3000, loop.quit)  # shown, settled, idle
    loop.exec()
    renders = []
    tag = w.plotter.render_window.AddObserver("EndEvent", lambda *_: renders.append(time.perf_counter()))
    start = np.array(w.doc.targets[target].position)
    x, y = _screen_point(w, start)
    drag = subprocess.Popen(_xdotool_drag(x, y, moves, rate))
    t0 = time.perf_counter()
    seen = {"reach": 0.0, "cpu0": None}  # farthest the target went from its start [m]: the drag really moved it

    def check() -> None:
        seen["reach"] = max(seen["reach"], float(np.linalg.norm(w.doc.targets[target].position - start)))
        if seen["cpu0"] is None and time.perf_counter() >= t0 + 0.5:
            seen["cpu0"] = time.process_time()
        if drag.poll() is not None:
            loop.quit()

    timer = QtCore.QTimer()
    timer.setInterval(20)
    timer.timeout.connect(check)
    timer.start()
    loop.exec()
    timer.stop()
    t1, cpu1 = time.perf_counter(), time.process_time()
    QtCore.QTimer.singleShot(300, loop.quit)
    loop.exec()
    w.plotter.render_window.RemoveObserver(tag)
    n = len([t for t in renders if t0 + 0.5 <= t <= t1])  # from the press on (the first 0.5 s is move + press)
    cpu0 = seen["cpu0"] if seen["cpu0"] is not None else cpu1
    return Drag(n / (t1 - (t0 + 0.5)), (cpu1 - cpu0) / max(n, 1), seen["reach"], n)


def _window():
    from PySide6 import QtCore

    from gsik_studio.window import MainWindow

    app = _app()
    scratch = tempfile.TemporaryDirectory()
    settings = QtCore.QSettings(os.path.join(scratch.name, "bench.ini"), QtCore.QSettings.IniFormat)
    w = MainWindow(settings=settings)
    w._bench_scratch = scratch
    w.resize(1280, 800)
    w.show()
    return app, w


def _gl_renderer(w) -> str:
    caps = w.plotter.render_window.ReportCapabilities()
    line = next((s for s in caps.splitlines() if "renderer string" in s), "OpenGL renderer: unknown")
    return line.split(":", 1)[1].strip()


def _biped(app, w, args) -> Drag:
    """The biped's left hand dragged, on a new biped document when the window shows another skeleton."""
    if w.doc.skeleton.name != "biped":
        w.doc.history.set_clean()
        w.files.new_on_skeleton("biped")
    return _measure(app, w, "left_hand", args.moves, args.rate)


def _character(app, w, args) -> Drag:
    from gsik_studio.model.characters import character_of

    w.doc.history.set_clean()
    if w.files.import_skeleton_path(args.character, confirm=False) is not True:
        sys.exit(f"could not open {args.character}")
    return _measure(app, w, character_of(w.doc.skeleton).effectors["left_hand"], args.moves, args.rate)


def _before(args) -> Drag:
    """The biped dragged in a window of ``args.before``'s code (a subprocess of this script)."""
    cmd = [sys.executable, os.path.abspath(__file__), "--json", "--rounds", "1", "--moves", str(args.moves),
           "--rate", str(args.rate)]
    done = subprocess.run(cmd, env={**os.environ, CHECKOUT_ENV: os.path.abspath(args.before)}, capture_output=True,
                          text=True)
    if done.returncode != 0:
        sys.exit(f"the biped on {args.before} failed:\n{done.stderr[-2000:]}")
    return Drag(*json.loads(done.stdout.strip().splitlines()[-1])["biped"])


def _row(name: str, d: Drag) -> str:
    return (f"  {name}: {d.fps:5.1f} renders/s, {1000 * d.cpu_per_render:5.0f} ms CPU per render ({d.renders} renders), "
            f"the target went up to {100 * d.reach:.0f} cm")


def _summary(rows: dict[str, list[Drag]]) -> None:
    fps = {k: float(np.mean([d.fps for d in v])) for k, v in rows.items() if v}
    cpu = {k: float(np.mean([d.cpu_per_render for d in v])) for k, v in rows.items() if v}
    for k in fps:
        print(f"mean {k}: {fps[k]:.1f} renders/s, {1000 * cpu[k]:.0f} ms CPU per render")
    pairs = [("character", "biped"), ("biped", "biped before"), ("character", "biped before")]
    for a, b in pairs:
        if a in fps and b in fps:
            each = [x.fps / y.fps for x, y in zip(rows[a], rows[b])]
            print(f"{a} / {b}: {fps[a] / fps[b]:.2f} of the frame rate, median of the rounds {np.median(each):.2f} "
                  f"(rounds: {', '.join(f'{r:.2f}' for r in each)}), {cpu[b] / cpu[a]:.2f} of the CPU per render "
                  "inverted")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moves", type=int, default=300)
    ap.add_argument("--rate", type=float, default=60.0, help="pointer moves per second sent")
    ap.add_argument("--character", help="also drag a skinned glTF character's hand in the same window (.glb)")
    ap.add_argument("--rounds", type=int, default=1, help="how many times to alternate the drags")
    ap.add_argument("--before", help="a checkout whose biped to drag first in each round, in its own window")
    ap.add_argument("--json", action="store_true", help="print the drags as one JSON line (used by --before)")
    args = ap.parse_args()
    if not os.environ.get("DISPLAY") or shutil.which("xdotool") is None:
        sys.exit("bench_xdrag needs an X display (xvfb-run) and xdotool")
    if os.environ.get(CHECKOUT_ENV):
        _use_checkout(os.environ[CHECKOUT_ENV])
    app, w = _window()
    rows: dict[str, list[Drag]] = {"biped before": [], "biped": [], "character": []}
    load = os.getloadavg()[0]
    for r in range(args.rounds):
        if args.before:
            rows["biped before"].append(_before(args))
        rows["biped"].append(_biped(app, w, args))
        if args.character:
            rows["character"].append(_character(app, w, args))
        if not args.json:
            print(f"round {r + 1}:")
            for k, v in rows.items():
                if v:
                    print(_row(f"{k} ({os.path.basename(args.character)})" if k == "character" else k, v[-1]))
    if args.json:
        print(json.dumps({k: v[0] for k, v in rows.items() if v}))
    else:
        extra = f", character: {w.body.mannequin.n_vertices:,} skinned vertices, {w.doc.skeleton.n_dofs} DOFs" \
            if args.character else ""
        print(f"window 1280x800 (3D view {w.plotter.width()}x{w.plotter.height()}), {_gl_renderer(w)}, "
              f"{args.moves} X pointer moves at {args.rate:.0f}/s per drag, load {load:.1f} to "
              f"{os.getloadavg()[0]:.1f}{extra}")
        _summary(rows)
    w.doc.history.set_clean()
    w.close()


if __name__ == "__main__":
    main()
