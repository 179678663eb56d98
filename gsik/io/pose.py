"""Poses as YAML files: joint angles, the pinned root and every effector target.

A pose file is plain YAML, readable and editable by hand::

    # gsik pose
    format: 1                   # version of this format
    skeleton: biped             # the skeleton's name; must match the skeleton it is loaded on
    root: right_foot            # the IK root: a joint or site, pinned to the world
    root_transform:             # world transform of the root frame
      position: [0.09, 0.0505, 0.0]        # [m]
      orientation: [1.0, 0.0, 0.0, 0.0]    # unit quaternion (w, x, y, z)
    joints:                     # every degree of freedom by name, angle [rad]
      waist.x: 0.0
      waist.y: 0.0
      # ... one line per DOF, all of them (see Skeleton.dof_names)
    targets:                    # every effector of this root (all effector sites but the root)
      left_hand:
        position: [-0.19, 0.049, 0.753]    # world position [m]
        orientation: [1.0, 0.0, 0.0, 0.0]  # world orientation, unit quaternion (w, x, y, z)
        enabled: true           # optional, default true: false leaves the effector free
        weight: 1.0             # optional, default 1.0: relative importance, >= 0
        position_only: false    # optional, default false: true ignores the orientation
        priority: 0             # optional, default 0: strict priority level (0 the most important)
      # ... one entry per effector

Rules:

- Angles are radians, lengths metres, in the skeleton's world frame
  (for the bundled biped: z up, facing +y, right side +x).
- ``format``, ``skeleton``, ``root``, ``root_transform``, ``joints`` and
  ``targets`` are required; so are every DOF of the skeleton and every
  effector of the root, each with ``position`` and ``orientation``.
- Unknown keys, unknown joints or effectors, a target for the root itself,
  NaN or infinite numbers and quaternions that are not of unit norm
  (within 1 %) are errors (:class:`gsik.PoseError`, naming the file, the
  line, the field and the value). A quaternion a little off unit norm is
  normalised.
- An angle outside its joint's limits is clamped into them and reported as
  a warning in :attr:`PoseRead.warnings` (never silently).
- A file may also hold a ``library``: a list of named poses, each a mapping
  of ``name`` (unique) and the four pose fields above (``root``,
  ``root_transform``, ``joints``, ``targets``), read into
  :attr:`PoseRead.library`. A file without it is a single pose, as before.
- Numbers are written with Python's shortest exact ``repr``, so writing a
  pose and reading it back gives exactly the same numbers.

:func:`write_pose` replaces the file atomically: a failed save leaves an
existing file untouched. This module needs NumPy and PyYAML only.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np
import yaml

from gsik import validate
from gsik.errors import PoseError, choices
from gsik.io.files import atomic_write_text, read_text
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
                value = _floats([value], 1, f"joint {name!r}")[0]
            joints[str(name)] = value
        targets = {}
        for name, t in dict(self.targets).items():
            if not isinstance(t, Target):
                raise PoseError(f"target {name!r} must be a gsik.Target, got {type(t).__name__}")
            targets[str(name)] = t
        object.__setattr__(self, "joints", MappingProxyType(joints))
        object.__setattr__(self, "targets", MappingProxyType(targets))

    def q(self, skeleton: Skeleton) -> np.ndarray:
        """The angles (n_dofs,) [rad] in ``skeleton``'s DOF order."""
        try:
            return np.array([self.joints[n] for n in skeleton.dof_names])
        except KeyError as exc:
            raise PoseError(f"pose has no angle for {exc.args[0]!r}") from None

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


class PoseRead(NamedTuple):
    """What reading a pose file gives.

    Attributes:
        pose: The validated :class:`Pose` (angles clamped into the limits).
        warnings: One sentence per problem that was repaired (an angle
            clamped into its limits); empty when the file was clean.
        library: The file's named poses ``((name, Pose), ...)`` in file order
            (empty for a single-pose file).
    """

    pose: Pose
    warnings: tuple[str, ...]
    library: tuple[tuple[str, Pose], ...] = ()


# -- reading -----------------------------------------------------------------

def _key_lines(node: yaml.Node, path: tuple, lines: dict, where: str) -> None:
    """Record the 1-based line of every mapping key / sequence item; reject duplicate keys."""
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        seen: dict[Any, int] = {}
        for key_node, value_node in node.value:
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            line = key_node.start_mark.line + 1
            if key in seen:
                raise PoseError(f"{where}:{line}: duplicate key {key!r} (first at line {seen[key]})")
            seen[key] = line
            _key_lines(value_node, path + (key,), lines, where)
            lines[path + (key,)] = line  # the key's line, not its value's
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _key_lines(item, path + (i,), lines, where)


