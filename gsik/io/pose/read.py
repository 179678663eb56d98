"""Reading pose files: one bounded YAML pass, then the fields checked against the skeleton."""

from __future__ import annotations

import math
import os
from typing import Any, NamedTuple

from gsik.errors import PoseError, choices, show_value
from gsik.io.files import read_text
from gsik.io.yaml_safe import MAX_BYTES, load_yaml
from gsik.io.pose import legacy, sequence
from gsik.io.pose.model import (LIMIT_TOLERANCE, POSE_FORMAT, QUATERNION_NORM_TOLERANCE, SKELETON_FILE_SUFFIXES,
                               _CLIP_KEY, _KEYS_KEY, _LIBRARY_KEY, _OPTIONAL_TOP_KEYS, _POLES_KEY, _POSE_KEYS,
                               _TARGET_KEYS, _TOP_KEYS, _TRANSFORM_KEYS, Pose, PoseRead)
from gsik.skeleton import Skeleton
from gsik.targets import MAX_COORDINATE, MAX_WEIGHT, Target


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
            self.fail(path, f"keys must be names, got {_show(keys[0])}")
        unknown = [k for k in value if k not in required + optional]
        if unknown:
            self.fail(path + (unknown[0],), f"unknown field; valid fields: {choices(required + optional)}")
        missing = [k for k in required if k not in value]
        if missing:
            self.fail(path, f"missing field(s) {choices(missing)}")

    def number(self, value, path: tuple) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(path, f"must be a number, got {_show(value)}")
        try:
            v = float(value)
        except OverflowError:  # an integer beyond float's range
            v = math.inf
        if not math.isfinite(v):
            self.fail(path, f"must be a finite number, got {_show(value)}")
        return v

    def vector(self, value, n: int, path: tuple) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != n:
            self.fail(path, f"must be a list of {n} numbers, got {_show(value)}")
        return tuple(self.number(v, path + (i,)) for i, v in enumerate(value))

    def position(self, value, path: tuple) -> tuple[float, ...]:
        """A world position [m] within :data:`gsik.targets.MAX_COORDINATE` of the origin."""
        p = self.vector(value, 3, path)
        if max(abs(v) for v in p) > MAX_COORDINATE:
            self.fail(path, f"must be within {MAX_COORDINATE:g} m of the origin in x, y and z, got {list(p)}")
        return p

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

    def whole(self, value, path: tuple, maximum: int) -> int:
        """A whole number in [0, ``maximum``]."""
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= maximum:
            self.fail(path, f"must be a whole number from 0 to {maximum}, got {_show(value)}")
        return value

    def items(self, value, path: tuple, what: str) -> list:
        """A list (``what`` names its items in the message)."""
        if not isinstance(value, list):
            self.fail(path, f"must be a list of {what}, got {_show(value)}")
        return value


def _show(value) -> str:
    return "nothing" if value is None else show_value(value)


class PoseDocument(NamedTuple):
    """A pose file read and parsed once (bounded: :func:`gsik.io.yaml_safe.load_yaml`), not yet checked against
    a skeleton.

    Attributes:
        source: The file's path (or a label), named in messages.
        data: The parsed YAML (a mapping for a pose).
        lines: The line of every place in ``data``.
    """

    source: str
    data: Any
    lines: dict

    @property
    def skeleton(self) -> str | None:
        """The ``skeleton:`` field: a bundled skeleton's name, or a skeleton file's path (``.yaml``, ``.urdf``,
        ``.bvh``) made relative to the pose file's folder; ``None`` when the field is missing or not a name."""
        name = self.data.get("skeleton") if isinstance(self.data, dict) else None
        if not isinstance(name, str) or not name:
            return None
        if names_a_skeleton_file(name) and not os.path.isabs(name) and not self.source.startswith("<"):
            return os.path.join(os.path.dirname(self.source), name)
        return name


def names_a_skeleton_file(name: str) -> bool:
    """True if a pose's ``skeleton:`` field is a path to a skeleton file rather than a skeleton's name."""
    return os.path.splitext(name)[1].lower() in SKELETON_FILE_SUFFIXES or "/" in name or os.sep in name


def parse_pose(text: str, source: str = "<pose>") -> PoseDocument:
    """Parse pose YAML once; YAML errors, and anything the bounded reader refuses, become :class:`PoseError`."""
    doc = load_yaml(text, source, PoseError)
    if doc.data is None:
        raise PoseError(f"{source}: empty file, expected a gsik pose (format: {POSE_FORMAT})")
    return PoseDocument(source, doc.data, doc.lines)


def read_pose_document(path: str | os.PathLike) -> PoseDocument:
    """Read and parse a pose file once (:class:`GsikFileError` if it cannot be read)."""
    return parse_pose(read_text(path, "pose file", limit=MAX_BYTES), os.fspath(path))


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
    return pose_from_document(parse_pose(text, source), skeleton)


def pose_from_document(doc: PoseDocument, skeleton: Skeleton) -> PoseRead:
    """Validate a parsed pose file for ``skeleton`` (see :func:`pose_from_yaml`)."""
    r = _Reader(doc.source, doc.lines)
    top = r.mapping(doc.data, (), _TOP_KEYS, _OPTIONAL_TOP_KEYS)
    _check_header(r, top, skeleton)
    pose, warnings = _read_pose_fields(r, top, (), skeleton)
    library = _read_library(r, top.get(_LIBRARY_KEY, []), skeleton, warnings)

    def pose_at(fields: dict, at: tuple) -> Pose:
        key_pose, more = _read_pose_fields(r, fields, at, skeleton)
        warnings.extend(more)
        return key_pose

    keys = sequence.read_keys(r, top[_KEYS_KEY], pose_at) if _KEYS_KEY in top else None
    poles = sequence.read_poles(r, top.get(_POLES_KEY, {}), skeleton)
    clip = sequence.read_clip(r, top[_CLIP_KEY], skeleton) if _CLIP_KEY in top else None
    return PoseRead(pose, tuple(warnings), library, keys, poles, clip)


