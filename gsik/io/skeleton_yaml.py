"""Reading skeleton definitions from YAML (schema: ``skeletons/README.md``)."""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

import yaml

from gsik.errors import GsikFileError, SkeletonError, choices
from gsik import validate
from gsik.io.files import read_text
from gsik.rotations import matrix_from_quaternion
from gsik.skeleton import AXES, JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton

FORMAT_VERSION = 1


def _bundled_dir() -> Path:
    """The folder of the bundled skeletons: the ``gsik.skeletons`` package (the repository's ``skeletons/``)."""
    return Path(str(resources.files("gsik.skeletons")))


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
            raise SkeletonError(f"no bundled skeleton {s!r}; bundled: {choices(bundled)} (or give a path to a .yaml file)")
        path = _bundled_dir() / f"{s}.yaml"
    try:
        text = read_text(path, "skeleton file")
    except GsikFileError as exc:  # a skeleton that cannot be loaded is a SkeletonError, whatever the cause
        raise SkeletonError(str(exc)) from None
    return skeleton_from_yaml(text, source=str(path))


def skeleton_from_yaml(text: str, source: str = "<string>") -> Skeleton:
    """Parse and compile a skeleton from YAML text."""
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc)
        raise SkeletonError(f"{source}: malformed YAML{where}: {problem}") from None
    return skeleton_from_dict(data, source)


class _Fields:
    """Reads one mapping of a YAML document, naming the place in every error."""

    def __init__(self, data, where: str, source: str):
        self.where = where
        self.source = source
        if not isinstance(data, dict):
            self.fail(f"must be a mapping, got {type(data).__name__}")
        self.data = data

    def fail(self, msg: str):
        raise SkeletonError(f"{self.source}: {self.where}: {msg}")

    def check_keys(self, allowed: tuple[str, ...]) -> None:
        unknown = [k for k in self.data if k not in allowed]
        if unknown:
            self.fail(f"unknown field {unknown[0]!r}; valid fields: {choices(allowed)}")

    def get(self, key: str, default=...):
        if key not in self.data:
            if default is ...:
                self.fail(f"missing field {key!r}")
            return default
        return self.data[key]

    def checked(self, check, *args):
        """``check(*args, SkeletonError)`` from :mod:`gsik.validate`, its error naming this place."""
        try:
            return check(*args, SkeletonError)
        except SkeletonError as exc:
            self.fail(str(exc))

    def name(self, key: str = "name", default=...) -> str | None:
        v = self.get(key, default)
        if v is None and default is None:
            return None
        return self.checked(validate.name, v, key)

    def number(self, value, what: str) -> float:
        return self.checked(validate.number, value, what)

    def vector(self, key: str, n: int = 3, default=...) -> tuple[float, ...]:
        v = self.get(key, default)
        if v is default and default is not ...:
            return default
        if not isinstance(v, (list, tuple)) or len(v) != n:
            self.fail(f"{key} must be a list of {n} numbers, got {v!r}")
        return tuple(self.number(x, f"{key}[{i}]") for i, x in enumerate(v))

    def orientation(self, key: str = "orientation"):
        q = self.get(key, None)
        if q is None:
            return None
        self.vector(key, 4)
        return matrix_from_quaternion(self.checked(validate.unit_quaternion, q, key))


def _axis(f: _Fields, value) -> tuple[float, float, float]:
    if isinstance(value, str):
        v = value.strip().lower()
        sign = -1.0 if v.startswith("-") else 1.0
        v = v.lstrip("+-")
        if v not in AXES:
            f.fail(f"axis must be x, y, z (optionally with a sign) or 3 numbers, got {value!r}")
        return tuple(sign * c for c in AXES[v])
    if isinstance(value, (list, tuple)) and len(value) == 3:
        return tuple(f.number(c, "axis") for c in value)
    f.fail(f"axis must be x, y, z (optionally with a sign) or 3 numbers, got {value!r}")


def _rotation(f: _Fields, data, k: int) -> RotationSpec:
    r = _Fields(data, f"{f.where}: rotations[{k}]", f.source)
    r.check_keys(("axis", "limits", "rest", "label"))
    raw_axis = r.get("axis")
    axis = _axis(r, raw_axis)
    limits = r.get("limits")
    if not isinstance(limits, (list, tuple)) or len(limits) != 2:
        r.fail(f"limits must be [lower, upper] in rad, got {limits!r}")
    lo, hi = (r.number(x, f"limits[{i}]") for i, x in enumerate(limits))
    rest = r.number(r.get("rest", 0.0), "rest")  # limits and rest are checked once, by build_skeleton
    label = r.get("label", None)
    if label is None and isinstance(raw_axis, str):
        label = raw_axis.strip().lower().lstrip("+-")
    return RotationSpec(axis, lo, hi, rest, label or "")


def skeleton_from_dict(data, source: str = "<memory>") -> Skeleton:
    """Validate a parsed YAML document and compile it into a :class:`Skeleton`."""
    top = _Fields(data, "top level", source)
    top.check_keys(("format", "name", "description", "units", "up", "root", "effectors", "joints", "sites", "segments"))
    version = top.get("format", FORMAT_VERSION)
    if version != FORMAT_VERSION:
        top.fail(f"format {version!r} is not supported; this gsik reads format {FORMAT_VERSION}")
    if top.get("units", "m") != "m":
        top.fail(f"units must be 'm' (metres), got {top.get('units')!r}")
    name = top.name("name")
    joints_data = top.get("joints")
    if not isinstance(joints_data, list) or not joints_data:
        top.fail(f"joints must be a non-empty list, got {joints_data!r}")
    joints = [_joint(_Fields(jd, f"joints[{i}]", source), i) for i, jd in enumerate(joints_data)]
    sites = [_site(_Fields(sd, f"sites[{i}]", source)) for i, sd in enumerate(_list(top, "sites"))]
    segments = [_segment(_Fields(sd, f"segments[{i}]", source)) for i, sd in enumerate(_list(top, "segments"))]
    effectors = _list(top, "effectors")
    for e in effectors:
        if not isinstance(e, str):
            top.fail(f"effectors must be a list of site names, got {e!r}")
    root = top.name("root", None)
    return build_skeleton(name, joints, sites, segments, effectors, root, source)


def _joint(f: _Fields, i: int) -> JointSpec:
    jname = f.name()
    f.where = f"joints[{i}] ({jname})"
    f.check_keys(("name", "parent", "offset", "rotations", "orientation"))
    rots = f.get("rotations", [])
    if not isinstance(rots, list):
        f.fail(f"rotations must be a list, got {rots!r}")
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
            f.fail(f"sole must be a list of [x, y] corners [m], got {sole!r}")
        sole = tuple((f.number(c[0], "sole x"), f.number(c[1], "sole y")) for c in sole)
    return SiteSpec(f.name(), f.name("parent"), f.vector("offset", default=(0.0, 0.0, 0.0)), f.orientation(), sole)


def _segment(f: _Fields) -> SegmentSpec:
    f.check_keys(("name", "from", "to", "mass", "com"))
    to = f.get("to")
    ends = [to] if isinstance(to, str) else to
    if not isinstance(ends, list) or not ends or not all(isinstance(e, str) and e for e in ends):
        f.fail(f"to must be a joint or site name or a list of them, got {to!r}")
    return SegmentSpec(f.name(), f.name("from"), tuple(ends), f.number(f.get("mass", 0.0), "mass"),
                       f.number(f.get("com", 0.5), "com"))


def _list(top: _Fields, key: str) -> list:
    v = top.get(key, [])
    if not isinstance(v, list):
        top.fail(f"{key} must be a list, got {v!r}")
    return v
