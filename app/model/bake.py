"""A key sequence baked in chunks: the frames shown are solved on demand, the rest a few at a time.

Plain Python. Baking a key sequence costs a solve per in-between frame (about
0.45 ms each unloaded: 10,000 frames take seconds), so neither Play nor
Export may do it in one go on the GUI thread. A :class:`KeyedBake` solves the
frames in order (each warm-started from the one before, exactly as a one-go
bake would) only when asked, ``budget_frames`` at a time: the timeline steps
it a chunk per play tick, Export steps it a chunk per event-loop turn under a
progress dialog. A frame asked for far past the frames baked so far is
previewed: solved on its own, warm-started from the nearest frame known, and
not kept (the baked frames stay those of the one-go bake).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

import gsik
from gsik.anim.motion import Motion
from gsik.errors import GsikError
from gsik.io.pose import Pose
from gsik_studio.model.keys import KEY_STEPS, _Baker, interpolated_targets

#: A frame asked for at most this many frames past those baked is baked up to (exact, kept); further on it is
#: previewed (about 15 ms of solving unloaded at most per frame asked).
BAKE_AHEAD = 32

#: Solver steps of a previewed frame per step of a baked one (it starts further from its answer).
PREVIEW_STEPS = 4


class BakedFrame(NamedTuple):
    """One frame of a motion: the root's name, its world transform (4, 4) [m], the angles (n_dofs,) [rad]."""

    root: str
    world_from_root: np.ndarray
    q: np.ndarray


def motion_frame(motion: Motion, i: int) -> BakedFrame:
    """Frame ``i`` of ``motion``."""
    return BakedFrame(motion.roots[i], motion.world_from_root[i], motion.q[i])


