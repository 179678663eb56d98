"""The parts of a pose file about motion: ``keys`` (keyed poses), ``poles`` (pole targets), ``clip`` (angle frames).

Read with the pose reader's checks (every error names file, line, field and value) and written with the pose
writer's exact numbers; the format is in :mod:`gsik.io.pose`. Sizes stay within the bounded YAML reader's limits
(:mod:`gsik.io.yaml_safe`), and a key sequence within :data:`MAX_SEQUENCE_FRAMES` frames, so a hostile file can
neither exhaust memory nor make the studio bake an endless sequence.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING

import numpy as np

from gsik.anim.motion import FRAME_TIME_RANGE, Motion
from gsik.errors import PoseError, choices, show_value
from gsik.io.pose import legacy
from gsik.io.pose.model import (_CLIP_FRAME_KEYS, _CLIP_KEY, _CLIP_KEYS, _KEY_SEQUENCE_KEYS, _KEYS_KEY, _POLE_KEYS,
                               _POLES_KEY, _POSE_KEYS, MAX_FPS, MIN_FPS, Clip, KeySequence, Pole, Pose)
from gsik.io.yaml_safe import yaml_string
from gsik.rotations import ROTATION_TOLERANCE
from gsik.skeleton import Skeleton
from gsik.targets import MAX_COORDINATE

if TYPE_CHECKING:
    from gsik.io.pose.read import _Reader

#: Most frames a key sequence may span (a key's frame and the length are below it): 5.5 minutes at 30 fps. The
#: studio solves every frame between keys when it plays or exports them (about 0.5 ms each): a bound in seconds.
MAX_SEQUENCE_FRAMES = 10_000

#: Frames per second of a key sequence when the file does not say.
DEFAULT_FPS = 30.0


# -- reading -------------------------------------------------------------------------------
def read_keys(r: _Reader, value, pose_at: Callable[[dict, tuple], Pose]) -> KeySequence:
    """The ``keys`` mapping: ``fps``, ``length`` and ``poses`` (each a ``frame`` and the pose fields; frames unique).

    ``pose_at(fields, path)`` reads the pose fields found at key path ``path``.
    """
    at = (_KEYS_KEY,)
    seq = r.mapping(value, at, _KEY_SEQUENCE_KEYS[2:], _KEY_SEQUENCE_KEYS[:2])
    fps = r.number(seq.get("fps", DEFAULT_FPS), at + ("fps",))
    if not MIN_FPS <= fps <= MAX_FPS:
        r.fail(at + ("fps",), f"must be from {MIN_FPS:g} to {MAX_FPS:g} frames per second, got {fps!r}")
    keys: dict[int, Pose] = {}
    for i, entry in enumerate(r.items(seq["poses"], at + ("poses",), "keyed poses")):
        here = at + ("poses", i)
        fields = r.mapping(entry, here, ("frame", *_POSE_KEYS))
        frame = r.whole(fields["frame"], here + ("frame",), MAX_SEQUENCE_FRAMES - 1)
        if frame in keys:
            r.fail(here + ("frame",), f"a second key at frame {frame}; keys so far at {sorted(keys)}")
        keys[frame] = pose_at(fields, here)
    last = max(keys, default=-1)
    length = r.whole(seq.get("length", last + 1), at + ("length",), MAX_SEQUENCE_FRAMES)
    if length < last + 1:
        r.fail(at + ("length",), f"must be at least the last key's frame + 1 ({last + 1}), got {length}")
    return KeySequence(tuple(sorted(keys.items())), fps, length)


def read_poles(r: _Reader, value, skeleton: Skeleton) -> dict[str, Pole]:
    """The ``poles`` mapping: joint name -> ``position`` and (optional, default true) ``enabled``."""
    at = (_POLES_KEY,)
    if not isinstance(value, dict):
        r.fail(at, f"must be a mapping of joint name to pole target, got {show_value(value)}")
    poles = {}
    for name, pole in value.items():
        here = at + (name,)
        if name not in skeleton.joint_names:
            r.fail(here, f"unknown joint {show_value(name)}; valid: {choices(skeleton.joint_names)}")
        fields = r.mapping(pole, here, _POLE_KEYS[:1], _POLE_KEYS[1:])
        poles[name] = Pole(r.position(fields["position"], here + ("position",)),
                           r.flag(fields.get("enabled", True), here + ("enabled",)))
    return poles


def read_clip(r: _Reader, value, skeleton: Skeleton) -> Clip:
    """The ``clip`` mapping: ``name``, ``frame_time`` [s], ``dofs`` (the skeleton's, in order) and ``frames``."""
    at = (_CLIP_KEY,)
    c = r.mapping(value, at, _CLIP_KEYS)
    name = r.name(c["name"], at + ("name",))
    frame_time = r.number(c["frame_time"], at + ("frame_time",))
    if not FRAME_TIME_RANGE[0] <= frame_time <= FRAME_TIME_RANGE[1]:
        r.fail(at + ("frame_time",), f"must be from {FRAME_TIME_RANGE[0]:g} to {FRAME_TIME_RANGE[1]:g} seconds, got "
                                     f"{frame_time!r}")
    dofs = legacy.dof_list(r.items(c["dofs"], at + ("dofs",), "DOF names"), skeleton.dof_names)
    if tuple(dofs) != skeleton.dof_names:
        r.fail(at + ("dofs",), f"must list the skeleton's {skeleton.n_dofs} DOFs in its order: "
                               f"{choices(skeleton.dof_names)}")
    frames = r.items(c["frames"], at + ("frames",), "frames")
    if not frames:
        r.fail(at + ("frames",), "must hold at least one frame")
    roots, W, q = [], np.zeros((len(frames), 4, 4)), np.zeros((len(frames), skeleton.n_dofs))
    for i, frame in enumerate(frames):
        here = at + ("frames", i)
        f = r.mapping(frame, here, _CLIP_FRAME_KEYS)
        root = r.name(f["root"], here + ("root",))
        if root not in skeleton.joint_names and root not in skeleton.site_names:
            r.fail(here + ("root",), f"unknown root {show_value(root)}; valid: any joint or site, "
                                     f"{choices(skeleton.joint_names + skeleton.site_names)}")
        roots.append(root)
        W[i] = _read_transform(r, f["world_from_root"], here + ("world_from_root",))
        q[i] = r.vector(f["angles"], skeleton.n_dofs, here + ("angles",))
    return Clip(name, Motion(skeleton, q, tuple(roots), W, frame_time))


def check_clip_frames(motion: Motion, skeleton: Skeleton) -> None:
    """PoseError for the first frame of ``motion`` that :func:`read_clip` would refuse for ``skeleton`` (its root
    not a joint or site, a non-finite number, a root placed beyond ``MAX_COORDINATE``, a transform that is not a
    rotation), checked over all frames at once, in the reader's words."""
    valid = set(skeleton.joint_names) | set(skeleton.site_names)
    W, R = motion.world_from_root, motion.world_from_root[:, :3, :3]
    with np.errstate(all="ignore"):
        bad_root = np.array([r not in valid for r in motion.roots])
        finite = np.isfinite(W[:, :3]).all(axis=(1, 2)) & np.isfinite(motion.q).all(axis=1)
        far = np.abs(W[:, :3, 3]).max(axis=1) > MAX_COORDINATE
        skew = np.abs(np.transpose(R, (0, 2, 1)) @ R - np.eye(3)).max(axis=(1, 2)) > ROTATION_TOLERANCE
        not_rotation = skew | (np.linalg.det(R) < 0.0)
    problems = [(bad_root, "root", lambda k: f"unknown root {show_value(motion.roots[k])}; valid: any joint or "
                                             f"site, {choices(skeleton.joint_names + skeleton.site_names)}"),
                (~finite, "", lambda k: "holds a number that is not finite"),
                (finite & far, "world_from_root", lambda k: f"must place the root within {MAX_COORDINATE:g} m of "
                                                            f"the origin, got {W[k, :3, 3].tolist()}"),
                (finite & not_rotation, "world_from_root", lambda k: "the first three columns must be a rotation "
                 f"(orthonormal within {ROTATION_TOLERANCE:g}, determinant +1), got {R[k].tolist()}")]
    for mask, field, text in problems:
        if mask.any():
            k = int(np.argmax(mask))
            raise PoseError(f"{'.'.join(filter(None, (_CLIP_KEY, 'frames', str(k), field)))}: {text(k)}")


def _read_transform(r: _Reader, value, path: tuple) -> np.ndarray:
    """A world transform (4, 4) from three rows ``[r0, r1, r2, position]``: a rotation and a position [m]."""
    rows = r.items(value, path, "3 rows of 4 numbers (rotation | position)")
    if len(rows) != 3:
        r.fail(path, f"must be 3 rows of 4 numbers (rotation | position), got {len(rows)} rows")
    T = np.eye(4)
    T[:3] = [r.vector(row, 4, path + (k,)) for k, row in enumerate(rows)]
    r.position(T[:3, 3].tolist(), path)
    R = T[:3, :3]
    if np.abs(R.T @ R - np.eye(3)).max() > ROTATION_TOLERANCE or np.linalg.det(R) < 0.0:
        r.fail(path, f"the first three columns must be a rotation (orthonormal within {ROTATION_TOLERANCE:g}, "
                     f"determinant +1), got {R.tolist()}")
    return T


# -- writing -------------------------------------------------------------------------------
def keys_lines(keys: KeySequence, pose_lines: Callable[[Pose, str], list[str]]) -> list[str]:
    """The ``keys`` block; ``pose_lines(pose, indent)`` writes the pose fields."""
    out = [f"{_KEYS_KEY}:", f"  fps: {num(keys.fps)}",
           f"  length: {max(keys.length, max((f for f, _ in keys.keys), default=-1) + 1)}", "  poses:"]
    for frame, pose in keys.keys:
        out += [f"    - frame: {int(frame)}", *pose_lines(pose, "      ")]
    return out if keys.keys else out[:-1] + ["  poses: []"]


def poles_lines(poles: Mapping[str, Pole]) -> list[str]:
    """The ``poles`` block (empty when there are none)."""
    out = [f"{_POLES_KEY}:"] if poles else []
    for name, pole in poles.items():
        out += [f"  {yaml_string(name)}:", f"    position: {num_list(pole.position)}",
                f"    enabled: {'true' if pole.enabled else 'false'}"]
    return out


def clip_lines(clip: Clip) -> list[str]:
    """The ``clip`` block: every frame's root, root transform (rotation | position rows) and angles, exactly."""
    m = clip.motion
    out = [f"{_CLIP_KEY}:", f"  name: {yaml_string(clip.name)}", f"  frame_time: {num(m.frame_time)}",
           f"  dofs: [{', '.join(yaml_string(n) for n in m.skeleton.dof_names)}]", "  frames:"]
    for root, W, q in zip(m.roots, m.world_from_root, m.q):
        rows = ", ".join(num_list(row) for row in W[:3].tolist())
        out += [f"    - root: {yaml_string(root)}", f"      world_from_root: [{rows}]",
                f"      angles: {num_list(q.tolist())}"]
    return out


def num(x: float) -> str:
    """The shortest text YAML reads back as exactly ``x`` (PyYAML needs a dot before an exponent)."""
    text = repr(float(x))
    if "e" in text and "." not in text:
        text = text.replace("e", ".0e")
    return text


def num_list(values) -> str:
    return "[" + ", ".join(num(v) for v in values) + "]"