def _read_pose_fields(r: _Reader, fields: dict, at: tuple, skeleton: Skeleton) -> tuple[Pose, list[str]]:
    """One pose from the fields of :data:`_POSE_KEYS` found at key path ``at``; and its warnings."""
    root = _read_root(r, fields["root"], skeleton, at)
    rt = r.mapping(fields["root_transform"], at + ("root_transform",), _TRANSFORM_KEYS)
    root_position = r.position(rt["position"], at + ("root_transform", "position"))
    root_orientation = r.quaternion(rt["orientation"], at + ("root_transform", "orientation"))
    joints, warnings = _read_joints(r, fields["joints"], skeleton, at)
    targets = _read_targets(r, fields["targets"], tuple(n for n in skeleton.effector_sites if n != root), root, at)
    return Pose(skeleton.name, root, root_position, root_orientation, joints, targets), warnings


def _read_library(r: _Reader, entries, skeleton: Skeleton, warnings: list[str]) -> tuple[tuple[str, Pose], ...]:
    """The ``library`` list: one mapping per named pose (``name`` and the pose fields); names unique."""
    out: list[tuple[str, Pose]] = []
    for i, entry in enumerate(r.items(entries, (_LIBRARY_KEY,), "named poses")):
        at = (_LIBRARY_KEY, i)
        fields = r.mapping(entry, at, ("name", *_POSE_KEYS))
        name = r.name(fields["name"], at + ("name",))
        if name in dict(out):
            r.fail(at + ("name",), f"duplicate pose name {name!r}; names so far: {choices(dict(out))}")
        pose, more = _read_pose_fields(r, fields, at, skeleton)
        warnings += more
        out.append((name, pose))
    return tuple(out)


def _check_header(r: _Reader, top: dict, skeleton: Skeleton) -> None:
    """The format version and the skeleton's name (or its file's path: then the joints and effectors must fit)."""
    fmt = top["format"]
    if isinstance(fmt, bool) or not isinstance(fmt, int):
        r.fail(("format",), f"must be the whole number {POSE_FORMAT}, got {_show(fmt)}")
    if fmt != POSE_FORMAT:
        newer = " (written by a newer gsik?)" if fmt > POSE_FORMAT else ""
        r.fail(("format",), f"unsupported pose format {fmt}{newer}; this gsik reads format {POSE_FORMAT}")
    name = r.name(top["skeleton"], ("skeleton",))
    if name != skeleton.name and not names_a_skeleton_file(name):
        r.fail(("skeleton",), f"pose is for skeleton {_show(name)}, but the skeleton is {_show(skeleton.name)}")


def _read_root(r: _Reader, value, skeleton: Skeleton, at: tuple = ()) -> str:
    root = r.name(value, at + ("root",))
    if root not in skeleton.joint_names and root not in skeleton.site_names:
        r.fail(at + ("root",), f"unknown root {_show(root)}; valid: {choices(skeleton.effector_sites)} "
                          f"(or any joint or site: {choices(skeleton.joint_names + skeleton.site_names)})")
    return root


def _require_names(r: _Reader, given: dict, field: tuple, valid: tuple[str, ...], what: tuple[str, str],
                   why=lambda key: "") -> None:
    """Every key of ``given`` is one of ``valid`` and every one of ``valid`` is given; ``what``: (key, value) nouns."""
    for key in given:
        if key not in valid:
            r.fail(field + (key,), f"unknown {what[0]} {_show(key)}{why(key)}; valid: {choices(valid)}")
    missing = [n for n in valid if n not in given]
    if missing:
        r.fail(field, f"missing {what[1]}(s) for {choices(missing)}")


def _read_joints(r: _Reader, joints_in, skeleton: Skeleton, at: tuple = ()) -> tuple[dict[str, float], list[str]]:
    """``{DOF: angle [rad]}`` clamped into the limits, and one warning per clamped angle."""
    here = at + ("joints",)
    if not isinstance(joints_in, dict):
        r.fail(here, f"must be a mapping of DOF name to angle [rad], got {_show(joints_in)}")
    joints_in = legacy.joints(joints_in, skeleton.dof_names)
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
    targets_in = legacy.targets(targets_in, effectors)
    _require_names(r, targets_in, here, effectors, ("effector", "target"),
                   lambda key: " (it is the IK root)" if key == root else "")
    return {eff: _read_target(r, targets_in[eff], here + (eff,)) for eff in effectors}


def _read_target(r: _Reader, value, path: tuple) -> Target:
    t = r.mapping(value, path, _TARGET_KEYS[:2], _TARGET_KEYS[2:])
    weight = r.number(t.get("weight", 1.0), path + ("weight",))
    if not 0 <= weight <= MAX_WEIGHT:
        r.fail(path + ("weight",), f"must be >= 0 and at most {MAX_WEIGHT:g}, got {weight!r}")
    priority = t.get("priority", 0)
    if isinstance(priority, bool) or not isinstance(priority, int) or priority < 0:
        r.fail(path + ("priority",), f"must be a whole number >= 0, got {_show(priority)}")
    return Target(
        position=r.position(t["position"], path + ("position",)),
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
    return pose_from_document(read_pose_document(path), skeleton)
