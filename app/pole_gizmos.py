"""Pole targets for knees and elbows as gizmos over the body: a violet sphere per pole, a thin line to its joint.

Built once (hidden while pole targets are off). The spheres are widgets of
the body's overlay renderer (drawn over the mannequin, as the selected joint's
highlight is), so a pole is seen and grabbed even behind an arm; they rest
out in front of the knees and behind the elbows
(:mod:`gsik_studio.model.pole_places`). A drag moves the pole through
:meth:`gsik_studio.model.pins.SolveControls.move_pole` (one undo step per drag).
A viewport layer: each frame the spheres not being dragged go to their poles
and the lines join each pole to its joint.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkInteractionWidgets import vtkSphereWidget
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

from gsik_studio.scene import line_cells, points_view, sphere_widget, touch

POLE_COLOR = (0.70, 0.45, 1.00)
POLE_SELECTED_COLOR = (0.88, 0.75, 1.00)
POLE_RADIUS = 0.026  # [m]


class PoleGizmos:
    """Sphere widgets for a document's pole targets, drawn over the body.

    Args:
        viewport: The viewport (its plotter's interactor, its document).
        overlay: The renderer drawn over the body (:func:`gsik_studio.body_view.overlay_renderer`).
    """

    def __init__(self, viewport, overlay):
        self.doc = viewport.doc
        self.controls = viewport.doc.controls
        self.dragging: str | None = None
        self._drag = object()  # one token per mouse drag: its moves are one undo step
        pl = viewport.plotter
        self.widgets: dict[str, vtkSphereWidget] = {}
        for name in self.controls.pole_joints:
            w = sphere_widget(pl, POLE_RADIUS, POLE_COLOR, POLE_SELECTED_COLOR, (14, 10))
            w.SetCurrentRenderer(overlay)  # drawn (and picked) over the body
            w.AddObserver("StartInteractionEvent", lambda _w, _e, n=name: self._start(n))
            w.AddObserver("InteractionEvent",
                          lambda w_, _e, n=name: self.controls.move_pole(n, w_.GetCenter(), self._drag))
            w.AddObserver("EndInteractionEvent", lambda _w, _e: self._end())
            self.widgets[name] = w
        n = len(self.widgets)
        self._lines = pv.PolyData(np.zeros((2 * n, 3)), lines=line_cells(np.arange(2 * n).reshape(-1, 2)))
        self._lines_xyz = points_view(self._lines)
        mapper = vtkPolyDataMapper()
        mapper.SetInputData(self._lines)
        self.lines = vtkActor()
        self.lines.SetMapper(mapper)
        prop = self.lines.GetProperty()
        prop.SetColor(POLE_COLOR)
        prop.SetLineWidth(1.5)
        prop.SetLighting(False)
        self.lines.VisibilityOff()
        overlay.AddActor(self.lines)
        viewport.layers.append(self)
        self.controls.changed.connect(self.sync)
        self.sync()  # a document opened before the window may have poles on

    def _start(self, name: str) -> None:
        self.dragging, self._drag = name, object()

    def _end(self) -> None:
        self.dragging = None
        self.doc.end_drag()

    def sync(self) -> None:
        """Show a sphere on each pole target and a line to its joint (hide them while poles are off)."""
        poles = self.controls.poles
        for k, (name, w) in enumerate(self.widgets.items()):
            t = poles.get(name)
            if t is None:
                if w.GetEnabled():
                    w.Off()
                self._lines_xyz[2 * k:2 * k + 2] = 0.0  # a line of no length
                continue
            if name != self.dragging:
                w.SetCenter(*t.position)
            if not w.GetEnabled():
                w.On()
            self._lines_xyz[2 * k] = self.controls.joint_position(name)
            self._lines_xyz[2 * k + 1] = w.GetCenter()
        touch(self._lines)
        self.lines.SetVisibility(bool(poles))

    def refresh(self, P=None, R=None) -> None:
        if self.controls.poles:
            self.sync()
