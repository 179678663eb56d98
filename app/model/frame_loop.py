"""The studio's per-frame work, outside Qt: the window's timers drive it, and so does the app benchmark.

Each frame either shows the next playback frame or steps the solver once,
then says so (``events.frame``: redraw the scene); the panel and status
read-outs are told at most every ``readout_interval`` seconds
(``events.readouts``), because Qt label updates cost more than a frame's solve.
"""

from __future__ import annotations

import collections
import time
from collections.abc import Mapping, Sequence

import gsik
from gsik.anim.motion import Motion
from gsik_studio.model.document import Document
from gsik_studio.model.events import Signal
from gsik_studio.model.playback import Playback

READOUT_INTERVAL_S = 0.25  # panel and status texts refresh at most this often


class LoopEvents:
    """Signals of a :class:`FrameLoop`.

    Attributes:
        frame: A solver step changed the pose (redraw the scene; playback frames say ``doc.events.pose``).
        readouts: Time to refresh the read-outs (throttled).
        wake: Frames are needed again (start the clock that calls the loop).
        message: ``(text)`` something the user should read (a playback that failed).
    """

    __slots__ = ("frame", "readouts", "wake", "message")

    def __init__(self):
        for name in self.__slots__:
            setattr(self, name, Signal())


class FrameLoop:
    """Steps a :class:`Document` frame by frame: playback frames, solver steps, read-out throttling.

    Args:
        doc: The document.
        readout_interval: Least time [s] between two ``events.readouts``.

    Attributes:
        paused: True stops solving (playback is not paused).
    """

    def __init__(self, doc: Document, readout_interval: float = READOUT_INTERVAL_S):
        self.doc = doc
        self.events = LoopEvents()
        self.paused = False
        self.readout_interval = readout_interval
        self._frame_times: collections.deque[float] = collections.deque(maxlen=120)
        self._last_readout = float("-inf")
        for signal in (doc.events.pose, doc.events.targets, doc.events.options, doc.events.settings):
            signal.connect(self.wake)

    @property
    def playback(self) -> Playback | None:
        return self.doc.playing

    @property
    def solving(self) -> bool:
        """True while solver frames are wanted (not paused, no playback, the pose not settled)."""
        return not self.paused and self.doc.playing is None and self.doc.needs_solving

    @property
    def running(self) -> bool:
        """True while any frames are wanted (solving or playing)."""
        return self.solving or self.doc.playing is not None

    def wake(self) -> None:
        """Say ``events.wake`` if solver frames are wanted."""
        if self.solving:
            self.events.wake.emit()

    def set_paused(self, paused: bool) -> None:
        self.paused = bool(paused)
        self.wake()
        self.readouts_now()

    def solve_frame(self) -> bool:
        """One solver frame if one is wanted; False when none is (the clock may stop)."""
        if not self.solving:
            self.readouts_now()
            return False
        self.doc.step()
        self.events.frame.emit()
        self._frame_done()
        if not self.doc.needs_solving:
            self.readouts_now()
            return False
        return True

    def play(self, frames: Motion | Sequence[Mapping], text: str = "Play", frame_time: float = 1 / 30) -> Playback:
        """Start playing a motion or target frames (see :meth:`Document.playback`)."""
        pb = self.doc.playback(frames, text, frame_time)
        self.readouts_now()
        return pb

    def play_frame(self) -> bool:
        """Show the next playback frame; False when the playback ended (or failed: ``events.message``)."""
        pb = self.doc.playing
        try:
            more = pb is not None and pb.advance()
        except gsik.GsikError as exc:
            self.events.message.emit(f"Playback stopped: {exc}")
            more = False
        if not more:
            self.stop_playback()
            return False
        self._frame_done()  # the document's pose event has redrawn the scene
        return True

    def stop_playback(self) -> None:
        """End a running playback (recorded as one undo step) and go back to solving."""
        if self.doc.playing is not None:
            self.doc.playing.stop()
        self.wake()

    def _frame_done(self) -> None:
        now = time.perf_counter()
        self._frame_times.append(now)
        if now - self._last_readout >= self.readout_interval:
            self.readouts_now()

    def readouts_now(self) -> None:
        """Say ``events.readouts`` now (after a change the user should see at once)."""
        self._last_readout = time.perf_counter()
        self.events.readouts.emit()

    @property
    def fps(self) -> float:
        """Frames per second over the last second."""
        now = time.perf_counter()
        recent = [t for t in self._frame_times if now - t <= 1.0]
        if len(recent) < 2:
            return 0.0
        return (len(recent) - 1) / max(recent[-1] - recent[0], 1e-9)
