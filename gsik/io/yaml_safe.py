"""Bounded YAML reading: plain data and the line of every key, in one pass, whatever the file holds.

Every YAML file gsik reads (poses, skeletons) goes through :func:`load_yaml`. It builds the data straight from
PyYAML's event stream (libyaml's parser when present), with PyYAML's safe resolver and scalar constructors, and
refuses what a hand-written data file never needs but a hostile one uses:

- aliases (``*a``) that expand the document past :data:`MAX_VALUES` values (a few hundred bytes of nested aliases
  expand to billions) or that refer to the collection they are in;
- tags other than the plain data types (``!!python/...``, ``!!binary``, ``!!set``, custom ``!tags``) and merge keys;
- nesting deeper than :data:`MAX_DEPTH`, text longer than :data:`MAX_CHARS`;
- integers beyond 64 bits and floats that overflow to infinity (``1.0e400``);
- keys that are lists or mappings, duplicate keys, more than one document, characters YAML forbids (NUL, ...).

Each refusal, and every PyYAML error, is raised as the caller's error type (a :class:`gsik.GsikError` subclass)
naming the file and the line. Building iteratively, never recursively, no input reaches Python's recursion limit.
"""

from __future__ import annotations

import re
from typing import Any, NamedTuple

import yaml
from yaml import events as ev
from yaml.constructor import SafeConstructor
from yaml.nodes import ScalarNode
from yaml.resolver import Resolver

from gsik.errors import GsikError, show_value

#: Deepest nesting of lists and mappings a file may have (a pose needs 4, a skeleton 5).
MAX_DEPTH = 64

#: Longest YAML text accepted [characters]: far above a skeleton at the solver's DOF limit.
MAX_CHARS = 8 * 1024 * 1024

#: Largest YAML file read [bytes]: :data:`MAX_CHARS` characters of up to 4 bytes each in UTF-8.
MAX_BYTES = 4 * MAX_CHARS

#: Most values (scalars, lists, mappings) a document may hold, counting each alias as the values it repeats.
MAX_VALUES = 1_000_000

#: Largest magnitude of an integer in a file (int64, what NumPy and the kernels can hold).
MAX_INT = 2**63 - 1

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's parser when PyYAML was built with it

_STR = "tag:yaml.org,2002:str"
_TAGS = {f"tag:yaml.org,2002:{t}" for t in ("str", "int", "float", "bool", "null", "seq", "map")}
_IMPLICIT_EXTRA = {"tag:yaml.org,2002:timestamp"}  # plain dates resolve to this, as in yaml.safe_load
_MERGE, _VALUE = "tag:yaml.org,2002:merge", "tag:yaml.org,2002:value"

# What YAML 1.1 allows in a stream (PyYAML's reader refuses everything else).
_NOT_PRINTABLE = re.compile("[^\x09\x0A\x0D\x20-\x7E\x85\xA0-\uD7FF\uE000-\uFFFD\U00010000-\U0010FFFF]")

_resolver = Resolver()
_constructor = SafeConstructor()


class YamlDocument(NamedTuple):
    """A YAML file read by :func:`load_yaml`.

    Attributes:
        data: Plain Python data: dicts, lists, str, int, float, bool, None (and ``datetime`` for plain dates).
        lines: 1-based line of every place in ``data``, keyed by its path from the top (``("joints", 3, "name")``):
            a mapping key's own line, a list item's first line; ``()`` is the document's line. Places inside a
            repeated alias have no entry of their own: the alias's place names the line.
    """

    data: Any
    lines: dict[tuple, int]


def load_yaml(text: str, source: str, error: type[GsikError]) -> YamlDocument:
    """Read one YAML document, bounded in size, depth and expansion (see the module docstring).

    Args:
        text: The YAML text.
        source: Name for messages (usually the file path).
        error: The error type to raise, called with one message (``PoseError``, ``SkeletonError``).

    Returns:
        :class:`YamlDocument`; ``data`` is ``None`` for an empty document.

    Raises:
        error: ``"<source>:<line>: <problem>"`` for anything refused or malformed.
    """
    _check_text(text, source, error)
    builder = _Builder(source, error)
    _parse_into(builder, text, source, error)
    return YamlDocument(builder.data, builder.lines)


def _check_text(text: str, source: str, error: type[GsikError]) -> None:
    """Refuse what is not a str, too long, or holds a character YAML does not allow, before parsing."""
    if not isinstance(text, str):
        raise error(f"{source}: YAML text must be a str, got {type(text).__name__}")
    if len(text) > MAX_CHARS:
        raise error(f"{source}: file is {len(text):,} characters long; the limit is {MAX_CHARS:,}")
    bad = _NOT_PRINTABLE.search(text)
    if bad:
        raise error(f"{source}:{text.count(chr(10), 0, bad.start()) + 1}: character U+{ord(bad.group()):04X} "
                    "is not allowed in YAML")


