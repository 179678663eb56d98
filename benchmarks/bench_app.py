"""gsik-studio frame-rate benchmark: the real window against a bare PyVista scene.

    xvfb-run -a -s "-screen 0 1600x1100x24" python benchmarks/bench_app.py [--frames 300]

1. The real :class:`gsik_studio.window.MainWindow` (1280x800, the mannequin and
   the centre of mass drawn) for ``--frames`` frames while the targets move: both hands circle, the head sways. Each
   frame is what the app does when the artist drags: a target move goes
   through the document's command (one merged undo step), the window's
   frame loop (:class:`gsik_studio.model.FrameLoop`, driven here instead of
   by the window's timer) steps the solver and updates the scene in place,
   then Qt paints the viewport (one VTK render).
2. A bare PyVista scene in a ``QtInteractor`` of the viewport's size with the
   same objects (the same kinds and counts of actors, sphere widgets and the
   box widget), whose points are moved in place each frame and rendered the
   same way: the floor this machine's rendering puts under any app.
3. The same window drawing the stick figure without the centre of mass:
   what the mannequin and the balance drawing cost, in the same run.

3. Both again under real mouse drags: Qt mouse events (``QTest``: press on a
   target sphere, then moves along a circle, release) go into each 3D view,
   through VTK's interactor and sphere widget as a person's drag does; one
   event-loop turn per mouse event, the app's own timer stepping the solver.
   Frames per second count renders that show a new mouse position (at most
   one per mouse event) per second of wall time; renders per mouse event
   are counted on the render window.

Printed: frames per second of all, the app's own time per frame excluding
VTK rendering and Qt painting (document command, solver step, scene update,
read-outs), and the solver's share of it; the last line is the real-mouse
ratio. Timings vary with machine load; nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _app():
    os.environ.setdefault("QT_QPA_PLATFORM", "xcb")
    from gsik_studio.qt_compat import protect_none

    protect_none()
    import pyvista as pv
    from PySide6 import QtWidgets

    pv.global_theme.multi_samples = 0
    return QtWidgets.QApplication.instance() or QtWidgets.QApplication(["bench_app"])


def RenderCounter(widget):
    """Counts the viewport's paint events (each one is one VTK render)."""
    from PySide6 import QtCore

    class Counter(QtCore.QObject):
        count = 0

        def eventFilter(self, obj, event):  # noqa: N802
            if event.type() == QtCore.QEvent.Paint:
                self.count += 1
            return False

    c = Counter()
    widget.installEventFilter(c)
    return c


def _pump(app, plotter, counter: RenderCounter) -> None:
    """Process Qt events until the scheduled repaint has rendered once."""
    before = counter.count
    deadline = time.perf_counter() + 1.0
    while counter.count == before and time.perf_counter() < deadline:
        app.processEvents()


class AppRun:
    """The real window; each frame moves three targets through a document command, runs one frame of the loop, paints.

    ``body``: "mannequin" (the default view) or "sticks"; ``com``: draw the centre of mass and support polygon.
    """

    def __init__(self, size: tuple[int, int], body: str = "mannequin", com: bool = True):
        import tempfile

        from PySide6 import QtCore

        from gsik_studio.window import MainWindow

        self.app = _app()
        self._scratch = tempfile.TemporaryDirectory()
        settings = QtCore.QSettings(os.path.join(self._scratch.name, "bench.ini"), QtCore.QSettings.IniFormat)
        self.w = w = MainWindow(settings=settings, run_timers=False)  # this benchmark drives w.loop itself
        w.resize(*size)
        w.show()
        w.set_body(body)
        w.show_support(com)
        for _ in range(20):
            self.app.processEvents()
        self.counter = RenderCounter(w.plotter)
        self.start = {n: np.array(t.position) for n, t in w.doc.targets.items()}
        self.app_times, self.solve_times, self.frame_times = [], [], []
        self.i = 0

    def frame(self, record: bool = True) -> None:
        w, doc, start = self.w, self.w.doc, self.start
        t0 = time.perf_counter()
        a = 2 * np.pi * self.i / 120
        self.i += 1
        doc.move_targets({
            "left_hand": start["left_hand"] + [-0.15 * np.sin(a), 0.25 + 0.15 * np.cos(a), 0.35],
            "right_hand": start["right_hand"] + [0.15 * np.sin(a), 0.25 - 0.15 * np.cos(a), 0.35],
            "head": start["head"] + [0.05 * np.sin(a), 0.03, 0.0],
        }, drag=1)
        w.loop.solve_frame()
        t1 = time.perf_counter()
        _pump(self.app, w.plotter, self.counter)
        t2 = time.perf_counter()
        if record:
            self.app_times.append(t1 - t0)
            self.solve_times.append(doc.last_solve_time)
            self.frame_times.append(t2 - t0)

    def close(self) -> dict:
        w = self.w
        out = dict(viewport=(w.plotter.width(), w.plotter.height()), objects=w.viewport.n_scene_objects(),
                   commands=len(w.doc.history.commands), renders=self.counter.count)
        w.doc.history.set_clean()
        w.close()
        self.app.processEvents()
        return out


