"""Small validators shared by every place data enters gsik (files, constructors, run settings).

Each takes the value, ``what`` (the place, named in the message) and ``error``
(the :class:`~gsik.errors.GsikError` subclass of the caller's domain), and
returns the value converted (floats, tuples, read-only arrays) or raises
``error`` with a message that names the place and the bad value.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np

from gsik.errors import GsikError

ErrorType = type[GsikError]


def frozen(a, dtype=float) -> np.ndarray:
    """A read-only copy of ``a`` as an array of ``dtype``."""
    a = np.array(a, dtype=dtype)
    a.flags.writeable = False
    return a


def number(value, what: str, error: ErrorType) -> float:
    """``value`` as a finite float; booleans and strings are refused."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise error(f"{what} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise error(f"{what} must be finite, got {value!r}")
    return float(value)


def in_range(value, lo: float, hi: float, what: str, error: ErrorType, unit: str = "") -> float:
    """``value`` as a finite float in ``[lo, hi]`` (``unit`` is named in the message)."""
    v = number(value, what, error)
    if not lo <= v <= hi:
        raise error(f"{what} must be between {lo} and {hi}{' ' + unit if unit else ''}, got {value!r}")
    return v


def positive(value, what: str, error: ErrorType, unit: str = "") -> float:
    """``value`` as a finite float above zero."""
    if isinstance(value, bool) or not isinstance(value, Real) or not (math.isfinite(value) and value > 0):
        raise error(f"{what} must be a positive number{' of ' + unit if unit else ''}, got {value!r}")
    return float(value)


def whole(value, what: str, error: ErrorType, minimum: int = 0, floats: bool = False) -> int:
    """``value`` as an int ``>= minimum``; with ``floats``, a float of whole value (``4.0``) is accepted too."""
    ok = not isinstance(value, bool) and (isinstance(value, Integral) or
                                          (floats and isinstance(value, Real) and float(value).is_integer()))
    if not ok or value < minimum:
        raise error(f"{what} must be a whole number >= {minimum}, got {value!r}")
    return int(value)


def name(value, what: str, error: ErrorType) -> str:
    """``value`` as a non-empty (not blank) string."""
    if not isinstance(value, str) or not value.strip():
        raise error(f"{what} must be a non-empty string, got {value!r}")
    return value


def vector(value, n: int, what: str, error: ErrorType) -> tuple[float, ...]:
    """``value`` as a tuple of ``n`` finite floats."""
    if _plain_floats(value, n):  # the common case (pose files, drags), without NumPy
        return tuple(value)
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{what} must be {n} numbers, got {value!r}") from None
    if v.shape != (n,):
        raise error(f"{what} must be {n} numbers, got {value!r}")
    if not np.all(np.isfinite(v)):
        raise error(f"{what} must be finite, got {value!r}")
    return tuple(float(x) for x in v)


def _plain_floats(value, n: int) -> bool:
    """True for a tuple or list of ``n`` finite Python floats."""
    return (isinstance(value, (tuple, list)) and len(value) == n
            and all(type(v) is float and math.isfinite(v) for v in value))


def finite_array(value, shape: tuple[int, ...], what: str, error: ErrorType) -> np.ndarray:
    """``value`` as a read-only float array of ``shape`` with finite entries."""
    a = frozen(value)
    if a.shape != tuple(shape):
        raise error(f"{what} must have shape {tuple(shape)}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise error(f"{what} {a.tolist()} is not finite")
    return a


def unit_quaternion(value, what: str, error: ErrorType, tolerance: float = 1e-3) -> np.ndarray:
    """``value`` as a quaternion ``[w, x, y, z]`` (4,) of norm within ``tolerance`` of 1, normalized."""
    q = np.asarray(vector(value, 4, what, error))
    norm = float(np.linalg.norm(q))
    if abs(norm - 1.0) > tolerance:
        raise error(f"{what} must be a unit quaternion [w, x, y, z], got norm {norm:.6g}")
    return q / norm


__all__ = ["frozen", "number", "in_range", "positive", "whole", "name", "vector", "finite_array", "unit_quaternion"]