def _parse_into(builder: _Builder, text: str, source: str, error: type[GsikError]) -> None:
    """Feed PyYAML's events to ``builder``; PyYAML's own errors become ``error`` with the line."""
    try:
        for event in yaml.parse(text, Loader=_Loader):
            builder.feed(event)
    except yaml.MarkedYAMLError as exc:
        if _Loader is not yaml.SafeLoader:
            _refuse_as_gsik_would(text, exc, source, error)
        mark = exc.problem_mark or exc.context_mark
        line = f":{mark.line + 1}" if mark is not None else ""
        problem = exc.problem or exc.context or "malformed YAML"
        raise error(f"{source}{line}: not valid YAML: {problem}") from None
    except yaml.YAMLError as exc:  # ReaderError: a character the check above did not foresee
        raise error(f"{source}: not valid YAML: {show_value(str(exc))}") from None


def _refuse_as_gsik_would(text: str, exc: yaml.MarkedYAMLError, source: str, error: type[GsikError]) -> None:
    """Raise gsik's own refusal if the text up to libyaml's error breaks one of gsik's bounds.

    libyaml scans a flow collection (``[[[...``) to its end before the first event, so its own limits (a nesting
    depth since PyYAML 6.0.4) can fire before :class:`_Builder` sees the depth. PyYAML's pure-Python parser yields
    events as it goes: re-reading the text up to the error's position with it gives gsik's refusal (file, line,
    limit) whatever libyaml's version; anything else falls through to libyaml's own error.
    """
    mark = exc.problem_mark or exc.context_mark
    if mark is None or mark.index is None:
        return
    builder = _Builder(source, error)
    try:
        for event in yaml.parse(text[: mark.index], Loader=yaml.SafeLoader):
            builder.feed(event)
    except yaml.YAMLError:
        return


class _Collection:
    """A list or mapping being built; ``key`` holds a mapping's pending key (``_NO_KEY`` when none).

    ``anchor`` and ``first``: the collection's anchor (or ``None``) and the value count before it began.
    """

    __slots__ = ("value", "path", "key", "key_line", "key_lines", "anchor", "first")

    def __init__(self, value, path: tuple, anchor: str | None, first: int):
        self.value = value
        self.path = path
        self.anchor = anchor
        self.first = first
        self.key = _NO_KEY
        self.key_line = 0
        self.key_lines: dict[Any, int] = {}


_NO_KEY = object()


