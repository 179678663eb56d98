"""The timeline bar: transport buttons, a frame slider with key marks, bound to a document's :class:`Timeline`.

Thin: every button calls one timeline method; the bar redraws itself on the
timeline's typed events (``frame``, ``content``, ``state``) inside signal
blockers, so showing a value never writes it back.
"""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtCore, QtGui, QtWidgets
from PySide6.QtCore import Qt

from gsik.io.pose.model import MAX_FPS
from gsik.io.pose.sequence import MAX_SEQUENCE_FRAMES
from gsik_studio.model.timeline import Timeline
from gsik_studio.widgets.fields import guard_wheel

S = QtWidgets.QStyle
LENGTH_TIP = "Frames on the timeline: key poses anywhere on it (a clip shows its own)"
FPS_TIP = "Frames per second the keyed poses play at"
KEY_COLOR = QtGui.QColor("#f0c040")
KEY_GRAB_PX = 6  # a press this close to a key mark drags the key


class FrameSlider(QtWidgets.QSlider):
    """A horizontal slider whose click jumps to the frame under the pointer, with key marks under the groove.

    Dragging a key mark moves the key (``key_moved(old, new)``); anything
    else scrubs (``scrubbed(frame)``, then ``released()``).
    """

    scrubbed = QtCore.Signal(int)
    released = QtCore.Signal()
    key_moved = QtCore.Signal(int, int)

    def __init__(self, parent: QtWidgets.QWidget | None = None):
        super().__init__(Qt.Horizontal, parent)
        self.keys: list[int] = []
        self._dragging_key: int | None = None
        self.setMinimumHeight(34)
        self.setMinimumWidth(150)  # the bar fits a 900 px wide window beside its transport and fields

    def x_of(self, frame: int) -> int:
        """Widget x [px] of a frame's position on the groove."""
        opt = QtWidgets.QStyleOptionSlider()
        self.initStyleOption(opt)
        handle = self.style().subControlRect(S.CC_Slider, opt, S.SC_SliderHandle, self)
        span = self.width() - handle.width()
        pos = S.sliderPositionFromValue(self.minimum(), self.maximum(), frame, span)
        return pos + handle.width() // 2

    def frame_at(self, x: float) -> int:
        opt = QtWidgets.QStyleOptionSlider()
        self.initStyleOption(opt)
        handle = self.style().subControlRect(S.CC_Slider, opt, S.SC_SliderHandle, self)
        span = self.width() - handle.width()
        return S.sliderValueFromPosition(self.minimum(), self.maximum(), int(x - handle.width() // 2), span)

    def _key_near(self, x: float) -> int | None:
        near = [k for k in self.keys if abs(self.x_of(k) - x) <= KEY_GRAB_PX]
        return min(near, key=lambda k: abs(self.x_of(k) - x)) if near else None

    def mousePressEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802 (Qt's name)
        if event.button() != Qt.LeftButton:
            return super().mousePressEvent(event)
        x = event.position().x()
        self._dragging_key = self._key_near(x) if event.position().y() > self.height() / 2 else None
        if self._dragging_key is None:
            self.scrubbed.emit(self.frame_at(x))
        event.accept()

    def mouseMoveEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802 (Qt's name)
        if event.buttons() & Qt.LeftButton and self._dragging_key is None:
            self.scrubbed.emit(self.frame_at(event.position().x()))
        event.accept()

    def mouseReleaseEvent(self, event: QtGui.QMouseEvent) -> None:  # noqa: N802 (Qt's name)
        if event.button() != Qt.LeftButton:
            return super().mouseReleaseEvent(event)
        if self._dragging_key is not None:
            old, self._dragging_key = self._dragging_key, None
            new = self.frame_at(event.position().x())
            if new != old:
                self.key_moved.emit(old, new)
        else:
            self.released.emit()
        event.accept()

    def paintEvent(self, event: QtGui.QPaintEvent) -> None:  # noqa: N802 (Qt's name)
        super().paintEvent(event)
        if not self.keys:
            return
        p = QtGui.QPainter(self)
        p.setRenderHint(QtGui.QPainter.Antialiasing)
        p.setBrush(KEY_COLOR)
        p.setPen(Qt.NoPen)
        y = self.height() - 7
        for k in self.keys:
            x = self.x_of(k)
            p.drawPolygon(QtGui.QPolygonF([QtCore.QPointF(x, y - 5), QtCore.QPointF(x + 5, y),
                                           QtCore.QPointF(x, y + 5), QtCore.QPointF(x - 5, y)]))
        p.end()


#: (name, icon, tooltip) of the bar's buttons, left to right
BUTTONS = (
    ("play", S.SP_MediaPlay, "Play or pause the timeline"),
    ("stop", S.SP_MediaStop, "Stop and go back to the first frame"),
    ("loop", S.SP_BrowserReload, "Loop: start over at the end"),
    ("previous_key", S.SP_MediaSkipBackward, "Go to the key before the current frame (Shift+Left)"),
    ("previous_frame", S.SP_MediaSeekBackward, "One frame back (Left)"),
    ("next_frame", S.SP_MediaSeekForward, "One frame on (Right)"),
    ("next_key", S.SP_MediaSkipForward, "Go to the key after the current frame (Shift+Right)"),
    ("key", S.SP_DialogApplyButton, "Key the current pose at the current frame (K)"),
    ("delete_key", S.SP_DialogDiscardButton, "Delete the key at the current frame"),
    ("discard", S.SP_TrashIcon, "Discard the clip from the timeline (the pose stays)"),
)


class TimelineBar(QtWidgets.QWidget):
    """Transport buttons, the frame slider and a frame read-out for one :class:`Timeline`.

    Args:
        timeline: The document's timeline.
        report: ``(text)`` shown to the user when a command is refused.
    """

    def __init__(self, timeline: Timeline, report: Callable[[str], None],
                 parent: QtWidgets.QWidget | None = None):
        super().__init__(parent)
        self.timeline, self._report = timeline, report
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(6, 2, 6, 2)
        self.buttons: dict[str, QtWidgets.QToolButton] = {}
        for name, icon, tip in BUTTONS:
            b = QtWidgets.QToolButton()
            b.setIcon(self.style().standardIcon(icon))
            b.setToolTip(tip)
            b.setObjectName(f"timeline_{name}")
            b.setCheckable(name in ("play", "loop"))
            layout.addWidget(b)
            self.buttons[name] = b
        self.slider = FrameSlider()
        layout.addWidget(self.slider, 1)
        self.label = QtWidgets.QLabel()
        self.label.setMinimumWidth(170)
        self.label.setFont(QtGui.QFontDatabase.systemFont(QtGui.QFontDatabase.FixedFont))
        layout.addWidget(self.label)
        self.length = _spin(QtWidgets.QSpinBox, 1, MAX_SEQUENCE_FRAMES, " frames", LENGTH_TIP)
        self.fps = _spin(QtWidgets.QDoubleSpinBox, 1, MAX_FPS, " fps", FPS_TIP)
        for w in (self.length, self.fps):
            layout.addWidget(w)
        self._connect()
        self.wheel_guard = guard_wheel(self)  # the wheel changes the length or fps only once clicked into
        self.show_content()

    def _connect(self) -> None:
        tl, b = self.timeline, self.buttons
        b["play"].toggled.connect(lambda on: self._run(tl.play) if on else tl.pause())
        b["stop"].clicked.connect(tl.stop)
        b["loop"].toggled.connect(tl.set_loop)
        b["key"].clicked.connect(lambda: self._run(tl.add_key))
        b["delete_key"].clicked.connect(lambda: self._run(lambda: tl.delete_key(tl.frame)))
        b["discard"].clicked.connect(tl.discard)
        for name, command in (("previous_key", lambda: tl.jump_to_key(-1)), ("previous_frame", lambda: tl.step_frame(-1)),
                              ("next_frame", lambda: tl.step_frame(1)), ("next_key", lambda: tl.jump_to_key(1))):
            b[name].clicked.connect(command)
        self.length.valueChanged.connect(lambda n: self._run(lambda: tl.set_length(n)))
        self.fps.valueChanged.connect(lambda fps: self._run(lambda: tl.set_fps(fps)))
        self.slider.scrubbed.connect(tl.scrub)
        self.slider.released.connect(tl.end_scrub)
        self.slider.key_moved.connect(lambda old, new: self._run(lambda: tl.move_key(old, new)))
        tl.events.frame.connect(self.show_frame)
        tl.events.content.connect(self.show_content)
        tl.events.state.connect(self.show_state)

    def _run(self, command: Callable[[], object]) -> None:
        """Run a timeline command; a refusal is reported, not raised."""
        from gsik.errors import GsikError

        try:
            ok = command()
        except GsikError as exc:
            self._report(str(exc))
            self.show_content()  # a refused length or fps shows the timeline's own again
            ok = None
        if ok is False:
            self._report("Nothing to play: walk, load a scenario, import a clip or key a pose first")
        self.show_state()

    def show_content(self) -> None:
        tl = self.timeline
        with QtCore.QSignalBlocker(self.slider):
            self.slider.setRange(0, tl.n_frames - 1)
        self.slider.keys = sorted(tl.keys)
        has_clip = tl.clip is not None
        self.buttons["discard"].setEnabled(has_clip)
        self.buttons["key"].setEnabled(not has_clip)
        self.buttons["delete_key"].setEnabled(bool(tl.keys) and not has_clip)
        for w, value in ((self.length, tl.n_frames), (self.fps, 1 / tl.frame_time)):
            with QtCore.QSignalBlocker(w):
                w.setValue(value)
            w.setEnabled(not has_clip)  # a clip has its own frames; the keys' timeline shows again once discarded
        self.slider.update()
        self.show_frame()

    def show_frame(self) -> None:
        tl = self.timeline
        if tl.n_frames - 1 != self.slider.maximum():
            self.show_content()
            return
        with QtCore.QSignalBlocker(self.slider):
            self.slider.setValue(tl.frame)
        what = tl.name or ("keys" if tl.keys else "empty")
        self.label.setText(f"{what}  {tl.frame:4d}/{tl.n_frames - 1}  {tl.frame * tl.frame_time:5.2f} s")

    def show_state(self) -> None:
        tl = self.timeline
        for name, on in (("play", tl.playing), ("loop", tl.loop)):
            with QtCore.QSignalBlocker(self.buttons[name]):
                self.buttons[name].setChecked(on)
        self.buttons["play"].setIcon(self.style().standardIcon(S.SP_MediaPause if tl.playing else S.SP_MediaPlay))


def _spin(kind, lo: float, hi: float, suffix: str, tip: str) -> QtWidgets.QAbstractSpinBox:
    """A spin box for the timeline's length or fps: one value per finished entry."""
    w = kind()
    w.setRange(lo, hi)
    w.setSuffix(suffix)
    w.setToolTip(tip)
    w.setKeyboardTracking(False)
    if isinstance(w, QtWidgets.QDoubleSpinBox):
        w.setDecimals(2)
    return w
