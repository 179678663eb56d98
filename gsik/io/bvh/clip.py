"""The BVH data: a hierarchy of joints and the raw motion, as plain read-only values."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gsik.errors import BvhError, choices
from gsik.validate import finite_array

#: The six BVH channel names, in canonical spelling.
CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
CHANNEL_LOOKUP = {c.lower(): c for c in CHANNEL_NAMES}
AXIS_INDEX = {"X": 0, "Y": 1, "Z": 2}




@dataclass(frozen=True, eq=False)
class BvhJoint:
    """One joint (or End Site) of a BVH hierarchy.

    Attributes:
        name: Name as written in the file, namespace kept (``"mixamorig:Hips"``).
        parent: Index of the parent in :attr:`BvhClip.joints`, -1 for the root.
        offset: (3,) translation from the parent, in file units.
        channels: Canonical channel names in file order, ``()`` for an End Site.
        is_end_site: True for an ``End Site`` block.
    """

    name: str
    parent: int
    offset: np.ndarray
    channels: tuple[str, ...] = ()
    is_end_site: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "offset", finite_array(self.offset, (3,), f"joint {self.name!r}: offset", BvhError))
        channels = tuple(self.channels)
        for c in channels:
            if c not in CHANNEL_NAMES:
                raise BvhError(
                    f"joint {self.name!r}: unknown channel {c!r}; expected one of {choices(CHANNEL_NAMES)}"
                )
        if len(set(channels)) != len(channels):
            raise BvhError(f"joint {self.name!r}: duplicate channel in {channels}")
        if self.is_end_site and channels:
            raise BvhError(f"End Site {self.name!r} cannot have channels")
        object.__setattr__(self, "channels", channels)
        object.__setattr__(self, "parent", int(self.parent))
        object.__setattr__(self, "is_end_site", bool(self.is_end_site))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BvhJoint):
            return NotImplemented
        return (
            self.name == other.name
            and self.parent == other.parent
            and self.channels == other.channels
            and self.is_end_site == other.is_end_site
            and np.array_equal(self.offset, other.offset)
        )

    __hash__ = None  # type: ignore[assignment]  # holds an array, like a list


@dataclass(frozen=True, eq=False)
class BvhClip:
    """A parsed BVH file: hierarchy plus raw motion.

    Attributes:
        joints: Joints in depth-first file order (parent before child),
            End Sites included.
        frame_time: Seconds per frame [s].
        motion: (n_frames, n_channels) raw channel values, file units for
            positions and degrees for rotations, columns in file order.
    """

    joints: tuple[BvhJoint, ...]
    frame_time: float
    motion: np.ndarray
    _starts: tuple[int, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        joints = tuple(self.joints)
        _check_hierarchy(joints)
        object.__setattr__(self, "joints", joints)
        frame_time = float(self.frame_time)
        if not (np.isfinite(frame_time) and frame_time > 0.0):
            raise BvhError(f"frame_time must be a positive finite number of seconds, got {self.frame_time!r}")
        object.__setattr__(self, "frame_time", frame_time)
        starts = [0]
        for j in joints:
            starts.append(starts[-1] + len(j.channels))
        object.__setattr__(self, "_starts", tuple(starts))
        motion = np.array(self.motion, dtype=float)
        if motion.ndim != 2 or motion.shape[1] != starts[-1]:
            raise BvhError(f"motion must have shape (n_frames, {starts[-1]}), got {motion.shape}")
        if not np.all(np.isfinite(motion)):
            frame, column = (int(i) for i in np.argwhere(~np.isfinite(motion))[0])
            joint = next(j for j, s in enumerate(starts[1:]) if column < s)
            raise BvhError(f"motion contains non-finite values: frame {frame + 1}, joint {joints[joint].name!r} "
                           f"{joints[joint].channels[column - starts[joint]]} is {float(motion[frame, column])!r}")
        motion.flags.writeable = False
        object.__setattr__(self, "motion", motion)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BvhClip):
            return NotImplemented
        return (
            self.joints == other.joints
            and self.frame_time == other.frame_time
            and np.array_equal(self.motion, other.motion)
        )

    __hash__ = None  # type: ignore[assignment]

    # -- sizes ---------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return int(self.motion.shape[0])

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def n_channels(self) -> int:
        return int(self.motion.shape[1])

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(j.name for j in self.joints)

    @property
    def duration(self) -> float:
        """Length of the clip [s]: ``n_frames * frame_time``."""
        return self.n_frames * self.frame_time

    # -- lookups -------------------------------------------------------------
    @cached_property
    def _index(self) -> dict[str, int]:
        return {j.name: i for i, j in enumerate(self.joints)}

    def joint_index(self, name: str) -> int:
        """Index of the joint called ``name``."""
        try:
            return self._index[name]
        except KeyError:
            raise BvhError(f"clip has no joint {name!r}; joints: {choices(self.names)}") from None

    def channel_index(self, joint: int | str) -> slice:
        """Columns of :attr:`motion` holding ``joint``'s channels (an index or a name)."""
        j = self.joint_index(joint) if isinstance(joint, str) else int(joint)
        if not 0 <= j < self.n_joints:
            raise BvhError(f"joint index {j} out of range [0, {self.n_joints})")
        return slice(self._starts[j], self._starts[j + 1])

    def children(self, joint: int) -> tuple[int, ...]:
        """Indices of the direct children of joint ``joint``."""
        return tuple(i for i, j in enumerate(self.joints) if j.parent == joint)

    def channel_labels(self) -> tuple[str, ...]:
        """(n_channels,) column labels ``"<joint> <channel>"``."""
        return tuple(f"{j.name} {c}" for j in self.joints for c in j.channels)


