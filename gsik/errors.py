"""The one error hierarchy of gsik.

Every error gsik raises on bad input is a :class:`GsikError`. Each subclass
also derives from the built-in exception a caller would naturally catch
(``ValueError`` for bad values, ``OSError`` for files that cannot be written),
so ``except ValueError`` keeps working for code that does not know gsik.
"""

from __future__ import annotations

from collections.abc import Iterable


class GsikError(Exception):
    """Base class of every error raised by gsik."""


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


class PriorError(GsikError, ValueError):
    """A pose prior file or pose-prior data is invalid, or does not fit the skeleton."""


class GsikFileError(GsikError, OSError):
    """A file could not be read or written (permission, missing folder, full disk).

    ``errno`` and ``filename`` may be set as on an ``OSError``; the message
    stays the readable sentence it was made with.
    """

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else super().__str__()


def choices(names: Iterable[str]) -> str:
    """Format valid names for an error message: ``'a', 'b', 'c'``."""
    return ", ".join(repr(n) for n in names)