class BareRun:
    """A bare QtInteractor filling a window, with copies of the app's meshes (same objects, same geometry)
    and the same widgets, points moved in place each frame: no document, no solver, no side panel."""

    def __init__(self, window_size: tuple[int, int], source):
        import pyvista as pv
        import vtk
        from pyvistaqt import QtInteractor
        from PySide6 import QtWidgets
        from vtkmodules.util.numpy_support import vtk_to_numpy

        from gsik_studio.scene import glyph_actor

        vp = source.w.viewport
        self.app = _app()
        self.win = win = QtWidgets.QMainWindow()
        self.pl = pl = QtInteractor(win, auto_update=False, multi_samples=0)
        win.setCentralWidget(pl)
        win.resize(*window_size)
        win.show()
        pl.set_background((0.1, 0.11, 0.13), top=(0.24, 0.26, 0.31))
        pl.enable_lightkit()

        def copy(name):
            return pv.wrap(vp.actors[name].GetMapper().GetInput()).copy()

        pl.add_mesh(copy("grid"), color="gray", line_width=1, lighting=False)
        pl.add_mesh(copy("floor"), color=(0.16, 0.17, 0.2))
        self.dynamic = []
        for name, kw in (("bones", dict(color="beige", line_width=7, render_lines_as_tubes=True)),
                         ("gizmos", dict(scalars="colors", rgb=True, line_width=2, lighting=False)),
                         ("triads", dict(scalars="colors", rgb=True, line_width=3, lighting=False)),
                         ("errors", dict(color="pink", line_width=1, lighting=False))):
            pd = copy(name)
            pl.add_mesh(pd, **kw)
            self.dynamic.append(pd)
        for name in ("joints", "effectors"):
            pd = pv.PolyData(vtk_to_numpy(vp.actors[name].GetMapper().GetInput().GetPoints().GetData()).copy())
            pl.add_actor(glyph_actor(pd, 0.022, None, (0.8, 0.8, 0.8)))
            self.dynamic.append(pd)
        pl.add_mesh(copy("root"), color="yellow", lighting=False)
        label = vtk.vtkBillboardTextActor3D()
        label.SetInput("left_hand")
        label.SetPosition(*source.start["left_hand"])
        pl.add_actor(label)
        text = vtk.vtkTextActor()
        text.SetInput("IK root: right foot")
        pl.add_actor(text)
        pl.add_axes()
        self.widgets = []
        for k, w0 in enumerate(vp.target_widgets):
            sw = vtk.vtkSphereWidget()
            sw.SetInteractor(pl.iren.interactor)
            sw.SetCurrentRenderer(pl.renderer)
            sw.SetRepresentationToSurface()
            sw.SetRadius(w0.GetRadius())
            sw.SetThetaResolution(w0.GetThetaResolution())
            sw.SetPhiResolution(w0.GetPhiResolution())
            sw.SetCenter(*w0.GetCenter())
            sw.GetSphereProperty().SetOpacity(w0.GetSphereProperty().GetOpacity())
            if w0.GetEnabled():
                sw.On()
            self.widgets.append(sw)
        box = vtk.vtkBoxWidget()
        box.SetInteractor(pl.iren.interactor)
        box.SetCurrentRenderer(pl.renderer)
        c = source.start["left_hand"]
        box.PlaceWidget(c[0] - 0.08, c[0] + 0.08, c[1] - 0.08, c[1] + 0.08, c[2] - 0.08, c[2] + 0.08)
        box.HandlesOff()
        box.On()
        self.box = box
        cam = source.w.plotter.camera
        pl.camera_position = [cam.position, cam.focal_point, cam.up]
        pl.camera.view_angle = cam.view_angle
        self.counter = RenderCounter(pl)
        self.views = [vtk_to_numpy(pd.GetPoints().GetData()) for pd in self.dynamic]
        self.base = [v.copy() for v in self.views]
        self.frame_times = []
        self.i = 0

    def frame(self, record: bool = True) -> None:
        t0 = time.perf_counter()
        a = 2 * np.pi * self.i / 120
        self.i += 1
        for pd, v, b in zip(self.dynamic, self.views, self.base):
            v[:] = b + [0.0, 0.03 * np.sin(a), 0.0]
            pd.GetPoints().Modified()
        self.widgets[2].SetCenter(*(self.views[-1][2] + [0.0, 0.2, 0.3]))
        self.pl.update()
        _pump(self.app, self.pl, self.counter)
        if record:
            self.frame_times.append(time.perf_counter() - t0)

    def close(self) -> dict:
        out = dict(viewport=(self.pl.width(), self.pl.height()), renders=self.counter.count)
        self.pl.close()
        self.win.close()
        self.app.processEvents()
        return out


