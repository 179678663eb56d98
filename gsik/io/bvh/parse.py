"""Reading BVH text: the hierarchy token by token, then the MOTION numbers as one stream."""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from gsik.errors import BvhError, choices, show_value
from gsik.io.bvh.clip import CHANNEL_LOOKUP, CHANNEL_NAMES, BvhClip, BvhJoint
from gsik.io.bvh.limits import MAX_BVH_BYTES, check_braces, check_frame_time, check_frames, check_joints
from gsik.io.files import read_text
from gsik.io.names import unique_name

_NUMBER_RE = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")
_INT_RE = re.compile(r"[+-]?\d+")
# Braces are tokens of their own even when glued to a name ("Hips{").
_TOKEN_RE = re.compile(r"[{}]|[^\s{}]+")
_FRAMES_RE = re.compile(r"frames\s*:\s*(\S*)\s*", re.IGNORECASE)
_FRAME_TIME_RE = re.compile(r"frame\s*time\s*:\s*(\S*)\s*", re.IGNORECASE)
# Tokens that can never be a channel name or a number: used to tell
# "too few values" from "a bad value".
_KEYWORDS = frozenset({"{", "}", "ROOT", "JOINT", "END", "OFFSET", "CHANNELS", "MOTION", "HIERARCHY"})




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
    """A cursor over the ``(token, line)`` pairs of the hierarchy section, read lazily: a hierarchy past a bound
    is refused at the bound, before the rest of it is split into tokens."""

    def __init__(self, pairs: Iterator[tuple[str, int]], source: str, eof_line: int):
        self._pairs = pairs
        self._ahead: tuple[str, int] | None = None
        self.source = source
        self.eof_line = eof_line

    def error(self, message: str, line: int | None) -> BvhError:
        return BvhError(message, line=line, path=self.source)

    def peek(self) -> tuple[str, int] | None:
        if self._ahead is None:
            self._ahead = next(self._pairs, None)
        return self._ahead

    def advance(self) -> None:
        """Drop the token :meth:`peek` showed."""
        self.peek()
        self._ahead = None

    def next(self, eof_message: str) -> tuple[str, int]:
        pair = self.peek()
        if pair is None:
            raise self.error(eof_message, self.eof_line)
        self._ahead = None
        return pair


def _number(token: str, line: int, where: str, source: str) -> float:
    """A strict, finite decimal number; nan/inf, ``1e400`` and anything else raise BvhError."""
    if _NUMBER_RE.fullmatch(token):
        value = float(token)
        if np.isfinite(value):
            return value
    raise _bad_number(token, line, where, source)


def _bad_number(token: str, line: int, where: str, source: str) -> BvhError:
    """The error for a token that is not a strict finite number."""
    try:
        finite = bool(np.isfinite(float(token)))
    except (ValueError, OverflowError):
        finite = True  # not a number at all
    kind = "non-numeric" if finite else "non-finite"
    return BvhError(f"{kind} value {show_value(token)} in {where}", line=line, path=source)


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


def _tokenize(lines: list[str]) -> Iterator[tuple[str, int]]:
    return ((m.group(), n) for n, line in enumerate(lines, start=1) for m in _TOKEN_RE.finditer(line))


def _read_offset(tokens: _Tokens, line: int, label: str) -> list[float]:
    values: list[float] = []
    while len(values) < 3:
        nxt = tokens.peek()
        if nxt is None or nxt[0].upper() in _KEYWORDS:
            raise tokens.error(f"OFFSET of {label} needs 3 numbers, found {len(values)}", line)
        tokens.advance()
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
        tokens.advance()
        name = CHANNEL_LOOKUP.get(nxt[0].lower())
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
    root_line = _expect_start(tokens)
    raws: list[_Raw] = []
    names: dict[str, int] = {}
    stack = [_open_joint(tokens, raws, names, "ROOT", root_line, -1)]
    while stack:
        top = stack[-1]
        raw = raws[top.joint]
        tok, line = tokens.next(f"unbalanced braces: '{{' opened on line {top.line} for {top.label} is never closed")
        upper = tok.upper()
        if tok == "}":
            _close_block(tokens, raw, top)
            stack.pop()
        elif upper == "OFFSET":
            _read_joint_offset(tokens, raw, top, line)
        elif upper == "CHANNELS":
            _read_joint_channels(tokens, raw, top, line)
        elif upper in ("JOINT", "END"):
            check_joints(len(raws) + 1, len(stack) + 1, tokens.source, line)
            stack.append(_open_child(tokens, raws, names, top, upper, tok, line))
        else:
            raise _unexpected(tokens, raw, top, tok, line)
    _expect_motion(tokens)
    return raws


