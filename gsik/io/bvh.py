"""BVH motion-capture files: parse, write, and the clip's own forward kinematics.

This module is the file-format layer only: it turns BVH text into plain,
read-only data (:class:`BvhClip`) and back, without converting to a gsik
skeleton.

BVH semantics used throughout:

* A joint's local rotation is the product of its rotation channels in the
  order they are listed: ``CHANNELS 3 Zrotation Xrotation Yrotation`` gives
  ``R = Rz @ Rx @ Ry`` (angles in degrees).
* A joint's local translation is its ``OFFSET``, except that each position
  channel (``Xposition`` ...) replaces the matching offset component.
* ``End Site`` blocks become joints with no channels, named after their
  parent with an ``_end`` suffix (made unique if that name is taken).

Malformed input raises :class:`~gsik.errors.BvhError` naming the problem, the
1-based line number and the source; file-system failures raise
:class:`~gsik.errors.GsikFileError`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gsik.errors import BvhError, choices
from gsik.io.files import atomic_write_text, read_text
from gsik.rotations import matrix_from_cos_sin

#: The six BVH channel names, in canonical spelling.
CHANNEL_NAMES = ("Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation")
_CHANNEL_LOOKUP = {c.lower(): c for c in CHANNEL_NAMES}
_AXIS_INDEX = {"X": 0, "Y": 1, "Z": 2}

_NUMBER_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
_INT_RE = re.compile(r"[+-]?\d+")
# Braces are tokens of their own even when glued to a name ("Hips{").
_TOKEN_RE = re.compile(r"[{}]|[^\s{}]+")
_FRAMES_RE = re.compile(r"frames\s*:\s*(\S*)\s*", re.IGNORECASE)
_FRAME_TIME_RE = re.compile(r"frame\s*time\s*:\s*(\S*)\s*", re.IGNORECASE)
# Tokens that can never be a channel name or a number: used to tell
# "too few values" from "a bad value".
_KEYWORDS = frozenset({"{", "}", "ROOT", "JOINT", "END", "OFFSET", "CHANNELS", "MOTION", "HIERARCHY"})


# ---------------------------------------------------------------------------
# Data
# ---------------------------------------------------------------------------


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
        offset = np.array(self.offset, dtype=float)
        if offset.shape != (3,):
            raise BvhError(f"joint {self.name!r}: offset must have shape (3,), got {offset.shape}")
        if not np.all(np.isfinite(offset)):
            raise BvhError(f"joint {self.name!r}: offset {offset.tolist()} is not finite")
        offset.flags.writeable = False
        object.__setattr__(self, "offset", offset)
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
            raise BvhError("motion contains non-finite values")
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
        if not isinstance(joint, BvhJoint):
            raise BvhError(f"joints[{i}] is a {type(joint).__name__}, not a BvhJoint")
        _check_name(joint.name)
        if joint.name in seen:
            raise BvhError(f"duplicate joint name {joint.name!r}")
        seen.add(joint.name)
        if i == 0:
            if joint.parent != -1 or joint.is_end_site:
                raise BvhError(f"the first joint {joint.name!r} must be the root (parent -1, not an End Site)")
            ancestors.append(0)
            continue
        if not 0 <= joint.parent < i:
            raise BvhError(f"joint {joint.name!r} has parent {joint.parent}; expected an index in [0, {i})")
        if joints[joint.parent].is_end_site:
            raise BvhError(f"End Site {joints[joint.parent].name!r} cannot have children")
        while ancestors and ancestors[-1] != joint.parent:
            ancestors.pop()
        if not ancestors:
            raise BvhError(f"joint {joint.name!r} is not in depth-first order after its parent's subtree")
        ancestors.append(i)


# ---------------------------------------------------------------------------
# Parsing
# ---------------------------------------------------------------------------


@dataclass
class _Raw:
    """A joint while it is being parsed (mutable)."""

    name: str
    parent: int
    line: int
    is_end_site: bool
    offset: list[float] | None = None
    channels: tuple[str, ...] | None = None
    channels_line: int = 0


@dataclass
class _Block:
    """An open ``{`` of the hierarchy."""

    joint: int
    label: str  # "ROOT 'Hips'", "End Site of 'Head'" for messages
    line: int  # line of the '{'


class _Tokens:
    """A cursor over the ``(token, line)`` pairs of the hierarchy section."""

    def __init__(self, pairs: list[tuple[str, int]], source: str, eof_line: int):
        self.pairs = pairs
        self.pos = 0
        self.source = source
        self.eof_line = eof_line

    def error(self, message: str, line: int | None) -> BvhError:
        return BvhError(message, line=line, path=self.source)

    def peek(self) -> tuple[str, int] | None:
        return self.pairs[self.pos] if self.pos < len(self.pairs) else None

    def next(self, eof_message: str) -> tuple[str, int]:
        if self.pos >= len(self.pairs):
            raise self.error(eof_message, self.eof_line)
        pair = self.pairs[self.pos]
        self.pos += 1
        return pair


def _number(token: str, line: int, where: str, source: str) -> float:
    """A strict decimal number; nan/inf and anything else raise BvhError."""
    if _NUMBER_RE.fullmatch(token):
        return float(token)
    raise _bad_number(token, line, where, source)


def _bad_number(token: str, line: int, where: str, source: str) -> BvhError:
    """The error for a token that is not a strict finite number."""
    try:
        finite = bool(np.isfinite(float(token)))
    except ValueError:
        finite = True  # not a number at all
    kind = "non-numeric" if finite else "non-finite"
    return BvhError(f"{kind} value {token!r} in {where}", line=line, path=source)


def _split_lines(text: str) -> list[str]:
    # splitlines() also splits on \f, \v, \x1c..: harmless for BVH, and it
    # handles \r\n and lone \r the same way.
    return text.removeprefix("\ufeff").splitlines()


def _find_motion_line(lines: list[str]) -> int | None:
    """0-based index of the first line whose first token is MOTION."""
    for i, line in enumerate(lines):
        head = line.split(None, 1)
        if head and head[0].upper() == "MOTION":
            return i
    return None


def _tokenize(lines: list[str]) -> list[tuple[str, int]]:
    return [(m.group(), n) for n, line in enumerate(lines, start=1) for m in _TOKEN_RE.finditer(line)]


def _read_offset(tokens: _Tokens, line: int, label: str) -> list[float]:
    values: list[float] = []
    while len(values) < 3:
        nxt = tokens.peek()
        if nxt is None or nxt[0].upper() in _KEYWORDS:
            raise tokens.error(f"OFFSET of {label} needs 3 numbers, found {len(values)}", line)
        tokens.pos += 1
        values.append(_number(nxt[0], nxt[1], f"OFFSET of {label}", tokens.source))
    return values


def _read_channels(tokens: _Tokens, line: int, label: str) -> tuple[str, ...]:
    count_tok, count_line = tokens.next(f"CHANNELS of {label} has no channel count")
    if not _INT_RE.fullmatch(count_tok) or int(count_tok) < 0:
        raise tokens.error(
            f"CHANNELS count of {label} must be a non-negative integer, found {count_tok!r}", count_line
        )
    count = int(count_tok)
    channels: list[str] = []
    while len(channels) < count:
        nxt = tokens.peek()
        if nxt is None or nxt[0].upper() in _KEYWORDS or _NUMBER_RE.fullmatch(nxt[0]):
            raise tokens.error(
                f"CHANNELS of {label} declares {count} channels but lists {len(channels)}", line
            )
        tokens.pos += 1
        name = _CHANNEL_LOOKUP.get(nxt[0].lower())
        if name is None:
            raise tokens.error(
                f"unknown channel name {nxt[0]!r} in CHANNELS of {label}; "
                f"expected one of {choices(CHANNEL_NAMES)}",
                nxt[1],
            )
        if name in channels:
            raise tokens.error(f"duplicate channel {name!r} in CHANNELS of {label}", nxt[1])
        channels.append(name)
    return tuple(channels)


def _open_joint(
    tokens: _Tokens, raws: list[_Raw], names: dict[str, int], keyword: str, kw_line: int, parent: int
) -> _Block:
    """Read ``<name> {`` after ROOT/JOINT and register the joint."""
    name, line = tokens.next(f"{keyword} has no name (unexpected end of file)")
    if name in ("{", "}"):
        raise tokens.error(f"{keyword} on line {kw_line} has no name (found {name!r})", line)
    if name in names:
        raise tokens.error(f"duplicate joint name {name!r} (first defined on line {names[name]})", line)
    names[name] = line
    brace, brace_line = tokens.next(f"expected '{{' after {keyword} {name}, found end of file")
    if brace != "{":
        raise tokens.error(f"expected '{{' after {keyword} {name}, found {brace!r}", brace_line)
    raws.append(_Raw(name=name, parent=parent, line=line, is_end_site=False))
    return _Block(joint=len(raws) - 1, label=f"{keyword} {name!r}", line=brace_line)


def _open_end_site(tokens: _Tokens, raws: list[_Raw], end_line: int, parent: int) -> _Block:
    """Read ``Site {`` after End."""
    site, line = tokens.next("expected 'Site' after 'End', found end of file")
    if site.lower() != "site":
        raise tokens.error(f"expected 'Site' after 'End', found {site!r}", line)
    brace, brace_line = tokens.next("expected '{' after End Site, found end of file")
    if brace != "{":
        raise tokens.error(f"expected '{{' after End Site, found {brace!r}", brace_line)
    raws.append(_Raw(name="", parent=parent, line=end_line, is_end_site=True))
    return _Block(joint=len(raws) - 1, label=f"End Site of {raws[parent].name!r}", line=brace_line)


def _close_block(tokens: _Tokens, raw: _Raw, block: _Block) -> None:
    if raw.offset is None:
        raise tokens.error(f"{block.label} has no OFFSET", raw.line)
    if raw.channels is None:
        if not raw.is_end_site:
            raise tokens.error(f"{block.label} has no CHANNELS", raw.line)
        raw.channels = ()


def _parse_hierarchy(tokens: _Tokens) -> list[_Raw]:
    """Parse ``HIERARCHY ROOT ... }`` into joints in file order."""
    tok, line = tokens.next("empty file")
    if tok.upper() != "HIERARCHY":
        raise tokens.error(f"expected 'HIERARCHY' at the start of the file, found {tok!r}", line)
    tok, line = tokens.next("missing ROOT after HIERARCHY")
    if tok.upper() != "ROOT":
        raise tokens.error(f"expected 'ROOT' after HIERARCHY, found {tok!r}", line)
    raws: list[_Raw] = []
    names: dict[str, int] = {}
    stack = [_open_joint(tokens, raws, names, "ROOT", line, -1)]
    while stack:
        top = stack[-1]
        raw = raws[top.joint]
        tok, line = tokens.next(f"unbalanced braces: '{{' opened on line {top.line} for {top.label} is never closed")
        upper = tok.upper()
        if tok == "}":
            _close_block(tokens, raw, top)
            stack.pop()
        elif upper == "OFFSET":
            if raw.offset is not None:
                raise tokens.error(f"{top.label} has a second OFFSET", line)
            raw.offset = _read_offset(tokens, line, top.label)
        elif upper == "CHANNELS":
            if raw.channels is not None:
                raise tokens.error(f"{top.label} has a second CHANNELS", line)
            raw.channels = _read_channels(tokens, line, top.label)
            raw.channels_line = line
            if raw.is_end_site and raw.channels:
                raise tokens.error(f"{top.label} cannot have channels", line)
        elif upper in ("JOINT", "END"):
            if raw.is_end_site:
                raise tokens.error(f"{top.label} cannot contain {tok!r}", line)
            if upper == "JOINT":
                stack.append(_open_joint(tokens, raws, names, "JOINT", line, top.joint))
            else:
                stack.append(_open_end_site(tokens, raws, line, top.joint))
        elif upper in ("ROOT", "MOTION", "HIERARCHY"):
            raise tokens.error(
                f"unbalanced braces: found {tok!r} inside {top.label} "
                f"(its '{{' on line {top.line} is never closed)",
                line,
            )
        elif tok.lower() in _CHANNEL_LOOKUP and raw.channels is not None:
            raise tokens.error(
                f"CHANNELS of {top.label} on line {raw.channels_line} declares "
                f"{len(raw.channels)} channels but lists more",
                line,
            )
        elif _NUMBER_RE.fullmatch(tok) and raw.offset is not None:
            raise tokens.error(f"unexpected number {tok!r} in {top.label} (OFFSET takes exactly 3 numbers)", line)
        else:
            raise tokens.error(f"unexpected {tok!r} in {top.label}", line)
    nxt = tokens.peek()
    if nxt is not None:
        tok, line = nxt
        if tok == "}":
            raise tokens.error("unbalanced braces: '}' without a matching '{'", line)
        if tok.upper() == "ROOT":
            raise tokens.error("a second ROOT: files with several hierarchies are not supported", line)
        raise tokens.error(f"expected 'MOTION' after the hierarchy, found {tok!r}", line)
    return raws


def _name_end_sites(raws: list[_Raw]) -> None:
    """Name End Sites ``<parent>_end``, adding a number if a joint already has that name."""
    taken = {r.name for r in raws if not r.is_end_site}
    for r in raws:
        if r.is_end_site:
            base = raws[r.parent].name + "_end"
            name, k = base, 2
            while name in taken:
                name, k = f"{base}{k}", k + 1
            taken.add(name)
            r.name = name


def _next_nonblank(lines: list[str], start: int) -> int | None:
    for i in range(start, len(lines)):
        if lines[i].strip():
            return i
    return None


def _parse_motion_header(lines: list[str], motion_at: int, source: str) -> tuple[int, float, int]:
    """Read ``Frames:`` and ``Frame Time:``.

    Returns:
        (n_frames, frame_time [s], 0-based index of the first data line).
    """
    # Anything after MOTION on its own line is read as the next line.
    rest = lines[motion_at].split(None, 1)
    work = list(lines)
    if len(rest) > 1:
        work[motion_at] = rest[1]
        i = motion_at
    else:
        i = _next_nonblank(work, motion_at + 1)
    if i is None:
        raise BvhError("missing 'Frames:' line after MOTION", line=motion_at + 1, path=source)
    m = _FRAMES_RE.fullmatch(work[i].strip())
    if m is None:
        if _FRAME_TIME_RE.fullmatch(work[i].strip()):
            raise BvhError("missing 'Frames:' line before 'Frame Time:'", line=i + 1, path=source)
        raise BvhError(f"expected 'Frames: <count>' after MOTION, found {work[i].strip()!r}", line=i + 1, path=source)
    if not _INT_RE.fullmatch(m.group(1)):
        raise BvhError(f"frame count must be an integer, found {m.group(1)!r}", line=i + 1, path=source)
    n_frames = int(m.group(1))
    if n_frames < 0:
        raise BvhError(f"negative frame count {n_frames}", line=i + 1, path=source)
    frames_line = i
    i = _next_nonblank(work, i + 1)
    if i is None:
        raise BvhError("missing 'Frame Time:' line after 'Frames:'", line=frames_line + 1, path=source)
    m = _FRAME_TIME_RE.fullmatch(work[i].strip())
    if m is None:
        raise BvhError(f"expected 'Frame Time: <seconds>', found {work[i].strip()!r}", line=i + 1, path=source)
    frame_time = _number(m.group(1), i + 1, "Frame Time", source)
    if frame_time <= 0.0:
        raise BvhError(f"Frame Time must be positive, found {m.group(1)!r}", line=i + 1, path=source)
    return n_frames, frame_time, i + 1


def _line_tokens(lines: list[str], start: int) -> Iterator[tuple[str, int]]:
    """``(token, 1-based line)`` of every whitespace-separated token from ``lines[start]`` on."""
    for n in range(start, len(lines)):
        for tok in lines[n].split():
            yield tok, n + 1


def _motion_values(
    lines: list[str], start: int, n_frames: int, labels: tuple[str, ...], source: str
) -> np.ndarray:
    """The MOTION number stream as an (n_frames, n_channels) array.

    Fast path: split everything and let NumPy convert. Only when that fails
    (or when a token might be non-strict) walk the lines to report where.
    """
    n_channels = len(labels)
    expected = n_frames * n_channels
    chunk = "\n".join(lines[start:])
    tokens = chunk.split()
    values: np.ndarray | None = None
    # NumPy also accepts "1_000", non-ASCII digits, nan and inf: check those slowly.
    if chunk.isascii() and "_" not in chunk:
        try:
            values = np.array(tokens, dtype=float)
        except ValueError:
            values = None
        if values is not None and not np.all(np.isfinite(values)):
            values = None
    if values is None:
        for k, (tok, line) in enumerate(_line_tokens(lines, start)):
            if not _NUMBER_RE.fullmatch(tok):
                where = "MOTION data"
                if k < expected and n_channels:
                    where += f" (frame {k // n_channels + 1}, channel {labels[k % n_channels]!r})"
                raise _bad_number(tok, line, where, source)
        values = np.array([float(t) for t in tokens], dtype=float)
    found = len(tokens)
    if found != expected:
        need = f"expected {expected} values ({n_frames} frames x {n_channels} channels), found {found}"
        if found < expected:
            # The last value read, or the Frame Time line when there is none.
            line = _line_of_token(lines, start, found - 1) if found else start
            raise BvhError(f"truncated MOTION data: {need}", line=line, path=source)
        line = _line_of_token(lines, start, expected)
        raise BvhError(f"too many MOTION values: {need}; the first extra value is on this line", line=line, path=source)
    return values.reshape(n_frames, n_channels)


def _line_of_token(lines: list[str], start: int, k: int) -> int:
    """1-based line of the ``k``-th (0-based) token from ``lines[start]`` on."""
    seen = 0
    for n in range(start, len(lines)):
        seen += len(lines[n].split())
        if seen > k:
            return n + 1
    return len(lines)


def parse_bvh(text: str, source: str = "<string>") -> BvhClip:
    """Parse BVH text.

    Accepts any channel order, 0-6 channels per joint, namespaced names,
    tabs, ``\\r\\n`` line ends, blank lines, and MOTION values laid out on
    any number of lines (they are read as one stream of numbers).

    Args:
        text: The whole file.
        source: Path or label used in error messages.

    Returns:
        The clip; its arrays are read-only.

    Raises:
        BvhError: malformed text, with ``.line`` (1-based) and ``.path`` set.
    """
    lines = _split_lines(text)
    if not any(line.strip() for line in lines):
        raise BvhError("empty file", line=1, path=source)
    motion_at = _find_motion_line(lines)
    hierarchy_lines = lines if motion_at is None else lines[:motion_at]
    eof_line = len(lines) if motion_at is None else motion_at + 1
    tokens = _Tokens(_tokenize(hierarchy_lines), source, eof_line)
    raws = _parse_hierarchy(tokens)
    if motion_at is None:
        raise BvhError("missing MOTION section after the hierarchy", line=len(lines), path=source)
    _name_end_sites(raws)
    joints = tuple(
        BvhJoint(name=r.name, parent=r.parent, offset=r.offset, channels=r.channels, is_end_site=r.is_end_site)
        for r in raws
    )
    labels = tuple(f"{j.name} {c}" for j in joints for c in j.channels)
    n_frames, frame_time, data_at = _parse_motion_header(lines, motion_at, source)
    motion = _motion_values(lines, data_at, n_frames, labels, source)
    return BvhClip(joints=joints, frame_time=frame_time, motion=motion)


def read_bvh(path: str | os.PathLike) -> BvhClip:
    """Read and parse a BVH file (UTF-8, or Latin-1 as a fallback).

    Raises:
        BvhError: malformed file (message names the path and line).
        GsikFileError: the file cannot be read.
    """
    # Old exporters write Latin-1 names; every byte decodes.
    return parse_bvh(read_text(path, "BVH file", "utf-8-sig", fallback="latin-1"), source=os.fspath(path))


# ---------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------


def format_bvh(clip: BvhClip, precision: int = 6) -> str:
    """Format a clip as standard BVH text (tab indentation, one frame per line).

    Offsets and motion values are written with ``precision`` decimals, the
    frame time exactly, so ``parse_bvh(format_bvh(c))`` reproduces ``c``
    to the printed precision (End Site names are always regenerated).

    Args:
        clip: The clip.
        precision: Decimal places for offsets and motion values (>= 0).

    Returns:
        The text, ending with a newline.
    """
    if not isinstance(precision, (int, np.integer)) or isinstance(precision, bool) or precision < 0:
        raise BvhError(f"precision must be a non-negative integer, got {precision!r}")
    if not isinstance(clip, BvhClip):
        raise BvhError(f"format_bvh needs a BvhClip, got {type(clip).__name__}")
    fmt = f"{{:.{int(precision)}f}}".format
    out = ["HIERARCHY"]
    open_blocks: list[int] = []  # joints whose '}' is still to be written

    def close_until(parent: int) -> None:
        while open_blocks and open_blocks[-1] != parent:
            open_blocks.pop()
            out.append("\t" * len(open_blocks) + "}")

    for i, joint in enumerate(clip.joints):
        close_until(joint.parent)
        pad = "\t" * len(open_blocks)
        head = "End Site" if joint.is_end_site else ("ROOT " if i == 0 else "JOINT ") + joint.name
        out += [pad + head, pad + "{", pad + "\tOFFSET " + " ".join(fmt(v) for v in joint.offset.tolist())]
        if not joint.is_end_site:
            out.append(pad + f"\tCHANNELS {len(joint.channels)}" + "".join(" " + c for c in joint.channels))
        open_blocks.append(i)
    close_until(-1)
    out += ["MOTION", f"Frames: {clip.n_frames}", f"Frame Time: {clip.frame_time!r}"]
    out += [" ".join(fmt(v) for v in row) for row in clip.motion.tolist()]
    return "\n".join(out) + "\n"


def write_bvh(path: str | os.PathLike, clip: BvhClip, precision: int = 6) -> None:
    """Write ``clip`` to ``path`` atomically (see :func:`gsik.io.files.atomic_write_text`).

    The text is formatted before the file system is touched, so a clip that
    cannot be formatted never affects an existing file.

    Raises:
        BvhError: ``clip`` or ``precision`` is invalid.
        GsikFileError: the file cannot be written.
    """
    atomic_write_text(path, format_bvh(clip, precision))


# ---------------------------------------------------------------------------
# The clip's own forward kinematics
# ---------------------------------------------------------------------------


def _cos_sin_deg(degrees: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of angles in degrees, exact at quarter turns (so 90 deg gives 0, 1)."""
    turns = np.remainder(np.asarray(degrees, dtype=float), 360.0)
    rad = np.deg2rad(turns)
    c, s = np.cos(rad), np.sin(rad)
    quarter = turns / 90.0
    exact = quarter == np.round(quarter)
    if np.any(exact):
        k = np.round(quarter[exact]).astype(int) % 4
        c[exact] = np.array([1.0, 0.0, -1.0, 0.0])[k]
        s[exact] = np.array([0.0, 1.0, 0.0, -1.0])[k]
    return c, s


def _axis_rotation(axis: int, degrees: np.ndarray) -> np.ndarray:
    """(n, 3, 3) right-handed rotations by ``degrees`` (n,) about axis 0 (X), 1 (Y) or 2 (Z)."""
    return matrix_from_cos_sin(axis, *_cos_sin_deg(np.atleast_1d(degrees)))


def bvh_local_rotations(clip: BvhClip) -> np.ndarray:
    """Each joint's rotation relative to its parent, for every frame.

    Rotation channels compose in file order: ``Zrotation Xrotation
    Yrotation`` gives ``Rz @ Rx @ Ry``. Joints without rotation channels
    (End Sites included) get the identity.

    Returns:
        (n_frames, n_joints, 3, 3) rotation matrices.
    """
    n_frames = clip.n_frames
    out = np.broadcast_to(np.eye(3), (n_frames, clip.n_joints, 3, 3)).copy()
    for j, joint in enumerate(clip.joints):
        start = clip.channel_index(j).start
        R = None
        for k, channel in enumerate(joint.channels):
            if channel.endswith("rotation"):
                Rk = _axis_rotation(_AXIS_INDEX[channel[0]], clip.motion[:, start + k])
                R = Rk if R is None else R @ Rk
        if R is not None:
            out[:, j] = R
    return out


def bvh_local_translations(clip: BvhClip) -> np.ndarray:
    """Each joint's translation from its parent, for every frame.

    The OFFSET, with each component that has a position channel replaced by
    that channel's value (for the usual root: the X/Y/Zposition values).

    Returns:
        (n_frames, n_joints, 3) translations in file units.
    """
    offsets = np.array([j.offset for j in clip.joints]).reshape(clip.n_joints, 3)
    out = np.broadcast_to(offsets, (clip.n_frames, clip.n_joints, 3)).copy()
    for j, joint in enumerate(clip.joints):
        start = clip.channel_index(j).start
        for k, channel in enumerate(joint.channels):
            if channel.endswith("position"):
                out[:, j, _AXIS_INDEX[channel[0]]] = clip.motion[:, start + k]
    return out


def bvh_forward_kinematics(clip: BvhClip) -> tuple[np.ndarray, np.ndarray]:
    """World rotations and positions of every joint (End Sites included).

    ``world_R[j] = world_R[parent] @ local_R[j]`` and
    ``world_p[j] = world_p[parent] + world_R[parent] @ t[j]``, with the
    local parts from :func:`bvh_local_rotations` and
    :func:`bvh_local_translations`; the root's world transform is its local one.

    Returns:
        world_rotations: (n_frames, n_joints, 3, 3).
        world_positions: (n_frames, n_joints, 3) in file units.
    """
    local_R = bvh_local_rotations(clip)
    local_t = bvh_local_translations(clip)
    world_R = np.empty_like(local_R)
    world_p = np.empty_like(local_t)
    for j, joint in enumerate(clip.joints):
        p = joint.parent
        if p < 0:
            world_R[:, j] = local_R[:, j]
            world_p[:, j] = local_t[:, j]
        else:
            world_R[:, j] = world_R[:, p] @ local_R[:, j]
            world_p[:, j] = world_p[:, p] + np.einsum("fij,fj->fi", world_R[:, p], local_t[:, j])
    return world_R, world_p


__all__ = [
    "CHANNEL_NAMES",
    "BvhClip",
    "BvhJoint",
    "bvh_forward_kinematics",
    "bvh_local_rotations",
    "bvh_local_translations",
    "format_bvh",
    "parse_bvh",
    "read_bvh",
    "write_bvh",
]