def _check_name(name: str) -> None:
    if not isinstance(name, str) or not name or any(ch.isspace() or ch in "{}" for ch in name):
        raise BvhError(f"joint name {name!r} must be one non-empty token without spaces or braces")


def _check_hierarchy(joints: tuple[BvhJoint, ...]) -> None:
    """Check that ``joints`` is one tree in depth-first order, as BVH writes it."""
    if not joints:
        raise BvhError("a clip needs at least one joint")
    seen: set[str] = set()
    ancestors: list[int] = []  # the open blocks while walking depth-first
    for i, joint in enumerate(joints):
        _check_joint_name(joint, i, seen)
        if i == 0:
            if joint.parent != -1 or joint.is_end_site:
                raise BvhError(f"the first joint {joint.name!r} must be the root (parent -1, not an End Site)")
        else:
            _check_parent(joints, i, ancestors)
        ancestors.append(i)


def _check_joint_name(joint: BvhJoint, i: int, seen: set[str]) -> None:
    """``joints[i]`` is a :class:`BvhJoint` with a valid name not ``seen`` before (added to ``seen``)."""
    if not isinstance(joint, BvhJoint):
        raise BvhError(f"joints[{i}] is a {type(joint).__name__}, not a BvhJoint")
    _check_name(joint.name)
    if joint.name in seen:
        raise BvhError(f"duplicate joint name {joint.name!r}")
    seen.add(joint.name)


def _check_parent(joints: tuple[BvhJoint, ...], i: int, ancestors: list[int]) -> None:
    """Joint ``i``'s parent comes before it, is no End Site, and is still open (pops closed blocks)."""
    joint = joints[i]
    if not 0 <= joint.parent < i:
        raise BvhError(f"joint {joint.name!r} has parent {joint.parent}; expected an index in [0, {i})")
    if joints[joint.parent].is_end_site:
        raise BvhError(f"End Site {joints[joint.parent].name!r} cannot have children")
    while ancestors and ancestors[-1] != joint.parent:
        ancestors.pop()
    if not ancestors:
        raise BvhError(f"joint {joint.name!r} is not in depth-first order after its parent's subtree")