class _Reader:
    """Validates parsed YAML, naming file, line and field in every error."""

    def __init__(self, source: str, lines: dict):
        self.source = source
        self.lines = lines

    def fail(self, path: tuple, message: str):
        line = None
        p = path
        while p and line is None:
            line = self.lines.get(p)
            p = p[:-1]
        where = self.source if line is None else f"{self.source}:{line}"
        field = ".".join(str(k) for k in path)
        raise PoseError(f"{where}: {field}: {message}" if field else f"{where}: {message}")

    def mapping(self, value, path: tuple, required: tuple[str, ...], optional: tuple[str, ...] = ()) -> dict:
        if not isinstance(value, dict):
            self.fail(path, f"must be a mapping of {', '.join(required + optional)}, got {_show(value)}")
        self._keys(value, path, required, optional)
        return value

    def _keys(self, value: dict, path: tuple, required: tuple[str, ...], optional: tuple[str, ...]) -> None:
        """Names only, none unknown, none of ``required`` missing."""
        keys = [k for k in value if not isinstance(k, str)]
        if keys:
            self.fail(path, f"keys must be names, got {keys[0]!r}")
        unknown = [k for k in value if k not in required + optional]
        if unknown:
            self.fail(path + (unknown[0],), f"unknown field; valid fields: {choices(required + optional)}")
        missing = [k for k in required if k not in value]
        if missing:
            self.fail(path, f"missing field(s) {choices(missing)}")

    def number(self, value, path: tuple) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(path, f"must be a number, got {_show(value)}")
        v = float(value)
        if not math.isfinite(v):
            self.fail(path, f"must be a finite number, got {value!r}")
        return v

    def vector(self, value, n: int, path: tuple) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != n:
            self.fail(path, f"must be a list of {n} numbers, got {_show(value)}")
        return tuple(self.number(v, path + (i,)) for i, v in enumerate(value))

    def quaternion(self, value, path: tuple) -> tuple[float, ...]:
        q = self.vector(value, 4, path)
        norm = math.sqrt(sum(v * v for v in q))
        if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
            self.fail(path, f"must be a unit quaternion [w, x, y, z], got {list(q)} (norm {norm:.6g})")
        if abs(norm - 1.0) > 1e-12:  # leave exact round-trip values alone
            q = tuple(v / norm for v in q)
        return q

    def flag(self, value, path: tuple) -> bool:
        if not isinstance(value, bool):
            self.fail(path, f"must be true or false, got {_show(value)}")
        return value

    def name(self, value, path: tuple) -> str:
        if not isinstance(value, str) or not value:
            self.fail(path, f"must be a name, got {_show(value)}")
        return value


def _show(value) -> str:
    if value is None:
        return "nothing"
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def pose_from_yaml(text: str, skeleton: Skeleton, source: str = "<pose>") -> PoseRead:
    """Parse and validate pose YAML for ``skeleton``.

    Args:
        text: The YAML text.
        skeleton: The skeleton the pose must fit (name, DOFs, effectors).
        source: Name used in error messages (usually the file path).

    Returns:
        :class:`PoseRead`: the pose, and warnings about angles clamped into their limits.

    Raises:
        PoseError: naming ``source``, the line, the field and the bad value.
    """
    data, lines = _parse(text, source)
    r = _Reader(source, lines)
    top = r.mapping(data, (), _TOP_KEYS, (_LIBRARY_KEY,))
    _check_header(r, top, skeleton)
    pose, warnings = _read_pose_fields(r, top, (), skeleton)
    library = _read_library(r, top.get(_LIBRARY_KEY, []), skeleton, warnings)
    return PoseRead(pose, tuple(warnings), library)


def _read_pose_fields(r: _Reader, fields: dict, at: tuple, skeleton: Skeleton) -> tuple[Pose, list[str]]:
    """One pose from the fields of :data:`_POSE_KEYS` found at key path ``at``; and its warnings."""
    root = _read_root(r, fields["root"], skeleton, at)
    rt = r.mapping(fields["root_transform"], at + ("root_transform",), _TRANSFORM_KEYS)
    root_position = r.vector(rt["position"], 3, at + ("root_transform", "position"))
    root_orientation = r.quaternion(rt["orientation"], at + ("root_transform", "orientation"))
    joints, warnings = _read_joints(r, fields["joints"], skeleton, at)
    targets = _read_targets(r, fields["targets"], tuple(n for n in skeleton.effector_sites if n != root), root, at)
    return Pose(skeleton.name, root, root_position, root_orientation, joints, targets), warnings