class KeyedBake:
    """The key sequence ``{frame: Pose}`` as a motion of :attr:`n_frames` frames, solved ``budget_frames`` at a time.

    Frames before the first key hold it, frames after the last key hold that;
    a key frame shows its pose exactly; a frame between keys is solved from
    :func:`gsik_studio.model.keys.interpolated_targets`, warm-started from the
    frame before (root and placement of the earlier key). Stepping in chunks of
    any size gives the frames of one :meth:`step` over all of them.

    Args:
        skeleton, settings: What the scratch solver solves with (the document's solver is never touched).
        keys: ``{frame: Pose}``, at least one.
        frame_time: Seconds per frame [s].
        steps: Solver steps per in-between frame.
        n_frames: Frames wanted; at least ``max(keys) + 1`` are baked.

    Raises:
        GsikError: no keys.
    """

    def __init__(self, skeleton: gsik.Skeleton, settings: gsik.SolverSettings, keys: Mapping[int, Pose],
                 frame_time: float, steps: int = KEY_STEPS, n_frames: int = 0):
        if not keys:
            raise GsikError("no keyed poses to bake: add a key first")
        self.skeleton, self.settings, self.keys = skeleton, settings, dict(keys)
        self.frame_time, self.steps = float(frame_time), int(steps)
        self._frames = sorted(self.keys)
        self.n_frames = max(self._frames[-1] + 1, int(n_frames))
        self._baker = _Baker(skeleton, settings, self.keys[self._frames[0]])
        self._placed = self._frames[0]  # the key the scratch solver holds exactly, if any
        self._preview: _Baker | None = None  # a second scratch solver for frames far ahead
        self._preview_at = -1  # the frame it holds (-1: none)

    @property
    def solved(self) -> int:
        """Frames baked so far (frames ``0 .. solved - 1``)."""
        return len(self._baker.q)

    @property
    def done(self) -> bool:
        """True when every frame is baked."""
        return self.solved >= self.n_frames

    def step(self, budget_frames: int) -> int:
        """Bake up to ``budget_frames`` more frames, in order; returns how many were baked (0 when done)."""
        n = max(0, min(int(budget_frames), self.n_frames - self.solved))
        for _ in range(n):
            self._bake_next()
        return n

    def finish(self) -> Motion:
        """Bake every frame left (in one go: not on the GUI thread for long sequences) and return the motion."""
        self.step(self.n_frames)
        return self.motion()

    def motion(self) -> Motion:
        """The baked motion.

        Raises:
            GsikError: frames are left to bake.
        """
        if not self.done:
            raise GsikError(f"the keys are baked up to frame {self.solved} of {self.n_frames}: bake the rest first")
        return self._baker.motion(self.frame_time)

    def frame(self, i: int) -> BakedFrame:
        """Frame ``i`` (0 <= i < :attr:`n_frames`): baked, baked up to when it is near, else previewed."""
        if not 0 <= i < self.n_frames:
            raise GsikError(f"frame {i} is outside the keys' {self.n_frames} frames")
        if i < self.solved + BAKE_AHEAD:
            self.step(i + 1 - self.solved)
            b = self._baker
            return BakedFrame(b.roots[i], b.W[i], b.q[i])
        return self._previewed(i)

    # -- inside ---------------------------------------------------------------------------
    def _segment(self, i: int) -> tuple[int, int] | None:
        """``(a, b)``: the keys frame ``i`` lies strictly between; None when it holds a key (which key: ``a``)."""
        k = int(np.searchsorted(self._frames, i, side="right")) - 1  # the last key at or before i
        if k < 0 or self._frames[k] == i or k == len(self._frames) - 1:
            return None
        return self._frames[k], self._frames[k + 1]

    def _held_key(self, i: int) -> int:
        """The key a frame outside every segment holds (the first key before it)."""
        k = int(np.searchsorted(self._frames, i, side="right")) - 1
        return self._frames[max(k, 0)]

    def _bake_next(self) -> None:
        i, b = self.solved, self._baker
        segment = self._segment(i)
        if segment is None:
            key = self._held_key(i)
            if key != self._placed:
                self._placed = key
                b.place(self.keys[key])
        else:
            self._placed = None
            a, c = segment
            b.drive(interpolated_targets(self.keys[a], self.keys[c], (i - a) / (c - a)), self.steps)
        b.record()

    def _previewed(self, i: int) -> BakedFrame:
        """Frame ``i`` solved on its own from the nearest known frame of its segment (nothing kept in the bake)."""
        segment = self._segment(i)
        if self._preview is None:
            self._preview = _Baker(self.skeleton, self.settings, self.keys[self._frames[0]])
        p = self._preview
        if segment is None:
            p.place(self.keys[self._held_key(i)])
            self._preview_at = -1
        else:
            a, c = segment
            if not a <= self._preview_at < i:  # no earlier frame of this segment held: from the key (or the bake)
                p.place(self.keys[a])
                if a <= self.solved - 1 < i:
                    j = self.solved - 1
                    _hold(p, BakedFrame(self._baker.roots[j], self._baker.W[j], self._baker.q[j]))
            p.drive(interpolated_targets(self.keys[a], self.keys[c], (i - a) / (c - a)), self.steps * PREVIEW_STEPS)
            self._preview_at = i
        return BakedFrame(p.solver.root, p.solver.world_from_root, p.solver.q)


def bake_keys(skeleton: gsik.Skeleton, settings: gsik.SolverSettings, keys: Mapping[int, Pose],
              frame_time: float, steps: int = KEY_STEPS, n_frames: int = 0) -> Motion:
    """The key sequence as a motion of ``max(keys) + 1`` frames, or ``n_frames`` when that is more, in one go
    (:class:`KeyedBake` stepped over every frame; a window steps it in chunks instead)."""
    return KeyedBake(skeleton, settings, keys, frame_time, steps, n_frames).finish()


def _hold(baker: _Baker, frame: BakedFrame) -> None:
    """Put the scratch solver at ``frame`` (root, placement, angles; the targets stay)."""
    if frame.root != baker.solver.root:
        baker.solver.set_root(frame.root)
    baker.solver.set_world_from_root(frame.world_from_root)
    baker.solver.set_q(frame.q)
