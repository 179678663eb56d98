"""Reading skeleton definitions from YAML (schema: ``skeletons/README.md``)."""

from __future__ import annotations

import os
from pathlib import Path

from gsik.errors import GsikFileError, SkeletonError, choices, show_value
from gsik import validate
from gsik.io.bundled import bundled_dir
from gsik.io.files import read_text
from gsik.io.yaml_safe import MAX_BYTES, load_yaml
from gsik.rotations import matrix_from_quaternion
from gsik.skeleton_builder import check_size
from gsik.skeleton import AXES, JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton

FORMAT_VERSION = 1


def _bundled_dir() -> Path:
    """The folder of the bundled skeletons (:func:`gsik.io.bundled.bundled_dir`)."""
    return bundled_dir()


def bundled_skeletons() -> tuple[str, ...]:
    """Names of the skeletons shipped with gsik (``"biped"``, ...)."""
    return tuple(sorted(p.stem for p in _bundled_dir().glob("*.yaml")))


def load_skeleton(name_or_path: str | os.PathLike) -> Skeleton:
    """Load a bundled skeleton by name (``"biped"``) or a skeleton YAML file by path.

    Raises:
        SkeletonError: unknown bundled name (listing the valid ones), a file
            that cannot be read, malformed YAML, or an invalid definition;
            the message names the file, the field and the bad value.
    """
    s = os.fspath(name_or_path)
    path = Path(s)
    if not (path.suffix in (".yaml", ".yml") or os.sep in s or path.exists()):
        bundled = bundled_skeletons()
        if s not in bundled:
            raise SkeletonError(f"no bundled skeleton {show_value(s)}; bundled: {choices(bundled)} (or give a path to a .yaml file)")
        path = _bundled_dir() / f"{s}.yaml"
    try:
        text = read_text(path, "skeleton file", limit=MAX_BYTES)
    except GsikFileError as exc:  # a skeleton that cannot be loaded is a SkeletonError, whatever the cause
        raise SkeletonError(str(exc)) from None
    return skeleton_from_yaml(text, source=str(path))


def skeleton_from_yaml(text: str, source: str = "<string>") -> Skeleton:
    """Parse and compile a skeleton from YAML text (read by :func:`gsik.io.yaml_safe.load_yaml`: bounded)."""
    doc = load_yaml(text, source, SkeletonError)
    return skeleton_from_dict(doc.data, source, doc.lines)


class _Fields:
    """Reads one mapping of a YAML document, naming the file, line and place in every error.

    ``path`` is the mapping's place in the document (``("joints", 3)``); ``lines`` maps such places to lines
    (empty for data that did not come from a file).
    """

    def __init__(self, data, where: str, source: str, path: tuple = (), lines: dict | None = None):
        self.where = where
        self.source = source
        self.path = path
        self.lines = lines or {}
        if not isinstance(data, dict):
            self.fail(f"must be a mapping, got {type(data).__name__}")
        self.data = data

    def child(self, data, where: str, *keys) -> _Fields:
        """The fields of a mapping inside this one, at ``keys`` below it."""
        return _Fields(data, where, self.source, self.path + keys, self.lines)

    def fail(self, msg: str, *keys):
        """Raise a :class:`SkeletonError` at ``keys`` below this mapping (its nearest known line)."""
        path = self.path + keys
        line = next((self.lines[path[:n]] for n in range(len(path), 0, -1) if path[:n] in self.lines), None)
        at = f", line {line}" if line is not None else ""
        raise SkeletonError(f"{self.source}: {self.where}{at}: {msg}")

    def check_keys(self, allowed: tuple[str, ...]) -> None:
        unknown = [k for k in self.data if k not in allowed]
        if unknown:
            self.fail(f"unknown field {show_value(unknown[0])}; valid fields: {choices(allowed)}", unknown[0])

    def get(self, key: str, default=...):
        if key not in self.data:
            if default is ...:
                self.fail(f"missing field {key!r}")
            return default
        return self.data[key]

    def checked(self, check, *args, at: tuple = ()):
        """``check(*args, SkeletonError)`` from :mod:`gsik.validate`, its error naming this place."""
        try:
            return check(*args, SkeletonError)
        except SkeletonError as exc:
            self.fail(str(exc), *at)

    def name(self, key: str = "name", default=...) -> str | None:
        v = self.get(key, default)
        if v is None and default is None:
            return None
        return self.checked(validate.name, v, key, at=(key,))

    def number(self, value, what: str, *at) -> float:
        return self.checked(validate.number, value, what, at=at)

    def vector(self, key: str, n: int = 3, default=...) -> tuple[float, ...]:
        v = self.get(key, default)
        if v is default and default is not ...:
            return default
        if not isinstance(v, (list, tuple)) or len(v) != n:
            self.fail(f"{key} must be a list of {n} numbers, got {show_value(v)}", key)
        return tuple(self.number(x, f"{key}[{i}]", key, i) for i, x in enumerate(v))

    def orientation(self, key: str = "orientation"):
        q = self.get(key, None)
        if q is None:
            return None
        self.vector(key, 4)
        return matrix_from_quaternion(self.checked(validate.unit_quaternion, q, key, at=(key,)))