def _read_library(r: _Reader, entries, skeleton: Skeleton, warnings: list[str]) -> tuple[tuple[str, Pose], ...]:
    """The ``library`` list: one mapping per named pose (``name`` and the pose fields); names unique."""
    if not isinstance(entries, list):
        r.fail((_LIBRARY_KEY,), f"must be a list of named poses, got {_show(entries)}")
    out: list[tuple[str, Pose]] = []
    for i, entry in enumerate(entries):
        at = (_LIBRARY_KEY, i)
        fields = r.mapping(entry, at, ("name", *_POSE_KEYS))
        name = r.name(fields["name"], at + ("name",))
        if name in dict(out):
            r.fail(at + ("name",), f"duplicate pose name {name!r}; names so far: {choices(dict(out))}")
        pose, more = _read_pose_fields(r, fields, at, skeleton)
        warnings += more
        out.append((name, pose))
    return tuple(out)


def _parse(text: str, source: str) -> tuple[Any, dict]:
    """The YAML data and the line of every key path; YAML errors become :class:`PoseError`."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.load(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = f":{mark.line + 1}" if mark is not None else ""
        problem = exc.problem or exc.context or "malformed YAML"
        raise PoseError(f"{source}{line}: not valid YAML: {problem}") from None
    except yaml.YAMLError as exc:
        raise PoseError(f"{source}: not valid YAML: {exc}") from None
    if node is None:
        raise PoseError(f"{source}: empty file, expected a gsik pose (format: {POSE_FORMAT})")
    lines: dict = {}
    _key_lines(node, (), lines, source)
    return data, lines


def _check_header(r: _Reader, top: dict, skeleton: Skeleton) -> None:
    """The format version and the skeleton's name."""
    fmt = top["format"]
    if isinstance(fmt, bool) or not isinstance(fmt, int):
        r.fail(("format",), f"must be the whole number {POSE_FORMAT}, got {_show(fmt)}")
    if fmt != POSE_FORMAT:
        newer = " (written by a newer gsik?)" if fmt > POSE_FORMAT else ""
        r.fail(("format",), f"unsupported pose format {fmt}{newer}; this gsik reads format {POSE_FORMAT}")
    name = r.name(top["skeleton"], ("skeleton",))
    if name != skeleton.name:
        r.fail(("skeleton",), f"pose is for skeleton {name!r}, but the skeleton is {skeleton.name!r}")


def _read_root(r: _Reader, value, skeleton: Skeleton, at: tuple = ()) -> str:
    root = r.name(value, at + ("root",))
    if root not in skeleton.joint_names and root not in skeleton.site_names:
        r.fail(at + ("root",), f"unknown root {root!r}; valid: {choices(skeleton.effector_sites)} "
                          f"(or any joint or site: {choices(skeleton.joint_names + skeleton.site_names)})")
    return root


def _require_names(r: _Reader, given: dict, field: tuple, valid: tuple[str, ...], what: tuple[str, str],
                   why=lambda key: "") -> None:
    """Every key of ``given`` is one of ``valid`` and every one of ``valid`` is given; ``what``: (key, value) nouns."""
    for key in given:
        if key not in valid:
            r.fail(field + (key,), f"unknown {what[0]} {key!r}{why(key)}; valid: {choices(valid)}")
    missing = [n for n in valid if n not in given]
    if missing:
        r.fail(field, f"missing {what[1]}(s) for {choices(missing)}")


def _read_joints(r: _Reader, joints_in, skeleton: Skeleton, at: tuple = ()) -> tuple[dict[str, float], list[str]]:
    """``{DOF: angle [rad]}`` clamped into the limits, and one warning per clamped angle."""
    here = at + ("joints",)
    if not isinstance(joints_in, dict):
        r.fail(here, f"must be a mapping of DOF name to angle [rad], got {_show(joints_in)}")
    _require_names(r, joints_in, here, skeleton.dof_names, ("joint", "angle"))
    joints, warnings = {}, []
    for i, dof in enumerate(skeleton.dof_names):
        v = r.number(joints_in[dof], here + (dof,))
        lo, hi = float(skeleton.lower[i]), float(skeleton.upper[i])
        if v < lo - LIMIT_TOLERANCE or v > hi + LIMIT_TOLERANCE:
            clamped = min(max(v, lo), hi)
            field = ".".join(str(k) for k in here + (dof,))
            warnings.append(f"{r.source}:{r.lines.get(here + (dof,))}: {field}: angle {v!r} rad is outside "
                            f"its limits [{lo!r}, {hi!r}]; clamped to {clamped!r}")
            v = clamped
        joints[dof] = v
    return joints, warnings


