"""The one error hierarchy of gsik.

Every error gsik raises on bad input is a :class:`GsikError`. Each subclass
also derives from the built-in exception a caller would naturally catch
(``ValueError`` for bad values, ``OSError`` for files that cannot be written),
so ``except ValueError`` keeps working for code that does not know gsik.
"""

from __future__ import annotations

import reprlib
from collections.abc import Iterable


class GsikError(Exception):
    """Base class of every error raised by gsik; ``exit_code`` is the command line's exit code for it."""

    exit_code = 2  # bad input


class SkeletonError(GsikError, ValueError):
    """A skeleton definition is invalid (bad field, unknown parent, cycle, ...)."""


class TargetError(GsikError, ValueError):
    """An effector target is invalid (NaN, not a rotation, unknown effector, ...)."""


class SolverError(GsikError, ValueError):
    """Solver settings or solver calls are invalid (bad setting, unknown root, ...)."""


class PoseError(GsikError, ValueError):
    """A pose file or pose data is invalid."""


class BvhError(GsikError, ValueError):
    """A BVH file is malformed; ``line`` is the 1-based line number, when known."""

    def __init__(self, message: str, *, line: int | None = None, path: str | None = None):
        self.line = line
        self.path = path
        where = path or ""
        if line is not None:
            where = f"{where}:{line}" if where else f"line {line}"
        super().__init__(f"{where}: {message}" if where else message)


class UrdfError(GsikError, ValueError):
    """A URDF robot description is malformed or uses an unsupported feature."""


class GaitError(GsikError, ValueError):
    """Walk parameters are invalid, or the skeleton lacks a site the gait needs."""


class ScenarioError(GsikError, ValueError):
    """An unknown scenario, a skeleton a scenario does not fit, or bad run settings."""


class RetargetError(GsikError, ValueError):
    """A clip cannot be retargeted: a bad mapping, or joints the retargeting needs are not mapped."""


class ToleranceError(GsikError, ValueError):
    """A computed result (a retargeted or tracked clip) is outside its tolerance, so it is not written; exit code 3."""

    exit_code = 3


class HumanoidError(GsikError, ValueError):
    """A rig cannot be read as a humanoid: required bones not found, or a bad mapping entry."""


class PriorError(GsikError, ValueError):
    """A pose prior file or pose-prior data is invalid, or does not fit the skeleton."""


class GltfError(GsikError, ValueError):
    """A glTF file is malformed, unsafe (a URI outside its folder, sizes past the limits) or not a skinned humanoid."""


class GsikFileError(GsikError, OSError):
    """A file could not be read or written (permission, missing folder, full disk).

    ``errno`` and ``filename`` may be set as on an ``OSError``; the message
    stays the readable sentence it was made with.
    """

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else super().__str__()


# -- bounded message text: a value quoted in a message never makes the message long ------------------------------
# A hostile file can hold a 20 MB name or a list of a million numbers; quoting it whole would make a 20 MB message
# (and, for nested data, take unbounded time to format). Every value gsik quotes goes through show_value, every
# list of valid names through choices.

#: Longest quoted value in a message [characters].
MAX_VALUE_CHARS = 80

#: Most names a message lists before saying how many more there are.
MAX_NAMES = 60

_repr = reprlib.Repr()
_repr.maxlevel = 3
_repr.maxstring = _repr.maxother = MAX_VALUE_CHARS
_repr.maxlong = 40
_repr.maxlist = _repr.maxtuple = _repr.maxdict = _repr.maxset = _repr.maxfrozenset = _repr.maxdeque = 6
_repr.maxarray = 6


def show_value(value, limit: int = MAX_VALUE_CHARS) -> str:
    """``repr(value)`` cut to at most ``limit`` characters (ending in ``...`` when cut).

    Bounded in time and memory however large or deeply nested ``value`` is: a long string is cut before its
    ``repr`` is made, a container shows its first few items.
    """
    if isinstance(value, str) and len(value) > limit:
        text = repr(value[:limit]) + "..."
    else:
        text = _repr.repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def choices(names: Iterable, limit: int = MAX_NAMES) -> str:
    """Valid names for an error message, ``'a', 'b', 'c'``; past ``limit`` names, ``..., and 88 more``."""
    names = names if isinstance(names, (list, tuple)) else list(names)
    shown = ", ".join(show_value(n) for n in names[:limit])
    return f"{shown}, ... and {len(names) - limit} more" if len(names) > limit else shown
