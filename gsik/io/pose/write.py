"""Writing pose files: shortest exact numbers, names quoted only where YAML needs it, atomic replace."""

from __future__ import annotations

import os
from collections.abc import Sequence

from gsik.errors import PoseError
from gsik.io.files import atomic_write_text
from gsik.io.yaml_safe import yaml_string
from gsik.io.pose.model import _LIBRARY_KEY, POSE_FORMAT, Pose


def _num(x: float) -> str:
    """The shortest text YAML reads back as exactly ``x`` (PyYAML needs a dot before an exponent)."""
    text = repr(float(x))
    if "e" in text and "." not in text:
        text = text.replace("e", ".0e")
    return text


def _list(values) -> str:
    return "[" + ", ".join(_num(v) for v in values) + "]"


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


def pose_to_yaml(pose: Pose, library: Sequence[tuple[str, Pose]] = ()) -> str:
    """The YAML text of ``pose`` (the format of the module docstring), with a ``library`` list of named poses if any."""
    out = [
        "# gsik pose (format documented in gsik/pose.py); angles [rad], lengths [m], quaternions (w, x, y, z)",
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
    return "\n".join(out) + "\n"


def write_pose(path: str | os.PathLike, pose: Pose, library: Sequence[tuple[str, Pose]] = ()) -> None:
    """Write ``pose`` (and a ``library`` of named poses, if any) to ``path`` atomically (temporary file, fsync, rename).

    Raises:
        GsikFileError: the file cannot be written; an existing file is left untouched.
    """
    if not isinstance(pose, Pose):
        raise PoseError(f"write_pose needs a Pose, got {type(pose).__name__}")
    atomic_write_text(path, pose_to_yaml(pose, library))