def _read_targets(r: _Reader, targets_in, effectors: tuple[str, ...], root: str,
                  at: tuple = ()) -> dict[str, Target]:
    here = at + ("targets",)
    if not isinstance(targets_in, dict):
        r.fail(here, f"must be a mapping of effector name to target, got {_show(targets_in)}")
    _require_names(r, targets_in, here, effectors, ("effector", "target"),
                   lambda key: " (it is the IK root)" if key == root else "")
    return {eff: _read_target(r, targets_in[eff], here + (eff,)) for eff in effectors}


def _read_target(r: _Reader, value, path: tuple) -> Target:
    t = r.mapping(value, path, _TARGET_KEYS[:2], _TARGET_KEYS[2:])
    weight = r.number(t.get("weight", 1.0), path + ("weight",))
    if weight < 0:
        r.fail(path + ("weight",), f"must be >= 0, got {weight!r}")
    priority = t.get("priority", 0)
    if isinstance(priority, bool) or not isinstance(priority, int) or priority < 0:
        r.fail(path + ("priority",), f"must be a whole number >= 0, got {_show(priority)}")
    return Target(
        position=r.vector(t["position"], 3, path + ("position",)),
        orientation=r.quaternion(t["orientation"], path + ("orientation",)),
        weight=weight,
        position_only=r.flag(t.get("position_only", False), path + ("position_only",)),
        enabled=r.flag(t.get("enabled", True), path + ("enabled",)),
        priority=priority,
    )


def read_pose(path: str | os.PathLike, skeleton: Skeleton) -> PoseRead:
    """Read and validate a pose file for ``skeleton``.

    Raises:
        GsikFileError: the file cannot be read.
        PoseError: the file is not a valid pose for ``skeleton`` (see the module docstring).
    """
    return pose_from_yaml(read_text(path, "pose file"), skeleton, os.fspath(path))


# -- writing -----------------------------------------------------------------

def _num(x: float) -> str:
    """The shortest text YAML reads back as exactly ``x`` (PyYAML needs a dot before an exponent)."""
    text = repr(float(x))
    if "e" in text and "." not in text:
        text = text.replace("e", ".0e")
    return text


def _list(values) -> str:
    return "[" + ", ".join(_num(v) for v in values) + "]"


def _name(text: str) -> str:
    """A YAML key or value for a name: plain when it reads back as the same string, else quoted."""
    try:
        plain = yaml.safe_load(f"{text}: 0") if text else None
    except yaml.YAMLError:  # "a: b" is not a plain key
        plain = None
    if isinstance(plain, dict) and list(plain) == [text]:
        return text
    return yaml.safe_dump(text, default_style='"').strip().removesuffix("...").strip()


def _pose_lines(pose: Pose, indent: str) -> list[str]:
    """The lines of the pose fields (:data:`_POSE_KEYS`), each starting with ``indent``."""
    out = [
        f"root: {_name(pose.root)}",
        "root_transform:",
        f"  position: {_list(pose.root_position)}",
        f"  orientation: {_list(pose.root_orientation)}",
        "joints:",
    ]
    out += [f"  {_name(n)}: {_num(v)}" for n, v in pose.joints.items()]
    out.append("targets:" if pose.targets else "targets: {}")
    for n, t in pose.targets.items():
        out += [
            f"  {_name(n)}:",
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
        f"skeleton: {_name(pose.skeleton)}",
        *_pose_lines(pose, ""),
    ]
    if library:
        out.append(f"{_LIBRARY_KEY}:")
        for name, p in library:
            if p.skeleton != pose.skeleton:
                raise PoseError(f"library pose {name!r} is for skeleton {p.skeleton!r}, not {pose.skeleton!r}")
            lines = _pose_lines(p, "    ")
            out += [f"  - name: {_name(name)}", *lines]
    return "\n".join(out) + "\n"


def write_pose(path: str | os.PathLike, pose: Pose, library: Sequence[tuple[str, Pose]] = ()) -> None:
    """Write ``pose`` (and a ``library`` of named poses, if any) to ``path`` atomically (temporary file, fsync, rename).

    Raises:
        GsikFileError: the file cannot be written; an existing file is left untouched.
    """
    if not isinstance(pose, Pose):
        raise PoseError(f"write_pose needs a Pose, got {type(pose).__name__}")
    atomic_write_text(path, pose_to_yaml(pose, library))