class _Builder:
    """Turns PyYAML events into plain data and a line map, refusing what the module docstring lists."""

    def __init__(self, source: str, error: type[GsikError]):
        self.source = source
        self.error = error
        self.stack: list[_Collection] = []
        self.lines: dict[tuple, int] = {}
        self.data = None
        self.documents = 0
        self.values = 0  # values so far, aliases counted as what they repeat
        self.anchors: dict[str, tuple[Any, int]] = {}  # anchor -> (value, number of values in it)

    def fail(self, event: ev.Event, problem: str):
        raise self.error(f"{self.source}:{event.start_mark.line + 1}: {problem}")

    def feed(self, event: ev.Event) -> None:
        if isinstance(event, ev.AliasEvent):
            self.alias(event)
        elif isinstance(event, ev.ScalarEvent):
            self.count(event, 1)
            value = self.scalar(event)
            if event.anchor is not None:
                self.anchors[event.anchor] = (value, 1)
            self.add(event, value)
        elif isinstance(event, (ev.SequenceStartEvent, ev.MappingStartEvent)):
            self.count(event, 1)
            self.start(event)
        elif isinstance(event, (ev.SequenceEndEvent, ev.MappingEndEvent)):
            done = self.stack.pop()
            if done.anchor is not None:
                self.anchors[done.anchor] = (done.value, self.values - done.first)
            if not self.stack:
                self.data = done.value
        elif isinstance(event, ev.DocumentStartEvent):
            self.documents += 1
            if self.documents > 1:
                self.fail(event, "a gsik file holds one YAML document; found a second one ('---')")

    def count(self, event: ev.NodeEvent, n: int) -> None:
        self.values += n
        if self.values > MAX_VALUES:
            self.fail(event, f"the document holds more than {MAX_VALUES:,} values (counting what aliases repeat)")

    def alias(self, event: ev.AliasEvent) -> None:
        """Repeat an anchored value (shared, as yaml.safe_load does), counting what it repeats."""
        if event.anchor not in self.anchors:
            inside = any(c.anchor == event.anchor for c in self.stack)
            problem = "refers to a list or mapping it is inside of" if inside else "refers to no anchor before it"
            self.fail(event, f"alias *{show_value(event.anchor)[1:-1]} {problem}")
        value, size = self.anchors[event.anchor]
        self.count(event, size)
        self.add(event, value)

    def start(self, event: ev.CollectionStartEvent) -> None:
        is_map = isinstance(event, ev.MappingStartEvent)
        self.check_tag(event, "tag:yaml.org,2002:map" if is_map else "tag:yaml.org,2002:seq")
        if len(self.stack) >= MAX_DEPTH:
            self.fail(event, f"lists and mappings are nested deeper than {MAX_DEPTH} levels")
        value: dict | list = {} if is_map else []
        first = self.values - 1
        path = self.add(event, value)
        self.stack.append(_Collection(value, path, event.anchor, first))

    def add(self, event: ev.NodeEvent, value) -> tuple:
        """Place ``value`` in the collection being built; returns its path."""
        line = event.start_mark.line + 1
        if not self.stack:
            self.data = value
            self.lines[()] = line
            return ()
        top = self.stack[-1]
        if isinstance(top.value, list):
            path = top.path + (len(top.value),)
            top.value.append(value)
            self.lines[path] = line
            return path
        if top.key is _NO_KEY:  # a key
            if isinstance(value, (dict, list)):
                self.fail(event, "a mapping key must be a plain value, not a list or mapping")
            if value in top.key_lines:
                self.fail(event, f"duplicate key {show_value(value)} (first at line {top.key_lines[value]})")
            top.key, top.key_line = value, line
            top.key_lines[value] = line
            return top.path
        path = top.path + (top.key,)
        top.value[top.key] = value
        self.lines[path] = top.key_line  # a key's own line, not its value's
        top.key = _NO_KEY
        return path

    def check_tag(self, event: ev.NodeEvent, default: str) -> str:
        tag = event.tag
        if tag is None or tag == "!":
            return default
        if tag not in _TAGS:
            self.fail(event, f"tag {show_value(tag)} is not allowed in gsik files (plain data only)")
        return tag

    def scalar(self, event: ev.ScalarEvent):
        if event.tag is None or event.tag == "!":
            tag = self.untagged(event)
        else:
            tag = self.check_tag(event, _STR)
        if tag == _STR:
            return event.value
        if tag not in _TAGS and tag not in _IMPLICIT_EXTRA:  # pragma: no cover - the safe resolver's set
            self.fail(event, f"values of type {show_value(tag)} are not allowed in gsik files")
        return self.construct(event, tag)

    def untagged(self, event: ev.ScalarEvent) -> str:
        """The tag of a scalar written without one (``!`` forces a string); a merge key is refused."""
        tag = _resolver.resolve(ScalarNode, event.value, event.implicit) if event.tag is None else _STR
        if tag == _MERGE and self.stack and self.stack[-1].key is _NO_KEY and isinstance(self.stack[-1].value, dict):
            self.fail(event, "merge keys ('<<') are not allowed in gsik files")
        return _STR if tag in (_MERGE, _VALUE) else tag

    def construct(self, event: ev.ScalarEvent, tag: str):
        text = event.value
        if tag.endswith(":int") and len(text) > 40:  # beyond int64 in any base; never parse a million digits
            self.fail(event, f"integer {show_value(text)} is too large (the limit is ±{MAX_INT})")
        node = ScalarNode(tag, text, event.start_mark, event.end_mark, event.style)
        try:
            value = _constructor.yaml_constructors[tag](_constructor, node)
        except (ValueError, OverflowError, yaml.YAMLError) as exc:
            self.fail(event, f"cannot read {show_value(text)} as {tag.rsplit(':', 1)[-1]}: {show_value(str(exc))}")
        if type(value) is int and abs(value) > MAX_INT:
            self.fail(event, f"integer {show_value(text)} is too large (the limit is ±{MAX_INT})")
        if type(value) is float and value in (float("inf"), float("-inf")) and "inf" not in text.lower():
            self.fail(event, f"number {show_value(text)} is too large for a float (about ±1.8e308 at most)")
        return value


# -- writing names ---------------------------------------------------------------------------------------------

_PLAIN_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*")


def yaml_string(text: str) -> str:
    """``text`` as a YAML scalar that :func:`load_yaml` reads back as exactly ``text``, key or value.

    A plain identifier-like name (``left_hand``, ``waist.x``) stays plain unless YAML would read it as something
    else (``null``, ``true``, ``on``); anything else is double-quoted with escapes for quotes, backslashes, line
    breaks and control characters, so names of any characters survive a save. (A lone surrogate is escaped too,
    but libyaml refuses to read it back: it is not text, and skeletons refuse such names.)
    """
    if _PLAIN_NAME.fullmatch(text) and _resolver.resolve(ScalarNode, text, (True, False)) == _STR:
        return text
    return '"' + "".join(_escape(c) for c in text) + '"'


def _escape(c: str) -> str:
    code = ord(c)
    if c in '"\\':
        return "\\" + c
    if 0x20 <= code <= 0x7E or (0xA0 <= code <= 0xFFFD and code not in (0x2028, 0x2029, 0xFEFF)
                                and not 0xD800 <= code <= 0xDFFF) or code >= 0x10000:
        return c
    return f"\\x{code:02X}" if code < 0x100 else f"\\u{code:04X}"


__all__ = ["MAX_CHARS", "MAX_DEPTH", "MAX_INT", "MAX_VALUES", "YamlDocument", "load_yaml", "yaml_string"]
