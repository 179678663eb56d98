"""Writing pose files: shortest exact numbers, names quoted only where YAML needs it, atomic replace."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

from gsik.errors import PoseError
from gsik.io.files import atomic_write_text
from gsik.io.pose.model import _LIBRARY_KEY, POSE_FORMAT, Clip, KeySequence, Pole, Pose
from gsik.anim.motion import Motion
from gsik.io.pose.sequence import check_clip_frames, clip_lines, keys_lines, num as _num, num_list as _list, poles_lines
from gsik.io.yaml_safe import MAX_CHARS, MAX_VALUES, load_yaml, yaml_string
from gsik.skeleton import Skeleton


def _pose_lines(pose: Pose, indent: str) -> list[str]:
    """The lines of the pose fields (:data:`_POSE_KEYS`), each starting with ``indent``."""
    out = [
        f"root: {yaml_string(pose.root)}",
        "root_transform:",
        f"  position: {_list(pose.root_position)}",
        f"  orientation: {_list(pose.root_orientation)}",
        "joints:",
    ]
    out += [f"  {yaml_string(n)}: {_num(v)}" for n, v in pose.joints.items()]
    out.append("targets:" if pose.targets else "targets: {}")
    for n, t in pose.targets.items():
        out += [
            f"  {yaml_string(n)}:",
            f"    position: {_list(t.position)}",
            f"    orientation: {_list(t.orientation)}",
            f"    enabled: {'true' if t.enabled else 'false'}",
            f"    weight: {_num(t.weight)}",
            f"    position_only: {'true' if t.position_only else 'false'}",
        ]
        if t.priority:  # written only when set: files of single-level poses stay as they were
            out.append(f"    priority: {t.priority}")
    return [indent + line for line in out]


def pose_to_yaml(pose: Pose, library: Sequence[tuple[str, Pose]] = (), keys: KeySequence | None = None,
                 poles: Mapping[str, Pole] | None = None, clip: Clip | None = None,
                 skeleton: Skeleton | None = None) -> str:
    """The YAML text of ``pose`` (the format of :mod:`gsik.io.pose`), with what else the file keeps, if any:
    a ``library`` list of named poses, a ``keys`` sequence, ``poles`` and a ``clip``.

    The text is read back before it is returned, so gsik never writes a file it would refuse: with ``skeleton``
    (or the clip's) in full, as :func:`gsik.io.pose.pose_from_yaml` reads it; without one, a long text through the
    bounded YAML reader.

    Raises:
        PoseError: a library pose, key or clip is for another skeleton, or the text would not read back (longer
            than :data:`gsik.io.yaml_safe.MAX_CHARS`: a clip of too many frames; a value the reader refuses).
    """
    out = [
        "# gsik pose (format: gsik/io/pose/__init__.py); angles [rad], lengths [m], quaternions (w, x, y, z)",
        f"format: {POSE_FORMAT}",
        f"skeleton: {yaml_string(pose.skeleton)}",
        *_pose_lines(pose, ""),
    ]
    if library:
        out.append(f"{_LIBRARY_KEY}:")
        for name, p in library:
            if p.skeleton != pose.skeleton:
                raise PoseError(f"library pose {name!r} is for skeleton {p.skeleton!r}, not {pose.skeleton!r}")
            lines = _pose_lines(p, "    ")
            out += [f"  - name: {yaml_string(name)}", *lines]
    _check_skeletons(pose.skeleton, keys, clip)
    if keys is not None:
        out += keys_lines(keys, _pose_lines)
    out += poles_lines(poles or {})
    text = "\n".join(out + (clip_lines(clip) if clip is not None else [])) + "\n"
    _check_readable(text, clip)
    skeleton = skeleton if skeleton is not None else clip.motion.skeleton if clip is not None else None
    if skeleton is not None:
        _check_round_trip(out, clip, skeleton)
    return text


def _check_round_trip(lines: list[str], clip: Clip | None, skeleton: Skeleton) -> None:
    """PoseError unless :func:`gsik.io.pose.pose_from_yaml` reads the file for ``skeleton``: every block but the
    clip's frames read back as written (``lines``), the clip with its first frame only, and every frame's values
    checked as the reader checks them (:func:`gsik.io.pose.sequence.check_clip_frames`), in one pass over arrays:
    reading a long clip back would take seconds."""
    from gsik.io.pose.read import pose_from_yaml  # read imports this module's neighbours: late, to avoid a cycle

    try:
        if clip is not None:
            check_clip_frames(clip.motion, skeleton)
            m = clip.motion
            first = Clip(clip.name, Motion(m.skeleton, m.q[:1], m.roots[:1], m.world_from_root[:1], m.frame_time))
            lines = lines + clip_lines(first)
        pose_from_yaml("\n".join(lines) + "\n", skeleton, "the pose file")
    except PoseError as exc:
        raise PoseError(f"gsik would not read this pose file back ({exc}); nothing was written") from None


def _check_readable(text: str, clip: Clip | None) -> None:
    """PoseError unless the bounded reader reads ``text`` back (a clip of too many frames)."""
    if len(text) <= min(MAX_CHARS, MAX_VALUES):  # every value takes a character: no limit can be reached
        return
    what = f" (the clip {clip.name!r} has {clip.motion.n_frames} frames)" if clip is not None else ""
    try:
        load_yaml(text, "the pose file", PoseError)
    except PoseError as exc:
        raise PoseError(f"{exc}{what}; a pose file must stay within what gsik reads back: discard or shorten the "
                        f"clip to save") from None


def _check_skeletons(skeleton: str, keys: KeySequence | None, clip: Clip | None) -> None:
    """Every key and the clip are of the pose's skeleton (PoseError naming the first that is not)."""
    parts = [(f"key at frame {f}", p.skeleton) for f, p in keys.keys] if keys is not None else []
    if clip is not None:
        parts.append((f"clip {clip.name!r}", clip.motion.skeleton.name))
    for what, name in parts:
        if name != skeleton:
            raise PoseError(f"{what} is for skeleton {name!r}, not {skeleton!r}")


def write_pose(path: str | os.PathLike, pose: Pose, library: Sequence[tuple[str, Pose]] = (),
               keys: KeySequence | None = None, poles: Mapping[str, Pole] | None = None,
               clip: Clip | None = None, skeleton: Skeleton | None = None) -> None:
    """Write ``pose`` (and a ``library``, ``keys``, ``poles``, ``clip``, if any: see :func:`pose_to_yaml`) to
    ``path`` atomically (temporary file, fsync, rename).

    Raises:
        GsikFileError: the file cannot be written; an existing file is left untouched.
        PoseError: see :func:`pose_to_yaml`; nothing was written.
    """
    if not isinstance(pose, Pose):
        raise PoseError(f"write_pose needs a Pose, got {type(pose).__name__}")
    atomic_write_text(path, pose_to_yaml(pose, library, keys, poles, clip, skeleton))