class MouseDrag:
    """Drags one target sphere of a 3D view with real Qt mouse events, one event-loop turn per event."""

    def __init__(self, app, plotter, center_world, radius_px: float = 60.0):
        self.app, self.pl = app, plotter
        ren = plotter.renderer
        ren.SetWorldPoint(*center_world, 1.0)
        ren.WorldToDisplay()
        self.x, self.y, _ = ren.GetDisplayPoint()
        self.radius = radius_px
        self.renders = 0
        plotter.render_window.AddObserver("EndEvent", self._count)
        self.events = 0
        self.seconds = 0.0
        self.k = 0

    def _count(self, *_):
        self.renders += 1

    def _qpoint(self, dx: float, dy: float):
        from PySide6 import QtCore

        ratio = self.pl.devicePixelRatioF()
        return QtCore.QPoint(int(round((self.x + dx) / ratio)), int(round(self.pl.height() - (self.y + dy) / ratio - 1)))

    def run(self, n_moves: int, record: bool = True) -> None:
        """Press on the sphere, ``n_moves`` moves around a circle (back where it started), release."""
        from PySide6 import QtCore
        from PySide6.QtTest import QTest

        left, none = QtCore.Qt.LeftButton, QtCore.Qt.NoModifier
        QTest.mouseMove(self.pl, self._qpoint(0, 0))
        QTest.mousePress(self.pl, left, none, self._qpoint(0, 0))
        self.app.processEvents()
        r0, t0 = self.renders, time.perf_counter()
        for i in range(1, n_moves + 1):
            a = 2 * np.pi * i / n_moves
            QTest.mouseMove(self.pl, self._qpoint(self.radius * np.sin(a), self.radius * (1 - np.cos(a))))
            self.app.processEvents()
        if record:
            self.seconds += time.perf_counter() - t0
            self.events += n_moves
            self.frames = getattr(self, "frames", 0) + self.renders - r0
        QTest.mouseRelease(self.pl, left, none, self._qpoint(0, 0))
        self.app.processEvents()

    @property
    def fps(self) -> float:
        """Frames that showed a new mouse position per second: a second render of the same event is not one."""
        return min(self.frames, self.events) / self.seconds

    @property
    def renders_per_event(self) -> float:
        return self.frames / self.events


