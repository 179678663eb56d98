"""How large a BVH file gsik reads: every bound checked before the work it bounds is done.

A hostile BVH can be small and still declare enormous work: ``Frames: 999999999`` in 250 bytes, a star of a million
joints, a hierarchy nested 100,000 deep. Each bound below is far above real motion capture (a CMU clip: 4 MB,
100 joints, depth 12, a few thousand frames) and far below what would exhaust memory; a file past one is refused
with a :class:`~gsik.errors.BvhError` naming the bound, the file's value and the limit.
"""

from __future__ import annotations

from gsik.anim.motion import FRAME_TIME_RANGE
from gsik.errors import BvhError

#: Largest BVH file read [bytes].
MAX_BVH_BYTES = 64 * 1024 * 1024

#: Most joints (End Sites included) in a hierarchy.
MAX_BVH_JOINTS = 8192

#: Deepest nesting of joints (the root is depth 1).
MAX_BVH_DEPTH = 1024

#: Most frames in a clip (at 120 frames/s, more than two hours).
MAX_BVH_FRAMES = 1_000_000

#: Most values a clip's motion may make: frames x (channels + joints), the numbers read plus one pose per joint
#: and frame computed from them.
MAX_BVH_VALUES = 20_000_000


def check_joints(n_joints: int, depth: int, source: str, line: int) -> None:
    """Refuse a hierarchy past :data:`MAX_BVH_JOINTS` joints or :data:`MAX_BVH_DEPTH` levels."""
    if n_joints > MAX_BVH_JOINTS:
        raise BvhError(f"too many joints: more than {MAX_BVH_JOINTS:,} (End Sites included); the limit is "
                       f"{MAX_BVH_JOINTS:,}", line=line, path=source)
    if depth > MAX_BVH_DEPTH:
        raise BvhError(f"joints nested too deep: depth {depth:,}; the limit is {MAX_BVH_DEPTH:,}", line=line,
                       path=source)


def check_frames(n_frames: int, n_channels: int, n_joints: int, source: str, line: int) -> None:
    """Refuse a ``Frames:`` count past :data:`MAX_BVH_FRAMES`, or frames x (channels + joints) past
    :data:`MAX_BVH_VALUES`, before a value is read."""
    if n_frames > MAX_BVH_FRAMES:
        raise BvhError(f"Frames: {n_frames:,}: the limit is {MAX_BVH_FRAMES:,} frames", line=line, path=source)
    values = n_frames * (n_channels + n_joints)
    if values > MAX_BVH_VALUES:
        raise BvhError(f"Frames: {n_frames:,} x ({n_channels:,} channels + {n_joints:,} joints) = {values:,} "
                       f"values; the limit is {MAX_BVH_VALUES:,}", line=line, path=source)


def check_braces(text: str, source: str) -> None:
    """Refuse a text with more than :data:`MAX_BVH_JOINTS` ``{`` before it is split into lines.

    Every joint and End Site opens one brace and nothing else may (names cannot hold one, MOTION holds numbers), so
    this bounds the hierarchy at the cost of one scan of the text, whatever its size; the error names the line of
    the first brace past the limit.
    """
    if text.count("{") <= MAX_BVH_JOINTS:
        return
    at = -1
    for _ in range(MAX_BVH_JOINTS + 1):
        at = text.find("{", at + 1)
    line = text.count("\n", 0, at) + 1
    raise BvhError(f"too many joints: more than {MAX_BVH_JOINTS:,} '{{' blocks (End Sites included); the limit is "
                   f"{MAX_BVH_JOINTS:,}", line=line, path=source)




def check_frame_time(frame_time: float, source: str, line: int) -> None:
    """Refuse a ``Frame Time`` outside :data:`FRAME_TIME_RANGE` (5e-324 s would overflow the frame rate)."""
    if not FRAME_TIME_RANGE[0] <= frame_time <= FRAME_TIME_RANGE[1]:
        raise BvhError(f"Frame Time {frame_time!r}: must be from {FRAME_TIME_RANGE[0]:g} to {FRAME_TIME_RANGE[1]:g} "
                       "seconds", line=line, path=source)
