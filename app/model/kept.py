"""What a document keeps besides its pose: the pose library, the timeline (keys and clip) and the pole targets.

Plain Python. :class:`Kept` is one immutable snapshot of all of it: the undo
history stores one next to the pose before and after every edit (so undo and
redo restore it exactly, whatever the edit touched), and pose files save and
open it (:func:`file_fields`, :func:`kept_from_file`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

from gsik.errors import PoseError, choices
from gsik.io.pose import Clip, KeySequence, Pole, PoseRead
from gsik.targets import Target
from gsik_studio.model.library import LibraryState
from gsik_studio.model.pins import POLE
from gsik_studio.model.poses import check_pose
from gsik_studio.model.timeline import TimelineState

if TYPE_CHECKING:
    from gsik_studio.model.document import Document


class Kept(NamedTuple):
    """Everything a document keeps besides its pose (immutable; the empty default is a new document's).

    Attributes:
        library: The pose library, ``((name, Pose), ...)``.
        timeline: The timeline's clip and keys.
        poles: Every pole target placed, ``((joint, Target), ...)``, enabled or not.
    """

    library: LibraryState = ()
    timeline: TimelineState = TimelineState()
    poles: tuple[tuple[str, Target], ...] = ()


def kept_state(doc: Document) -> Kept:
    """What ``doc`` keeps now."""
    return Kept(doc.library.snapshot(), doc.timeline.snapshot(), doc.controls.pole_snapshot())


def show_kept(doc: Document, kept: Kept) -> None:
    """Make ``doc`` keep ``kept`` (undo, redo, open, new); no undo step. Each part signals only if it changed."""
    doc.library.restore(kept.library)
    doc.timeline.restore(kept.timeline)
    doc.controls.restore_poles(kept.poles)


def file_fields(kept: Kept) -> dict:
    """The keyword arguments of :func:`gsik.io.pose.write_pose` that save ``kept``."""
    tl, new = kept.timeline, TimelineState()
    own_timeline = tl.keys or (tl.fps, tl.length) != (new.fps, new.length)  # else a new document's: no block
    return dict(library=kept.library,
                keys=KeySequence(tl.keys, tl.fps, tl.length) if own_timeline else None,
                poles={n: Pole(tuple(t.position), t.enabled) for n, t in kept.poles},
                clip=Clip(tl.name, tl.clip) if tl.clip is not None else None)


def kept_from_file(doc: Document, read: PoseRead) -> Kept:
    """What a pose file read for ``doc``'s skeleton keeps, checked against ``doc`` before anything changes.

    Raises:
        PoseError: a library pose or key does not fit the skeleton, or a pole is on a joint the studio has no
            pole target for.
    """
    keys = read.keys.keys if read.keys is not None else ()
    for _, pose in read.library + keys:
        check_pose(doc.skeleton, pose)
    joints = doc.controls.pole_joints
    for name in read.poles:
        if name not in joints:
            raise PoseError(f"pole target on {name!r}: the studio has pole targets on {choices(joints)} only")
    poles = tuple((n, Target(p.position, position_only=True, enabled=p.enabled, priority=POLE))
                  for n, p in read.poles.items())
    timeline = TimelineState(read.clip.motion if read.clip else None, read.clip.name if read.clip else "", keys)
    if read.keys is not None:  # the file's timeline (a file without ``keys`` gets a new document's)
        timeline = timeline._replace(fps=read.keys.fps, length=max(read.keys.length, 1))
    return Kept(read.library, timeline, poles)
