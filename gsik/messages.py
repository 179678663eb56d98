"""Bounded text for error messages: a value quoted in a message never makes the message long.

A hostile file can hold a 20 MB name or a list of a million numbers; quoting it whole would make a 20 MB message
(and, for nested data, take unbounded time to format). Every value gsik quotes in a message goes through
:func:`show_value`, every list of valid names through :func:`show_names`.
"""

from __future__ import annotations

import reprlib
from collections.abc import Iterable

#: Longest quoted value in a message [characters].
MAX_VALUE_CHARS = 80

#: Most names a message lists before saying how many there are in all.
MAX_NAMES = 12

_repr = reprlib.Repr()
_repr.maxlevel = 3
_repr.maxstring = MAX_VALUE_CHARS
_repr.maxother = MAX_VALUE_CHARS
_repr.maxlong = 40
_repr.maxlist = _repr.maxtuple = _repr.maxdict = _repr.maxset = _repr.maxfrozenset = _repr.maxdeque = 6
_repr.maxarray = 6


def show_value(value, limit: int = MAX_VALUE_CHARS) -> str:
    """``repr(value)``, cut to at most ``limit`` characters (ending in ``...`` when cut).

    Works in time and memory bounded by ``limit`` for strings and by the few items it looks at for containers,
    however large or deeply nested ``value`` is.
    """
    if isinstance(value, str) and len(value) > limit:
        value = value[:limit]  # repr of the head only: never copy a 20 MB string
        text = repr(value) + "..."
    else:
        try:
            text = _repr.repr(value)
        except Exception:  # a hostile __repr__: say what it is instead
            text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[:limit - 3] + "..."


def show_names(names: Iterable, limit: int = MAX_NAMES) -> str:
    """Valid names for a message, ``'a', 'b', 'c'``; past ``limit`` names, ``..., and 88 more``."""
    names = list(names) if not isinstance(names, (list, tuple)) else names
    shown = ", ".join(show_value(n) for n in names[:limit])
    return f"{shown}, ... and {len(names) - limit} more" if len(names) > limit else shown