def _axis(f: _Fields, value) -> tuple[float, float, float]:
    if isinstance(value, str):
        v = value.strip().lower()
        sign = -1.0 if v.startswith("-") else 1.0
        v = v.lstrip("+-")
        if v not in AXES:
            f.fail(f"axis must be x, y, z (optionally with a sign) or 3 numbers, got {show_value(value)}", "axis")
        return tuple(sign * c for c in AXES[v])
    if isinstance(value, (list, tuple)) and len(value) == 3:
        return tuple(f.number(c, "axis", "axis", i) for i, c in enumerate(value))
    f.fail(f"axis must be x, y, z (optionally with a sign) or 3 numbers, got {show_value(value)}", "axis")


def _rotation(f: _Fields, data, k: int) -> RotationSpec:
    r = f.child(data, f"{f.where}: rotations[{k}]", "rotations", k)
    r.check_keys(("axis", "limits", "rest", "label"))
    raw_axis = r.get("axis")
    axis = _axis(r, raw_axis)
    limits = r.get("limits")
    if not isinstance(limits, (list, tuple)) or len(limits) != 2:
        r.fail(f"limits must be [lower, upper] in rad, got {show_value(limits)}", "limits")
    lo, hi = (r.number(x, f"limits[{i}]", "limits", i) for i, x in enumerate(limits))
    rest = r.number(r.get("rest", 0.0), "rest", "rest")  # limits and rest are checked once, by build_skeleton
    label = r.get("label", None)
    if label is None and isinstance(raw_axis, str):
        label = raw_axis.strip().lower().lstrip("+-")
    return RotationSpec(axis, lo, hi, rest, label or "")


def skeleton_from_dict(data, source: str = "<memory>", lines: dict | None = None) -> Skeleton:
    """Validate a parsed YAML document and compile it into a :class:`Skeleton`.

    ``lines`` maps places in ``data`` to file lines (as :func:`gsik.io.yaml_safe.load_yaml` gives), so errors
    name the line too.
    """
    top = _Fields(data, "top level", source, (), lines)
    top.check_keys(("format", "name", "description", "units", "up", "root", "effectors", "joints", "sites", "segments"))
    version = top.get("format", FORMAT_VERSION)
    if version != FORMAT_VERSION:
        top.fail(f"format {show_value(version)} is not supported; this gsik reads format {FORMAT_VERSION}", "format")
    if top.get("units", "m") != "m":
        top.fail(f"units must be 'm' (metres), got {show_value(top.get('units'))}", "units")
    name = top.name("name")
    joints_data = top.get("joints")
    if not isinstance(joints_data, list) or not joints_data:
        top.fail(f"joints must be a non-empty list, got {show_value(joints_data)}", "joints")
    check_size(0, len(joints_data), source)  # a joint is at least a frame: refuse a huge file before reading on
    joints = [_joint(top.child(jd, f"joints[{i}]", "joints", i), i) for i, jd in enumerate(joints_data)]
    sites = [_site(top.child(sd, f"sites[{i}]", "sites", i)) for i, sd in enumerate(_list(top, "sites"))]
    segments = [_segment(top.child(sd, f"segments[{i}]", "segments", i))
                for i, sd in enumerate(_list(top, "segments"))]
    effectors = _list(top, "effectors")
    for i, e in enumerate(effectors):
        if not isinstance(e, str):
            top.fail(f"effectors must be a list of site names, got {show_value(e)}", "effectors", i)
    root = top.name("root", None)
    return build_skeleton(name, joints, sites, segments, effectors, root, source)


def _joint(f: _Fields, i: int) -> JointSpec:
    jname = f.name()
    f.where = f"joints[{i}] ({jname if len(jname) <= 60 else jname[:57] + '...'})"
    f.check_keys(("name", "parent", "offset", "rotations", "orientation"))
    rots = f.get("rotations", [])
    if not isinstance(rots, list):
        f.fail(f"rotations must be a list, got {show_value(rots)}", "rotations")
    return JointSpec(
        name=jname,
        parent=f.name("parent", None),
        offset=f.vector("offset", default=(0.0, 0.0, 0.0)),
        rotations=tuple(_rotation(f, r, k) for k, r in enumerate(rots)),
        orientation=f.orientation(),
    )


def _site(f: _Fields) -> SiteSpec:
    f.check_keys(("name", "parent", "offset", "orientation", "sole"))
    sole = f.get("sole", None)
    if sole is not None:
        if not isinstance(sole, list) or not all(isinstance(c, (list, tuple)) and len(c) == 2 for c in sole):
            f.fail(f"sole must be a list of [x, y] corners [m], got {show_value(sole)}", "sole")
        sole = tuple((f.number(c[0], "sole x", "sole", i), f.number(c[1], "sole y", "sole", i))
                     for i, c in enumerate(sole))
    return SiteSpec(f.name(), f.name("parent"), f.vector("offset", default=(0.0, 0.0, 0.0)), f.orientation(), sole)


def _segment(f: _Fields) -> SegmentSpec:
    f.check_keys(("name", "from", "to", "mass", "com"))
    to = f.get("to")
    ends = [to] if isinstance(to, str) else to
    if not isinstance(ends, list) or not ends or not all(isinstance(e, str) and e for e in ends):
        f.fail(f"to must be a joint or site name or a list of them, got {show_value(to)}", "to")
    return SegmentSpec(f.name(), f.name("from"), tuple(ends), f.number(f.get("mass", 0.0), "mass", "mass"),
                       f.number(f.get("com", 0.5), "com", "com"))


def _list(top: _Fields, key: str) -> list:
    v = top.get(key, [])
    if not isinstance(v, list):
        top.fail(f"{key} must be a list, got {show_value(v)}", key)
    return v