def _expect_start(tokens: _Tokens) -> int:
    """``HIERARCHY`` then ``ROOT``; returns the line of ``ROOT``."""
    tok, line = tokens.next("empty file")
    if tok.upper() != "HIERARCHY":
        raise tokens.error(f"expected 'HIERARCHY' at the start of the file, found {tok!r}", line)
    tok, line = tokens.next("missing ROOT after HIERARCHY")
    if tok.upper() != "ROOT":
        raise tokens.error(f"expected 'ROOT' after HIERARCHY, found {tok!r}", line)
    return line


def _read_joint_offset(tokens: _Tokens, raw: _Raw, block: _Block, line: int) -> None:
    if raw.offset is not None:
        raise tokens.error(f"{block.label} has a second OFFSET", line)
    raw.offset = _read_offset(tokens, line, block.label)


def _read_joint_channels(tokens: _Tokens, raw: _Raw, block: _Block, line: int) -> None:
    if raw.channels is not None:
        raise tokens.error(f"{block.label} has a second CHANNELS", line)
    raw.channels = _read_channels(tokens, line, block.label)
    raw.channels_line = line
    if raw.is_end_site and raw.channels:
        raise tokens.error(f"{block.label} cannot have channels", line)


def _open_child(tokens: _Tokens, raws: list[_Raw], names: dict[str, int], block: _Block, upper: str, tok: str,
                line: int) -> _Block:
    """The block of a ``JOINT`` or ``End Site`` inside ``block``."""
    if raws[block.joint].is_end_site:
        raise tokens.error(f"{block.label} cannot contain {tok!r}", line)
    if upper == "JOINT":
        return _open_joint(tokens, raws, names, "JOINT", line, block.joint)
    return _open_end_site(tokens, raws, line, block.joint)


def _unexpected(tokens: _Tokens, raw: _Raw, block: _Block, tok: str, line: int) -> BvhError:
    """The error for a token no joint block may hold here, saying what it most likely means."""
    if tok.upper() in ("ROOT", "MOTION", "HIERARCHY"):
        return tokens.error(
            f"unbalanced braces: found {tok!r} inside {block.label} "
            f"(its '{{' on line {block.line} is never closed)",
            line,
        )
    if tok.lower() in CHANNEL_LOOKUP and raw.channels is not None:
        return tokens.error(
            f"CHANNELS of {block.label} on line {raw.channels_line} declares "
            f"{len(raw.channels)} channels but lists more",
            line,
        )
    if _NUMBER_RE.fullmatch(tok) and raw.offset is not None:
        return tokens.error(f"unexpected number {tok!r} in {block.label} (OFFSET takes exactly 3 numbers)", line)
    return tokens.error(f"unexpected {tok!r} in {block.label}", line)


def _expect_motion(tokens: _Tokens) -> None:
    """Nothing but ``MOTION`` may follow the hierarchy's last ``}``."""
    nxt = tokens.peek()
    if nxt is None:
        return
    tok, line = nxt
    if tok == "}":
        raise tokens.error("unbalanced braces: '}' without a matching '{'", line)
    if tok.upper() == "ROOT":
        raise tokens.error("a second ROOT: files with several hierarchies are not supported", line)
    raise tokens.error(f"expected 'MOTION' after the hierarchy, found {tok!r}", line)


