"""Playing a motion or a sequence of target frames onto a document, recorded as one undo step."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import gsik
from gsik.anim.motion import Motion
from gsik_studio.model.bake import KeyedBake, motion_frame

if TYPE_CHECKING:
    from gsik_studio.model.document import Document


class Playback:
    """Plays frames onto a document through its public methods, then records the result as one undo step.

    A frame is either a frame of a :class:`gsik.anim.motion.Motion` or of a
    :class:`gsik_studio.model.bake.KeyedBake` (angles, root and root transform
    shown directly; a bake solves the frame when asked) or a dict of targets
    (shown, then the solver steps). Call :meth:`advance` once per frame (the frame loop does it
    every :attr:`frame_time` seconds) until it returns False, or :meth:`stop`
    to end early; the played result is then one command (``text``) that undo
    takes back to :attr:`before`, the pose before playing.
    """

    def __init__(self, doc: Document, frames, text: str, frame_time: float):
        self.doc = doc
        self.text = text
        if isinstance(frames, (Motion, KeyedBake)):
            if frames.skeleton.name != doc.skeleton.name:
                raise gsik.GsikError(f"motion is for skeleton {frames.skeleton.name!r}, not {doc.skeleton.name!r}")
            self.motion: Motion | KeyedBake | None = frames
            self.target_frames: Sequence = ()
            self.n_frames = frames.n_frames
            self.frame_time = float(frames.frame_time)  # [s]
        else:
            self.motion = None
            self.target_frames = list(frames)
            self.n_frames = len(self.target_frames)
            self.frame_time = float(frame_time)  # [s]
        self.index = 0
        self.before = doc.pose()
        self.finished = False

    def advance(self) -> bool:
        """Show the next frame; False when there is none (the playback then finishes)."""
        if self.finished:
            return False
        if self.index >= self.n_frames:
            self.stop()
            return False
        self.show(self.index)
        return True

    def show(self, i: int) -> None:
        """Show frame ``i`` (0 <= i < :attr:`n_frames`); the next :meth:`advance` shows ``i + 1``."""
        if self.motion is not None:
            m = self.motion
            self.doc.show_motion_frame(*(m.frame(i) if isinstance(m, KeyedBake) else motion_frame(m, i)))
        else:
            self.doc.drive_targets(self.target_frames[i])
        self.index = i + 1

    def stop(self) -> None:
        """End the playback here and record it as one undo step."""
        if self.finished:
            return
        self.finished = True
        self.doc.record_playback(self)