def _fps(frame_times: list[float]) -> float:
    return len(frame_times) / sum(frame_times)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=300, help="frames per scene (default 300)")
    p.add_argument("--size", default="1280x800", help="window size (default 1280x800)")
    p.add_argument("--block", type=int, default=25, help="frames per turn: the scenes take turns (default 25)")
    args = p.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    if not os.environ.get("DISPLAY"):
        sys.exit("bench_app needs an X display: run it under xvfb-run (see the docstring)")

    app_run = AppRun(size)
    viewport = (app_run.w.plotter.width(), app_run.w.plotter.height())
    bare = BareRun(size, app_run)
    bare_vp = BareRun(viewport, app_run)
    sticks = AppRun(size, body="sticks", com=False)
    runs = (app_run, bare, bare_vp, sticks)
    for run in runs:  # warm up
        for _ in range(10):
            run.frame(record=False)
    # Take turns in blocks, so that load from other processes hits every scene alike.
    done = 0
    while done < args.frames:
        n = min(args.block, args.frames - done)
        for run in runs:
            for _ in range(n):
                run.frame()
        done += n
    fps_app, fps_bare, fps_vp, fps_sticks = (_fps(r.frame_times) for r in runs)
    drags = _mouse_drags(app_run, bare_vp, args)
    info, bare_info, vp_info, _ = (r.close() for r in runs)
    app_ms = 1e3 * statistics.median(app_run.app_times)
    p95 = 1e3 * float(np.percentile(app_run.app_times, 95))
    solve = 1e3 * statistics.median(app_run.solve_times)
    print(f"gsik-studio benchmark: window {size[0]}x{size[1]} (3D viewport {viewport[0]}x{viewport[1]}), "
          f"{args.frames} frames per scene in turns of {args.block}, 3 targets moving")
    frame_ms = 1e3 * statistics.median(app_run.frame_times)
    print(f"  app window:            {fps_app:6.1f} fps  (median frame {frame_ms:.1f} ms;"
          f" {info['renders']} paints for {args.frames + 10} frames; {info['commands']} undo step for the whole drag)")
    print(f"  app's own time/frame:  {app_ms:6.3f} ms median, {p95:.3f} ms p95 (target command, solver step, scene "
          f"update, read-outs; no VTK render, no Qt paint)")
    print(f"    of which the solver: {solve:6.3f} ms median")
    print(f"  bare PyVista scene:    {fps_bare:6.1f} fps  (same objects {info['objects']}, same window size, "
          f"the 3D view filling it)")
    print(f"  app / bare:            {100 * fps_app / fps_bare:6.1f} %")
    print(f"  app, stick view, no centre of mass: {fps_sticks:.1f} fps (mannequin / sticks: "
          f"{100 * fps_app / fps_sticks:.1f} %; own time {1e3 * statistics.median(sticks.app_times):.3f} ms median)")
    print(f"  bare scene, window the size of the app's 3D view {vp_info['viewport'][0]}x{vp_info['viewport'][1]}: "
          f"{fps_vp:.1f} fps (app / that: {100 * fps_app / fps_vp:.1f} %)")
    app_drag, bare_drag = drags
    print(f"  real mouse drags ({app_drag.events} Qt mouse moves per scene, one event-loop turn each; bare scene "
          f"the size of the app's 3D view): renders per mouse event app {app_drag.renders_per_event:.2f}, "
          f"bare {bare_drag.renders_per_event:.2f}")
    print(f"app/bare under real mouse drags: {100 * app_drag.fps / bare_drag.fps:.0f}% "
          f"(app {app_drag.fps:.1f} fps, bare {bare_drag.fps:.1f} fps)")


def _mouse_drags(app_run: AppRun, bare: BareRun, args) -> tuple[MouseDrag, MouseDrag]:
    """Both scenes dragged by real Qt mouse events in turns; the app's solver runs on its own timer."""
    w = app_run.w
    w.run_timers = True
    name = "left_hand"
    k = w.viewport._sites.index(name)
    app_drag = MouseDrag(app_run.app, w.plotter, w.viewport.target_widgets[k].GetCenter())
    bare_drag = MouseDrag(bare.app, bare.pl, bare.widgets[k].GetCenter())
    for d in (app_drag, bare_drag):
        d.run(20, record=False)  # warm up
    done = 0
    while done < args.frames:
        n = min(args.block * 2, args.frames - done)
        for d in (app_drag, bare_drag):
            d.run(n)
        done += n
    w.doc.history.set_clean()
    return app_drag, bare_drag


if __name__ == "__main__":
    main()
