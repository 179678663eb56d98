"""Foot contacts of a clip, and the pinned targets that keep a planted foot from sliding.

A foot point (an ankle or heel, a toe) is *planted* in a frame when it is
low and slow: within :attr:`ContactSettings.height_fraction` of the body's
height above its own lowest level over the clip, and moving slower than
:attr:`ContactSettings.speed_fraction` body heights per second (measured over
about :attr:`ContactSettings.speed_seconds`, so the threshold means the same
at 30 and at 120 fps). Runs of planted frames shorter than
:attr:`ContactSettings.min_seconds` are dropped and gaps shorter than
:attr:`ContactSettings.gap_seconds` closed: each remaining run is a contact
span.

While in contact, a foot point's target is *pinned*: the same world
position (the mean of its targets over the span) for the whole span, which
the retargeting tracks at the top priority; the targets ease into and out of
the pin over :attr:`ContactSettings.blend_seconds` either side.

A contact is released where the clip's foot point, smoothed over the blend
time, leaves its spot (where the contact began) by more than
:attr:`ContactSettings.release_fraction` of the body's height, though still
low and slow (a toe pivoting, a foot creeping through a long stance): the
point is free for :attr:`ContactSettings.gap_seconds` and a new contact begins
where it is then. So a pin never holds a point much farther than that from
the clip (issue 17: CMU 002_08's left toe crept 5 cm through a 2.5 s stance
and, held at one place, was 48 mm off), and a held foot still never slides.

The slide (:func:`planted_speed`) is the p95 speed [m/s] of the foot points
over the frames the clip has them planted.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


@dataclass(frozen=True)
class ContactSettings:
    """Thresholds of contact detection, relative to the body's height and the clip's frame rate.

    Attributes:
        height_fraction: Highest a planted point stands above its lowest level, in body heights.
        speed_fraction: Fastest a planted point moves, in body heights per second.
        speed_seconds: Time over which the speed is measured [s] (a central difference).
        min_seconds: Shortest contact span kept [s].
        gap_seconds: Longest gap closed inside a contact [s].
        blend_seconds: Time over which targets ease into and out of a pin [s].
        release_fraction: How far the smoothed point may leave its contact's spot before the contact is released,
            in body heights (half the retarget check's 2% per joint).
    """

    height_fraction: float = 0.03
    speed_fraction: float = 0.05
    speed_seconds: float = 0.08
    min_seconds: float = 0.1
    gap_seconds: float = 0.05
    blend_seconds: float = 0.1
    release_fraction: float = 0.01


class ContactSpan(NamedTuple):
    """One contact: foot point ``column`` is planted in frames ``start`` to ``stop - 1``."""

    column: int
    start: int
    stop: int


@dataclass(frozen=True, eq=False)
class Contacts:
    """A clip's foot contacts.

    Attributes:
        names: The foot points (skeleton frames), one column each.
        planted: (n_frames, n_points) bool, True inside a contact span.
        spans: The contact spans, by column then time.
        fps: Frames per second of the clip [1/s].
    """

    names: tuple[str, ...]
    planted: np.ndarray
    spans: tuple[ContactSpan, ...]
    fps: float

    def __post_init__(self):
        self.planted.flags.writeable = False


def _frames(seconds: float, fps: float) -> int:
    """``seconds`` as a whole number of frames, at least 1."""
    return max(1, int(round(seconds * fps)))


def point_speeds(points: np.ndarray, fps: float, window: int = 1) -> np.ndarray:
    """(n_frames, n_points) speeds [m/s] of ``points`` (n_frames, n_points, 3) [m], central differences over
    ``window`` frames either side (one-sided at the ends)."""
    n = len(points)
    ahead = np.minimum(np.arange(n) + window, n - 1)
    behind = np.maximum(np.arange(n) - window, 0)
    span = np.maximum(ahead - behind, 1)[:, None]
    return np.linalg.norm(points[ahead] - points[behind], axis=-1) * fps / span


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True in the 1-D bool array ``flags``."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def _spans(flags: np.ndarray, min_frames: int, gap_frames: int) -> list[tuple[int, int]]:
    """Runs of ``flags`` with gaps up to ``gap_frames`` closed and runs under ``min_frames`` dropped."""
    closed = flags.copy()
    runs = _runs(flags)
    for (_, a), (b, _) in zip(runs, runs[1:]):
        if b - a <= gap_frames:
            closed[a:b] = True
    return [(a, b) for a, b in _runs(closed) if b - a >= min_frames]


def smoothed(points: np.ndarray, half: int) -> np.ndarray:
    """``points`` (n_frames, ...) averaged over ``half`` frames either side (fewer at the ends): the clip's path
    without its frame-to-frame jitter."""
    c = np.cumsum(np.concatenate([np.zeros((1,) + points.shape[1:]), points]), axis=0)
    n = len(points)
    hi = np.minimum(np.arange(n) + half + 1, n)
    lo = np.maximum(np.arange(n) - half, 0)
    return (c[hi] - c[lo]) / (hi - lo).reshape((n,) + (1,) * (points.ndim - 1))


def _settled(path: np.ndarray, radius: float, gap: int, min_frames: int) -> list[tuple[int, int]]:
    """``(start, stop)`` runs of ``path`` (n, 3) [m] that stay within ``radius`` [m] of where each began; after a
    run ends, ``gap`` frames are left free; runs shorter than ``min_frames`` are dropped."""
    runs, a, n = [], 0, len(path)
    while a < n:
        away = np.flatnonzero(np.linalg.norm(path[a:] - path[a], axis=-1) > radius)
        b = a + int(away[0]) if len(away) else n
        if b - a >= min_frames:
            runs.append((a, b))
        a = b + gap if len(away) else n
    return runs


def detect_contacts(points: np.ndarray, names: tuple[str, ...], fps: float, body_height: float, up: int = 2,
                    settings: ContactSettings = ContactSettings()) -> Contacts:
    """The contact spans of foot points ``points`` (n_frames, n_points, 3) [m], ``up`` the vertical axis index.

    ``body_height`` [m] scales the thresholds (see :class:`ContactSettings`); ``fps`` [1/s] sets the speed
    window and the shortest span.
    """
    height = points[..., up] - np.percentile(points[..., up], 2.0, axis=0)
    speed = point_speeds(points, fps, _frames(settings.speed_seconds / 2, fps))
    low_and_slow = (height < settings.height_fraction * body_height) & (speed < settings.speed_fraction * body_height)
    planted = np.zeros(low_and_slow.shape, dtype=bool)
    smooth = smoothed(points, _frames(settings.blend_seconds, fps))
    spans = []
    for k in range(points.shape[1]):
        for a, b in _spans(low_and_slow[:, k], _frames(settings.min_seconds, fps), _frames(settings.gap_seconds,
                                                                                             fps)):
            for c, d in _settled(smooth[a:b, k], settings.release_fraction * body_height,
                                 _frames(settings.gap_seconds, fps), _frames(settings.min_seconds, fps)):
                planted[a + c:a + d, k] = True
                spans.append(ContactSpan(k, a + c, a + d))
    return Contacts(tuple(names), planted, tuple(spans), float(fps))


def pin_weights(contacts: Contacts, settings: ContactSettings = ContactSettings()) -> np.ndarray:
    """(n_frames, n_points) how much each point is held by its pin: 1 inside a span, easing linearly to 0 over
    :attr:`ContactSettings.blend_seconds` either side, 0 elsewhere."""
    w = contacts.planted.astype(float)
    n = len(w)
    k = _frames(settings.blend_seconds, contacts.fps)
    for column, start, stop in contacts.spans:
        for i in range(max(0, start - k), start):
            w[i, column] = max(w[i, column], 1.0 - (start - i) / (k + 1))
        for i in range(stop, min(n, stop + k)):
            w[i, column] = max(w[i, column], 1.0 - (i - stop + 1) / (k + 1))
    return w


def pin_targets(points: np.ndarray, contacts: Contacts, settings: ContactSettings = ContactSettings()) -> np.ndarray:
    """``points`` (n_frames, n_points, 3) [m] with each contact span held at one place (a new array).

    Inside a span the point is the mean of its positions over the span; over
    :attr:`ContactSettings.blend_seconds` before and after, it eases linearly
    from its own path to the pin and back (:func:`pin_weights`).
    """
    n = len(points)
    k = _frames(settings.blend_seconds, contacts.fps)
    held = np.array(points, dtype=float)
    for column, start, stop in contacts.spans:
        pin = points[start:stop, column].mean(axis=0)
        for i in range(max(0, start - k), min(n, stop + k)):
            if start <= i < stop or not contacts.planted[i, column]:  # another span's frames keep their pin
                held[i, column] = pin
    w = pin_weights(contacts, settings)[..., None]
    return points + w * (held - points)


def planted_speed(points: np.ndarray, planted: np.ndarray, fps: float, percentile: float = 95.0) -> float:
    """The ``percentile`` speed [m/s] of ``points`` (n_frames, n_points, 3) [m] from each planted frame to the next
    planted one ((n_frames, n_points) bool ``planted``); 0 when nothing is planted twice in a row."""
    both = planted[1:] & planted[:-1]
    if not both.any():
        return 0.0
    step = np.linalg.norm(np.diff(points, axis=0), axis=-1) * fps
    return float(np.percentile(step[both], percentile))
