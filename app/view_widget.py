"""The 3D view's Qt widget: a ``pyvistaqt.QtInteractor`` that renders once per event-loop turn.

VTK's widgets and interactor styles render the window themselves on every
interaction event (``vtkRenderWindowInteractor::Render``), and the app renders
again when it redraws the frame: two or more renders per mouse event. Here the
interactor's own renders are switched off and turned into a Qt ``update()``,
which Qt merges with the app's into one paint, so the window renders at most
once per turn of the event loop whatever asks for it.

The widget also takes the keyboard focus when the pointer moves over it, so
single-key view shortcuts typed with the pointer over the view go to the view
and never into a spin box of the side panel that happened to have focus.
"""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtCore, QtGui
from pyvistaqt import QtInteractor


class ViewWidget(QtInteractor):
    """A ``QtInteractor`` with coalesced rendering and focus that follows the pointer in.

    Attributes:
        renders: How many times the scene was rendered (for benchmarks and tests).
        snap_press: ``f(x, y) -> (dx, dy)`` in display pixels (origin bottom-left): a left press is moved by
            this offset, and so is the drag that follows until the release (a click just off a target grabs it).
    """

    snap_press: Callable[[float, float], tuple[float, float]] | None = None

    def __init__(self, parent=None, **kwargs):
        super().__init__(parent, **kwargs)
        self.renders = 0
        self._offset: QtCore.QPointF | None = None  # the snapped press's shift, until the release
        self._painting = False
        iren = self.iren.interactor
        iren.EnableRenderOff()  # interaction events only ask for a paint (RenderEvent below)
        iren.AddObserver("RenderEvent", self._on_render_event)
        self.installEventFilter(self)
        self.setFocusPolicy(QtCore.Qt.StrongFocus)
        self.setMouseTracking(True)

    def eventFilter(self, obj, ev):  # noqa: N802 (Qt's name)
        """A paint renders (the base class's paintEvent calls the interactor's Render): allow that one."""
        if obj is self and ev.type() == QtCore.QEvent.Paint and not getattr(self, "_closed", False):
            self._painting = True
            self.iren.interactor.EnableRenderOn()
        return False

    def _on_render_event(self, *_) -> None:
        if self._painting:  # this paint's own render: done; back to asking for paints
            self._painting = False
            self.iren.interactor.EnableRenderOff()
            self.renders += 1
        else:
            self.update()

    def enterEvent(self, ev):  # noqa: N802 (Qt's name)
        self._take_focus()
        super().enterEvent(ev)

    def mouseMoveEvent(self, ev):  # noqa: N802 (Qt's name)
        self._take_focus()
        super().mouseMoveEvent(self._shifted(ev))

    def mousePressEvent(self, ev):  # noqa: N802 (Qt's name)
        if ev.button() == QtCore.Qt.LeftButton and self.snap_press is not None:
            ratio = self.devicePixelRatioF()
            p = ev.position()
            dx, dy = self.snap_press(p.x() * ratio, (self.height() - p.y() - 1) * ratio)
            self._offset = QtCore.QPointF(dx / ratio, -dy / ratio) if (dx or dy) else None
        super().mousePressEvent(self._shifted(ev))

    def mouseReleaseEvent(self, ev):  # noqa: N802 (Qt's name)
        super().mouseReleaseEvent(self._shifted(ev))
        if ev.button() == QtCore.Qt.LeftButton:
            self._offset = None

    def _shifted(self, ev):
        if self._offset is None:
            return ev
        return QtGui.QMouseEvent(ev.type(), ev.position() + self._offset, ev.globalPosition() + self._offset,
                                 ev.button(), ev.buttons(), ev.modifiers())

    def _take_focus(self) -> None:
        if not self.hasFocus():
            self.setFocus(QtCore.Qt.MouseFocusReason)
