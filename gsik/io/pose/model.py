"""The pose value types and the format's constants (the format itself: :mod:`gsik.io.pose`)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from gsik import validate
from gsik.anim.motion import Motion
from gsik.errors import PoseError, show_value
from gsik.rotations import matrix_from_quaternion, transform
from gsik.skeleton import Skeleton
from gsik.targets import Target

#: The version of the pose format this module reads and writes.
POSE_FORMAT = 1

#: How far from unit norm a quaternion in a file may be (it is normalised).
QUATERNION_NORM_TOLERANCE = 0.01

#: Angles within this of a limit [rad] count as inside it (no warning).
LIMIT_TOLERANCE = 1e-9

_POSE_KEYS = ("root", "root_transform", "joints", "targets")
_TOP_KEYS = ("format", "skeleton", *_POSE_KEYS)
_LIBRARY_KEY = "library"
_KEYS_KEY, _POLES_KEY, _CLIP_KEY = "keys", "poles", "clip"
_OPTIONAL_TOP_KEYS = (_LIBRARY_KEY, _KEYS_KEY, _POLES_KEY, _CLIP_KEY)
_KEY_SEQUENCE_KEYS = ("fps", "length", "poses")
_POLE_KEYS = ("position", "enabled")
_CLIP_KEYS = ("name", "frame_time", "dofs", "frames")
_CLIP_FRAME_KEYS = ("root", "world_from_root", "angles")

#: Most frames per second a key sequence may have.
MAX_FPS = 1000.0
#: Fewest frames per second (one frame in 1000 s): below, a sequence's frame time overflows or never plays.
MIN_FPS = 1e-3

#: What a pose's ``skeleton:`` field ends in when it names a skeleton file instead of a bundled skeleton.
SKELETON_FILE_SUFFIXES = (".yaml", ".yml", ".urdf", ".bvh")
_TRANSFORM_KEYS = ("position", "orientation")
_TARGET_KEYS = ("position", "orientation", "enabled", "weight", "position_only", "priority")

def _floats(value, n: int, what: str) -> tuple[float, ...]:
    return validate.vector(value, n, what, PoseError)


def _unit_quaternion(value, what: str) -> tuple[float, float, float, float]:
    q = _floats(value, 4, what)
    norm = math.sqrt(sum(v * v for v in q))
    if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
        raise PoseError(f"{what} must be a unit quaternion (w, x, y, z), got {list(q)} of norm {norm:.6g}")
    return q


@dataclass(frozen=True)
class Pose:
    """A complete, immutable pose of one skeleton: what a pose file holds.

    Attributes:
        skeleton: Name of the skeleton.
        root: The IK root (a joint or site), pinned to the world.
        root_position: World position (3,) [m] of the root frame.
        root_orientation: World orientation of the root frame, unit quaternion (w, x, y, z).
        joints: ``{DOF name: angle [rad]}`` in the skeleton's DOF order (read-only).
        targets: ``{effector name: gsik.Target}`` for every effector of the root (read-only).
    """

    skeleton: str
    root: str
    root_position: tuple[float, float, float]
    root_orientation: tuple[float, float, float, float]
    joints: Mapping[str, float]
    targets: Mapping[str, Target]

    def __post_init__(self):
        object.__setattr__(self, "root_position", _floats(self.root_position, 3, "root position"))
        object.__setattr__(self, "root_orientation", _unit_quaternion(self.root_orientation, "root orientation"))
        joints = {}
        for name, value in dict(self.joints).items():
            if type(value) is not float or not math.isfinite(value):
                value = _floats([value], 1, f"joint {show_value(name)}")[0]
            joints[str(name)] = value
        targets = {}
        for name, t in dict(self.targets).items():
            if not isinstance(t, Target):
                raise PoseError(f"target {show_value(name)} must be a gsik.Target, got {type(t).__name__}")
            targets[str(name)] = t
        object.__setattr__(self, "joints", MappingProxyType(joints))
        object.__setattr__(self, "targets", MappingProxyType(targets))

    def q(self, skeleton: Skeleton) -> np.ndarray:
        """The angles (n_dofs,) [rad] in ``skeleton``'s DOF order."""
        try:
            return np.array([self.joints[n] for n in skeleton.dof_names])
        except KeyError as exc:
            raise PoseError(f"pose has no angle for {show_value(exc.args[0])}") from None

    @property
    def world_from_root(self) -> np.ndarray:
        """World transform (4, 4) of the root frame."""
        q = np.array(self.root_orientation)
        return transform(matrix_from_quaternion(q / np.linalg.norm(q)), np.array(self.root_position))

    def replace(self, **changes) -> Pose:
        """A copy with some fields changed (validated again)."""
        fields = dict(skeleton=self.skeleton, root=self.root, root_position=self.root_position,
                      root_orientation=self.root_orientation, joints=self.joints, targets=self.targets)
        fields.update(changes)
        return Pose(**fields)


class KeySequence(NamedTuple):
    """Keyed poses on a timeline: what a pose file's ``keys`` holds.

    Attributes:
        keys: ``((frame, Pose), ...)`` in increasing frame order, frames whole numbers >= 0.
        fps: Frames per second of the sequence [1/s] (> 0).
        length: Frames on the timeline (>= the last key's frame + 1).
    """

    keys: tuple[tuple[int, Pose], ...]
    fps: float = 30.0
    length: int = 0


class Pole(NamedTuple):
    """A pole target on a joint (knee, elbow): where its bend should point.

    Attributes:
        position: World position (3,) [m].
        enabled: False: kept, but the solver ignores it.
    """

    position: tuple[float, float, float]
    enabled: bool = True


class Clip(NamedTuple):
    """A motion kept with a pose (the studio's timeline clip): its name and its angle frames.

    Attributes:
        name: What the clip is called ("walk.bvh", "Walk").
        motion: The frames: angles, root and root transform per frame, frame time.
    """

    name: str
    motion: Motion


class PoseRead(NamedTuple):
    """What reading a pose file gives.

    Attributes:
        pose: The validated :class:`Pose` (angles clamped into the limits).
        warnings: One sentence per problem that was repaired (an angle
            clamped into its limits); empty when the file was clean.
        library: The file's named poses ``((name, Pose), ...)`` in file order
            (empty for a single-pose file).
        keys: The file's key sequence (None when it has none).
        poles: ``{joint: Pole}`` in file order (empty when it has none).
        clip: The file's clip (None when it has none).
    """

    pose: Pose
    warnings: tuple[str, ...]
    library: tuple[tuple[str, Pose], ...] = ()
    keys: KeySequence | None = None
    poles: Mapping[str, Pole] = MappingProxyType({})
    clip: Clip | None = None


# -- reading -----------------------------------------------------------------
