"""The document's timeline: a clip (a walk, a scenario, an imported BVH) or keyed poses, played from the wall clock.

Plain Python. The frame shown while playing is chosen from the clock
(``frame = start_frame + elapsed / frame_time``), so a slow machine drops
frames instead of slowing the motion down. The clip stays on the timeline
after it played (scrub it, play it again) until :meth:`Timeline.discard`.
Keys are baked in chunks (:class:`gsik_studio.model.bake.KeyedBake`): each
play tick bakes :data:`BAKE_FRAMES_PER_TICK` frames, and a frame shown before
it is baked is solved on its own, so Play never blocks for long.

Every stretch of frames shown (one play until pause or stop, one scrub) is a
:class:`gsik_studio.model.playback.Playback` of the document: an edit, undo or
load interrupts it, and it is recorded as one undo step.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, NamedTuple

from gsik import validate
from gsik.anim.motion import Motion
from gsik.errors import GsikError
from gsik.io.pose.model import MAX_FPS
from gsik.io.pose.sequence import MAX_SEQUENCE_FRAMES
from gsik.io.pose import Pose
from gsik.targets import Target
from gsik_studio.model.events import Signal
from gsik_studio.model.bake import KeyedBake
from gsik_studio.model.keys import bake_target_frames

if TYPE_CHECKING:
    from gsik_studio.model.document import Document
    from gsik_studio.model.playback import Playback

#: Frame time of keyed sequences [s] (30 frames per second), unless a file says otherwise.
KEY_FRAME_TIME = 1 / 30

#: Frames of the keys baked per play tick (about 4 ms of solving unloaded): Play never solves the whole sequence in
#: one go, yet the bake runs ahead of the clock whenever a tick shows fewer than 8 new frames.
BAKE_FRAMES_PER_TICK = 8

#: Frames of a new document's timeline (3 s at 30 fps): room to key poses before any clip is loaded.
DEFAULT_LENGTH = 90


class TimelineState(NamedTuple):
    """What a document keeps of its timeline (immutable: the undo history and pose files hold it).

    Attributes:
        clip: The motion on the timeline, or None.
        name: The clip's name ("" without a clip).
        keys: ``((frame, Pose), ...)`` keyed poses in frame order.
        fps: Frames per second of the keys' timeline.
        length: Frames of the keys' timeline (at least 1, and past the last key).
    """

    clip: Motion | None = None
    name: str = ""
    keys: tuple[tuple[int, Pose], ...] = ()
    fps: float = 1 / KEY_FRAME_TIME
    length: int = DEFAULT_LENGTH


class TimelineEvents:
    """Signals of a :class:`Timeline` (no arguments).

    Attributes:
        frame: The current frame changed.
        content: The clip or the keys changed (length, key marks).
        state: Playing, paused or looping changed.
    """

    __slots__ = ("frame", "content", "state")

    def __init__(self):
        for name in self.__slots__:
            setattr(self, name, Signal())


class Timeline:
    """A clip or a key sequence on a document, with play, pause, stop, loop and scrub.

    Args:
        doc: The document whose pose shows the current frame.
        clock: Seconds from a monotonic clock (tests pass a fake one).

    Attributes:
        clip: The motion on the timeline (None: the keys play, if any).
        name: The clip's name (undo texts: "Walk", "Scrub Walk").
        keys: ``{frame: Pose}`` keyed poses (used when there is no clip).
        key_fps: Frames per second of the keys' timeline (shown when there is no clip).
        key_length: Frames of the keys' timeline (at least 1, past the last key), with or without keys.
        frame: The current frame index.
        playing: True while the clock moves the frame.
        loop: True to start over at the end instead of stopping there.
    """

    def __init__(self, doc: Document, clock: Callable[[], float] = time.perf_counter):
        self.doc = doc
        self.clock = clock
        self.events = TimelineEvents()
        self.clip: Motion | None = None
        self.name = ""
        self.keys: dict[int, Pose] = {}
        self.key_fps, self.key_length = TimelineState().fps, TimelineState().length
        self.frame = 0
        self.playing = False
        self.loop = False
        self._bake: KeyedBake | None = None  # the keys baked so far, until they change
        self._session: Playback | None = None
        self._start = (0.0, 0)  # (clock, frame) when playing started

    # -- content ------------------------------------------------------------------------
    @property
    def bake(self) -> KeyedBake | None:
        """The keys' bake (frames solved so far kept until the keys, length or fps change); None without keys."""
        if self.keys and self._bake is None:
            self._bake = KeyedBake(self.doc.skeleton, self.doc.settings, self.keys, 1 / self.key_fps,
                                   n_frames=self.key_length)
        return self._bake if self.keys else None

    @property
    def source(self) -> Motion | KeyedBake | None:
        """What plays: the clip, else the keys' bake (frames solved as shown), else None."""
        return self.clip if self.clip is not None else self.bake

    @property
    def motion(self) -> Motion | None:
        """The clip, else the keys as a motion (baking every frame left in one go: the window steps
        :attr:`bake` in chunks first), else None."""
        source = self.source
        return source.finish() if isinstance(source, KeyedBake) else source

    @property
    def n_frames(self) -> int:
        """Frames on the timeline: the clip's, else the keys' timeline length (always past the last key)."""
        if self.clip is not None:
            return self.clip.n_frames
        return max([*self.keys, self.key_length - 1, 0]) + 1

    @property
    def frame_time(self) -> float:
        """Seconds per frame [s]."""
        return float(self.clip.frame_time) if self.clip is not None else 1 / self.key_fps

    def load(self, motion: Motion, name: str, text: str | None = None) -> None:
        """Put a motion on the timeline (replacing any clip), at frame 0, not playing: one undo step (``text``)."""
        if motion.skeleton.name != self.doc.skeleton.name:
            raise GsikError(f"motion is for skeleton {motion.skeleton.name!r}, not {self.doc.skeleton.name!r}")
        self._change(text or f"Load {name}", clip=motion, name=name, frame=0)

    def load_target_frames(self, frames: Sequence[Mapping[str, Target | None]], name: str,
                           frame_time: float) -> None:
        """Solve target frames from the document's pose (one solver step each, as live) and load them."""
        self.load(bake_target_frames(self.doc.skeleton, self.doc.settings, self.doc.pose(), frames, frame_time),
                  name)

    def discard(self) -> None:
        """Take the clip off the timeline (the pose shown stays): one undo step."""
        if self.clip is not None:  # the keys' timeline (length, fps, keys) shows again
            self._change(f"Discard {self.name or 'clip'}", clip=None, name="")

    # -- state kept in the document ----------------------------------------------------------
    def snapshot(self) -> TimelineState:
        """What the document keeps of the timeline (undo and pose files)."""
        return TimelineState(self.clip, self.name, tuple(sorted(self.keys.items())), self.key_fps, self.key_length)

    def restore(self, state: TimelineState) -> None:
        """Show ``state`` (undo, redo, a file opened); no undo step. The current frame stays on the timeline."""
        if state != self.snapshot():
            self._set(state)
            self.events.content.emit()

    def _set(self, state: TimelineState, frame: int | None = None) -> None:
        """Take ``state`` (not playing), and the current ``frame`` if given (kept on the timeline)."""
        self.pause()
        if (tuple(sorted(self.keys.items())), self.key_length, self.key_fps) != (state.keys, state.length, state.fps):
            self._bake = None
        self.clip, self.name, self.keys = state.clip, state.name, dict(state.keys)
        self.key_fps, self.key_length = state.fps, state.length
        self.frame = min(self.frame if frame is None else frame, self.n_frames - 1)

    def _change(self, text: str, frame: int | None = None, **fields) -> None:
        """Replace fields of :meth:`snapshot` (and the current frame) as one undo step of the document."""
        state = self.snapshot()._replace(**fields)
        self.doc._edit(text, lambda: self._set(state, frame), signal=self.events.content)

    # -- keys -----------------------------------------------------------------------------
    def add_key(self, frame: int | None = None) -> int:
        """Key the document's pose at ``frame`` (default: the current frame); returns the frame. One undo step."""
        if self.clip is not None:
            raise GsikError(f"the timeline holds the clip {self.name!r}: discard it before keying poses")
        f = self.frame if frame is None else self._check_frame(frame)
        self._change(f"Add key at frame {f}", keys=tuple(sorted({**self.keys, f: self.doc.pose()}.items())),
                     length=max(self.key_length, f + 1))
        return f

    def move_key(self, old: int, new: int) -> None:
        """Move the key at frame ``old`` to frame ``new`` (replacing a key there). One undo step."""
        pose = self._key(old)
        new = self._check_frame(new)
        if new != old:
            keys = {f: p for f, p in self.keys.items() if f != old}
            self._change(f"Move key {old} to {new}", keys=tuple(sorted({**keys, new: pose}.items())),
                         length=max(self.key_length, new + 1))

    def delete_key(self, frame: int) -> None:
        """Delete the key at ``frame``. One undo step."""
        self._key(frame)
        self._change(f"Delete key at frame {frame}", keys=tuple((f, p) for f, p in sorted(self.keys.items())
                                                                 if f != frame))

    def set_length(self, frames: int) -> None:
        """Frames of the keys' timeline (whole, at least 1 and past the last key): one undo step.

        Raises:
            GsikError: a length that is not a whole number in range, or one that would cut off a key.
        """
        need = max(self.keys, default=0) + 1
        n = validate.whole(frames, "the timeline's length" + (f" (a key is at frame {need - 1})" if self.keys else ""),
                           GsikError, minimum=need, floats=True, maximum=MAX_SEQUENCE_FRAMES)
        if n != self.key_length:
            self._change(f"Set timeline length to {n} frames", length=n)

    def set_fps(self, fps: float) -> None:
        """Frames per second of the keys' timeline (above 0, at most :data:`MAX_FPS`): one undo step."""
        fps = validate.positive(fps, "the timeline's frames per second", GsikError)
        if fps > MAX_FPS:
            raise GsikError(f"the timeline's frames per second must be at most {MAX_FPS:g}, got {fps!r}")
        if fps != self.key_fps:
            self._change(f"Set timeline to {fps:g} fps", fps=fps)

    def step_frame(self, delta: int) -> None:
        """Show the frame ``delta`` frames on (negative: back), clamped to the timeline; one scrub."""
        self.scrub(self.frame + int(delta))
        self.end_scrub()

    def jump_to_key(self, direction: int) -> None:
        """Show the next key after the current frame (``direction`` > 0) or the one before it (< 0), if any."""
        keys = [k for k in sorted(self.keys) if (k > self.frame if direction > 0 else k < self.frame)]
        if keys:
            self.scrub(keys[0] if direction > 0 else keys[-1])
            self.end_scrub()

    def _key(self, frame: int) -> Pose:
        if frame not in self.keys:
            raise GsikError(f"no key at frame {frame}; keys at {sorted(self.keys) or 'no frame'}")
        return self.keys[frame]

    @staticmethod
    def _check_frame(frame: int) -> int:
        """A key's frame: a whole number below the bound pose files keep (past the timeline's end is fine)."""
        return validate.whole(frame, "a key's frame", GsikError, floats=True, maximum=MAX_SEQUENCE_FRAMES - 1)

    # -- transport ------------------------------------------------------------------------
    def _open_session(self, text: str) -> Playback | None:
        """The playback that shows frames (a new one if none runs); None when there is nothing to play."""
        m = self.source
        if m is None:
            return None
        if self._session is None or self._session.finished:
            self._session = self.doc.playback(m, text, m.frame_time)
        return self._session

    def _close_session(self) -> None:
        if self._session is not None:
            session, self._session = self._session, None
            session.stop()  # recorded as one undo step

    def _show(self, frame: int) -> None:
        self.frame = frame
        self._session.show(frame)
        self.events.frame.emit()

    def play(self) -> bool:
        """Start playing from the current frame (from 0 when at the end); False when there is nothing to play."""
        if self.playing:
            return True
        if self.source is None:
            return False
        if self.frame >= self.n_frames - 1:
            self.frame = 0
        self._close_session()
        self._open_session(self.name or "Play keys")
        self._show(self.frame)
        self._start = (self.clock(), self.frame)
        self.playing = True
        self.events.state.emit()
        return True

    def pause(self) -> None:
        """Stop the clock on the current frame (what was played is one undo step)."""
        self._close_session()
        if self.playing:
            self.playing = False
            self.events.state.emit()

    def stop(self) -> None:
        """Stop playing and go back to the first frame (one undo step)."""
        if self._open_session(f"Stop {self.name or 'keys'}") is not None:
            self._show(0)
        self.pause()

    def set_loop(self, on: bool) -> None:
        self.loop = bool(on)
        self.events.state.emit()

    def scrub(self, frame: int) -> None:
        """Show ``frame`` (clamped into the timeline); while playing, play on from there."""
        f = min(max(int(frame), 0), self.n_frames - 1)
        if self._open_session(f"Scrub {self.name or 'keys'}") is None:
            self.frame = f
            self.events.frame.emit()
            return
        self._show(f)
        if self.playing:
            self._start = (self.clock(), f)

    def end_scrub(self) -> None:
        """The slider was let go: the frames scrubbed become one undo step (unless playing on)."""
        if not self.playing:
            self._close_session()

    def frame_now(self) -> int:
        """The frame the clock says should be shown now (past the end when not looping)."""
        t0, f0 = self._start
        f = f0 + math.floor((self.clock() - t0) / self.frame_time + 1e-9)
        return f % self.n_frames if self.loop else f

    def tick(self) -> bool:
        """Show the frame the clock says (dropping any in between); False when playing ended."""
        if not self.playing:
            return False
        if self._session is None or self._session.finished:  # an edit or undo interrupted it
            self._session = None
            self.pause()
            return False
        if self.clip is None and self.bake is not None:
            self.bake.step(BAKE_FRAMES_PER_TICK)
        f = self.frame_now()
        if f >= self.n_frames:
            self._show(self.n_frames - 1)  # the last frame stays: no snapping back
            self.pause()
            return False
        if f != self.frame:
            self._show(f)
        return True
