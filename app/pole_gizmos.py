"""Pole targets for knees and elbows as small gizmos: one small violet sphere widget per pole, drag to bend.

Built once (hidden while pole targets are off); a drag moves the pole
through :meth:`gsik_studio.model.pins.SolveControls.move_pole` (one undo step per drag). A viewport layer:
each frame the spheres not being dragged go to their poles.
"""

from __future__ import annotations

from vtkmodules.vtkInteractionWidgets import vtkSphereWidget

from gsik_studio.scene import sphere_widget

POLE_COLOR = (0.70, 0.45, 1.00)
POLE_SELECTED_COLOR = (0.88, 0.75, 1.00)
POLE_RADIUS = 0.022  # [m]


class PoleGizmos:
    """Sphere widgets for a document's pole targets.

    Args:
        viewport: The viewport (its plotter's interactor and renderer, its document).
    """

    def __init__(self, viewport):
        self.doc = viewport.doc
        self.controls = viewport.doc.controls
        self.dragging: str | None = None
        self._drag = object()  # one token per mouse drag: its moves are one undo step
        pl = viewport.plotter
        self.widgets: dict[str, vtkSphereWidget] = {}
        for name in self.controls.pole_joints:
            w = sphere_widget(pl, POLE_RADIUS, POLE_COLOR, POLE_SELECTED_COLOR, (14, 10))
            w.AddObserver("StartInteractionEvent", lambda _w, _e, n=name: self._start(n))
            w.AddObserver("InteractionEvent",
                          lambda w_, _e, n=name: self.controls.move_pole(n, w_.GetCenter(), self._drag))
            w.AddObserver("EndInteractionEvent", lambda _w, _e: self._end())
            self.widgets[name] = w
        viewport.layers.append(self)
        self.controls.changed.connect(self.sync)
        self.sync()  # a document opened before the window may have poles on

    def _start(self, name: str) -> None:
        self.dragging, self._drag = name, object()

    def _end(self) -> None:
        self.dragging = None
        self.doc.end_drag()

    def sync(self) -> None:
        """Show a sphere on each pole target (hide them while poles are off)."""
        poles = self.controls.poles
        for name, w in self.widgets.items():
            t = poles.get(name)
            if t is None:
                if w.GetEnabled():
                    w.Off()
                continue
            if name != self.dragging:
                w.SetCenter(*t.position)
            if not w.GetEnabled():
                w.On()

    def refresh(self, P=None, R=None) -> None:
        if self.controls.poles and self.dragging is None:
            self.sync()