def _name_end_sites(raws: list[_Raw]) -> None:
    """Name End Sites ``<parent>_end``, adding a number if a joint already has that name."""
    taken = {r.name for r in raws if not r.is_end_site}
    for r in raws:
        if r.is_end_site:
            r.name = unique_name(raws[r.parent].name + "_end", taken)
            taken.add(r.name)


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
    check_frame_time(frame_time, source, i + 1)
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

    Fast path: NumPy's C reader over the lines, one frame a line, its memory the array's own (a million frames
    no longer become tens of millions of Python strings). Only when that fails (a token that is not a plain
    decimal number, frames laid over several lines) are the tokens walked, to read them as one stream or say where
    the bad one is.
    """
    values = _bulk_numbers(lines[start:])
    if values is None:
        _find_bad_number(lines, start, n_frames, labels, source)
        values = np.array([float(tok) for tok, _ in _line_tokens(lines, start)], dtype=float)
    _check_count(lines, start, values.size, n_frames, len(labels), source)
    return values.reshape(n_frames, len(labels))


# Characters of plain decimal numbers and the space between them: anything else needs the strict, slow check
# (NumPy's reader would also take "nan", "inf", "1_000" and non-ASCII digits).
_NOT_DECIMAL = re.compile(r"[^0-9eE+\-. \t\r\n]")


def _bulk_numbers(data_lines: list[str]) -> np.ndarray | None:
    """The values of ``data_lines`` in file order as finite floats, or ``None`` when they need the token walk."""
    if any(_NOT_DECIMAL.search(line) for line in data_lines):
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "input contained no data": zero frames or channels, counted later
        try:
            values = np.loadtxt(data_lines, dtype=float, comments=None, ndmin=2)
        except ValueError:  # a malformed number, or frames over several lines
            return None
    values = values.ravel()
    return values if np.all(np.isfinite(values)) else None


def _find_bad_number(lines: list[str], start: int, n_frames: int, labels: tuple[str, ...], source: str) -> None:
    """Raise for the first token that is not a strict decimal number, naming its frame and channel."""
    n_channels = len(labels)
    for k, (tok, line) in enumerate(_line_tokens(lines, start)):
        if not _NUMBER_RE.fullmatch(tok) or not np.isfinite(float(tok)):
            where = "MOTION data"
            if k < n_frames * n_channels and n_channels:
                where += f" (frame {k // n_channels + 1}, channel {labels[k % n_channels]!r})"
            raise _bad_number(tok, line, where, source)


def _check_count(lines: list[str], start: int, found: int, n_frames: int, n_channels: int, source: str) -> None:
    """Exactly ``n_frames * n_channels`` values, or an error on the line where they run out or overflow."""
    expected = n_frames * n_channels
    if found == expected:
        return
    need = f"expected {expected} values ({n_frames} frames x {n_channels} channels), found {found}"
    if found < expected:
        # The last value read, or the Frame Time line when there is none.
        line = _line_of_token(lines, start, found - 1) if found else start
        raise BvhError(f"truncated MOTION data: {need}", line=line, path=source)
    line = _line_of_token(lines, start, expected)
    raise BvhError(f"too many MOTION values: {need}; the first extra value is on this line", line=line, path=source)


def _line_of_token(lines: list[str], start: int, k: int) -> int:
    """1-based line of the ``k``-th (0-based) token from ``lines[start]`` on."""
    seen = 0
    for n in range(start, len(lines)):
        seen += len(lines[n].split())
        if seen > k:
            return n + 1
    return len(lines)


_LONE_SURROGATE = re.compile("[\ud800-\udfff]")


def _check_text(lines: list[str], source: str) -> None:
    """Refuse a lone surrogate (text decoded with ``surrogateescape``, or built in memory): no name could hold it."""
    for i, line in enumerate(lines):
        if _LONE_SURROGATE.search(line):
            raise BvhError("not text: a lone surrogate character (the file is not valid UTF-8 or Latin-1 text)",
                           line=i + 1, path=source)


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
        BvhError: malformed text, or past a bound of :mod:`gsik.io.bvh.limits`, with ``.line`` (1-based) and
            ``.path`` set.
    """
    check_braces(text, source)
    lines = _split_lines(text)
    if not any(line.strip() for line in lines):
        raise BvhError("empty file", line=1, path=source)
    _check_text(lines, source)
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
    check_frames(n_frames, len(labels), len(joints), source, data_at - 1)
    motion = _motion_values(lines, data_at, n_frames, labels, source)
    return BvhClip(joints=joints, frame_time=frame_time, motion=motion)


def read_bvh(path: str | os.PathLike) -> BvhClip:
    """Read and parse a BVH file (UTF-8, or Latin-1 as a fallback).

    Raises:
        BvhError: malformed file (message names the path and line).
        GsikFileError: the file cannot be read.
    """
    # Old exporters write Latin-1 names; every byte decodes.
    text = read_text(path, "BVH file", "utf-8-sig", fallback="latin-1", limit=MAX_BVH_BYTES)
    return parse_bvh(text, source=os.fspath(path))
