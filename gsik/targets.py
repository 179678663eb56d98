"""Effector targets: validated once, where they enter, and cheap to make.

A target is made on every mouse move while dragging, so construction stays
on a fast path of plain float checks (no ``np.allclose``, no SVD) for the
usual inputs: a float (3,) array or list, a (4,) quaternion, a (3, 3) matrix.
"""

from __future__ import annotations

import math
import struct

import numpy as np

from gsik.errors import TargetError, show_value
from gsik.rotations import ROTATION_TOLERANCE, quaternion_from_rows

#: How far from unit norm a target quaternion may be [-] (the rotation uses it normalised).
QUATERNION_TOLERANCE = ROTATION_TOLERANCE * 100
#: Largest target coordinate [m] (each of x, y, z): far beyond any character, far below where the solver's
#: squares and products of errors and weights could overflow.
MAX_COORDINATE = 1e6
#: Largest target weight [-].
MAX_WEIGHT = 1e6
#: Columns of a target matrix orthonormal within this [-] keep it as given; farther off (up to
#: ``ROTATION_TOLERANCE``) it is re-orthonormalised.
EXACT_ROTATION = 1e-12
#: The identity orientation (w, x, y, z): what a target made without an orientation holds.
IDENTITY = (1.0, 0.0, 0.0, 0.0)
# Fields in value order: equality, hashing and replace() all walk this one list.
_FIELDS = ("position", "orientation", "weight", "position_only", "enabled", "priority")
_PACK3 = struct.Struct("3d").pack
_PACK9 = struct.Struct("9d").pack
#: Write 3 (9) floats into a writable buffer at a byte offset: a position (rotation) row of a float64 array.
PACK3_INTO = struct.Struct("3d").pack_into
PACK9_INTO = struct.Struct("9d").pack_into
_EYE = np.frombuffer(_PACK9(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)).reshape(3, 3)


class Target:
    """An immutable 6-DOF goal for one end-effector.

    Args:
        position: World position (3,) [m].
        orientation: World orientation as a unit quaternion (4,) ``(w, x, y, z)``
            (kept exactly as given) or a rotation matrix (3, 3); ``None`` for a
            position-only target (identity orientation, ``position_only`` set).
        weight: Relative importance (>= 0) in the weighted least squares.
        position_only: Ignore the orientation (kept, so it can be re-enabled).
        enabled: False leaves the effector free: the solver skips the target.
        priority: Strict priority level, a whole number >= 0: 0 (the default)
            is the most important; a target on level k is met only in what
            the levels above it leave free, so it never moves them. Targets on
            one level trade off by ``weight``.

    Attributes:
        position: Read-only float array (3,) [m].
        orientation: Unit quaternion ``(w, x, y, z)`` as a tuple of 4 floats.
        rotation: The orientation as a read-only rotation matrix (3, 3).
        weight, position_only, enabled, priority: As given (float, bool, bool, int).

    Raises:
        TargetError: on NaN or infinite values, wrong shapes, a matrix that
            is not a rotation, a quaternion that is not of unit norm, a
            negative weight, or a priority that is not a whole number >= 0.

    Targets compare and hash by value (position, orientation, weight,
    position_only, enabled, priority), so whole poses compare equal.
    """

    __slots__ = ("position", "_orientation", "rotation", "weight", "position_only", "enabled", "priority", "_key")

    def __init__(self, position, orientation=None, weight: float = 1.0, position_only: bool = False,
                 enabled: bool = True, priority: int = 0):
        if orientation is None:
            q, R, position_only = IDENTITY, _EYE, True
        else:
            q, R = checked_orientation(orientation)
        self._fill(_position(position), q, R, weight, position_only, enabled, priority)

    def _fill(self, p: np.ndarray, q: tuple, R: np.ndarray, weight, position_only, enabled, priority) -> None:
        _set = object.__setattr__
        _set(self, "position", p)
        _set(self, "_orientation", q)
        _set(self, "rotation", R)
        _set(self, "weight", weight if type(weight) is float and 0.0 <= weight <= MAX_WEIGHT else _weight(weight))
        _set(self, "position_only", bool(position_only))
        _set(self, "enabled", bool(enabled))
        _set(self, "priority", priority if type(priority) is int and priority >= 0 else _priority(priority))
        _set(self, "_key", None)

    def __setattr__(self, name, value):
        raise AttributeError(f"Target is immutable; use replace({name}=...)")

    def __delattr__(self, name):
        raise AttributeError("Target is immutable")

    def _values(self) -> tuple:
        if self._key is None:
            values = tuple(getattr(self, f) for f in _FIELDS)
            object.__setattr__(self, "_key", (tuple(self.position.tolist()),) + values[1:])
        return self._key

    def __eq__(self, other):
        if not isinstance(other, Target):
            return NotImplemented
        return self is other or self._values() == other._values()

    def __hash__(self):
        return hash(self._values())

    def __repr__(self):
        return "Target(" + ", ".join(f"{n}={v!r}" for n, v in zip(_FIELDS, self._values())) + ")"

    def __reduce__(self):
        return _rebuild, self._values()

    @property
    def orientation(self) -> tuple[float, float, float, float]:
        """Unit quaternion ``(w, x, y, z)``: as given, or (given a matrix) made from it on first use."""
        if self._orientation is None:
            object.__setattr__(self, "_orientation", quaternion_from_rows(self.rotation.tolist()))
        return self._orientation

    @property
    def uses_orientation(self) -> bool:
        """True if the orientation rows take part in the solve."""
        return not self.position_only

    @property
    def quaternion(self) -> np.ndarray:
        """The orientation as a unit quaternion (4,) ``(w, x, y, z)`` array (a copy)."""
        return np.array(self.orientation)

    @classmethod
    def from_transform(cls, world_from_effector: np.ndarray, weight: float = 1.0, position_only: bool = False,
                       enabled: bool = True, priority: int = 0) -> Target:
        """A target at a world transform (4, 4); its rotation block becomes :attr:`rotation` as given."""
        T = world_from_effector if type(world_from_effector) is np.ndarray else np.asarray(world_from_effector,
                                                                                              dtype=float)
        if T.shape != (4, 4):
            raise TargetError(f"target transform must have shape (4, 4), got {T.shape}")
        return cls(T[:3, 3], T[:3, :3], weight, position_only, enabled, priority)

    def _moved_to(self, xyz: tuple[float, float, float], q: tuple | None, rows: tuple | None) -> Target:
        """A copy at the position ``xyz`` and, unless ``rows`` is None, the orientation ``(q, rows)``, both already
        checked (:func:`checked_position`, :func:`checked_rotation`): what ``replace`` would make."""
        new = Target.__new__(Target)
        q, R = (self._orientation, self.rotation) if rows is None else (q, rotation_matrix(rows))
        new._fill(np.frombuffer(_PACK3(*xyz)), q, R, self.weight, self.position_only, self.enabled, self.priority)
        return new

    def replace(self, **changes) -> Target:
        """A copy with some fields changed (validated again; an unchanged orientation keeps its matrix)."""
        unknown = sorted(set(changes) - set(_FIELDS))
        if unknown:
            raise TargetError(f"unknown Target field(s) {unknown}; valid: {list(_FIELDS)}")
        values = {f: getattr(self, f) for f in _FIELDS if f != "orientation"}  # the quaternion only if needed
        values.update(changes)
        if "orientation" in changes:
            return Target(**values)
        new = Target.__new__(Target)  # same orientation: keep its quaternion and matrix
        new._fill(_position(values["position"]), self._orientation, self.rotation, values["weight"],
                  values["position_only"], values["enabled"], values["priority"])
        return new


def _rebuild(position, orientation, weight, position_only, enabled, priority=0) -> Target:
    return Target(position, orientation, weight, position_only, enabled, priority)


def _position(value) -> np.ndarray:
    return np.frombuffer(_PACK3(*checked_position(value)))  # a fresh read-only float64 array


def checked_position(value) -> tuple[float, float, float]:
    """A target position ``value`` (3,) [m] as three floats, checked as :class:`Target` checks it.

    Raises:
        TargetError: if it is not 3 numbers, or not finite, or farther than :data:`MAX_COORDINATE`.
    """
    x, y, z = _three_floats(value)
    if not (abs(x) <= MAX_COORDINATE and abs(y) <= MAX_COORDINATE and abs(z) <= MAX_COORDINATE):  # NaN fails too
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            raise TargetError(f"target position must be finite, got {[x, y, z]}")
        raise TargetError(f"target position must be within {MAX_COORDINATE:g} m of the origin in x, y and z, "
                          f"got {[x, y, z]}")
    return x, y, z


def _three_floats(value) -> tuple[float, float, float]:
    """A position ``value`` (3,) as three Python floats, not yet checked for range."""
    if type(value) is np.ndarray and value.shape == (3,):
        xyz = value.tolist()
    else:
        try:
            a = np.array(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise TargetError(f"target position must be 3 numbers, got {show_value(value)}") from None
        if a.shape != (3,):
            raise TargetError(f"target position must have shape (3,), got {a.shape}")
        xyz = a.tolist()
    try:
        return float(xyz[0]), float(xyz[1]), float(xyz[2])
    except (TypeError, ValueError, OverflowError):
        raise TargetError(f"target position must be 3 numbers, got {show_value(value)}") from None


def _priority(value) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise TargetError(f"target priority must be a whole number >= 0 (0 is the most important), got {value!r}")
    return int(value)


def _weight(value) -> float:
    try:
        w = float(value)
    except (TypeError, ValueError, OverflowError):
        raise TargetError(f"target weight must be a number, got {show_value(value)}") from None
    if not 0.0 <= w <= MAX_WEIGHT:  # NaN fails too
        raise TargetError(f"target weight must be finite and >= 0, at most {MAX_WEIGHT:g}, got {show_value(value)}")
    return w


def checked_orientation(value) -> tuple[tuple[float, float, float, float] | None, np.ndarray]:
    """``(quaternion, read-only matrix)`` of a quaternion (4,) or a rotation matrix (3, 3) (quaternion None),
    checked as :class:`Target` checks it.

    Raises:
        TargetError: for a wrong shape, a non-finite value, a matrix that is not a rotation or a quaternion not
            of unit norm.
    """
    q, rows = checked_rotation(value)
    return q, rotation_matrix(rows)


def rotation_matrix(rows: tuple[float, ...]) -> np.ndarray:
    """A fresh read-only rotation matrix (3, 3) of its 9 entries ``rows`` (row by row)."""
    return np.frombuffer(_PACK9(*rows)).reshape(3, 3)


def checked_rotation(value) -> tuple[tuple[float, float, float, float] | None, tuple[float, ...]]:
    """``(quaternion, the rotation matrix's 9 entries row by row)`` of a quaternion (4,) or a rotation matrix
    (3, 3) (quaternion None), checked as :func:`checked_orientation`; no array made."""
    if type(value) is tuple and len(value) == 4:
        return _from_quaternion(value)
    try:  # dtype.char: comparing the dtype with np.float64 costs microseconds
        a = value if type(value) is np.ndarray and value.dtype.char == "d" else np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise TargetError(f"target orientation must be a 3x3 rotation matrix or a quaternion, "
                          f"got {show_value(value)}") from None
    if a.shape == (4,):
        return _from_quaternion(tuple(a.tolist()))
    if a.shape == (3, 3):
        return _from_matrix(a)
    raise TargetError(f"target orientation must have shape (3, 3) or (4,), got {a.shape}")


def _from_quaternion(q: tuple) -> tuple[tuple[float, float, float, float], tuple[float, ...]]:
    try:
        w, x, y, z = q = (float(q[0]), float(q[1]), float(q[2]), float(q[3]))
    except (TypeError, ValueError, OverflowError):
        raise TargetError(f"target quaternion (w, x, y, z) must be 4 numbers, got {show_value(q)}") from None
    n2 = w * w + x * x + y * y + z * z
    if not math.isfinite(n2):
        if all(math.isfinite(v) for v in q):  # huge components: their squares overflow
            raise TargetError(f"target quaternion (w, x, y, z) must have unit norm, got {list(q)}")
        raise TargetError(f"target orientation must be finite, got {list(q)}")
    norm = math.sqrt(n2)
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise TargetError(f"target quaternion (w, x, y, z) must have unit norm, got norm {norm:.6g}")
    s = 2.0 / n2
    return q, (1.0 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y),
               s * (x * y + w * z), 1.0 - s * (x * x + z * z), s * (y * z - w * x),
               s * (x * z - w * y), s * (y * z + w * x), 1.0 - s * (x * x + y * y))


def _from_matrix(a: np.ndarray) -> tuple[None, tuple[float, ...]]:
    m = a.tolist()
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = m
    # Columns orthonormal and det > 0, in plain floats (np.allclose costs more than the whole target).
    off = max(abs(a00 * a00 + a10 * a10 + a20 * a20 - 1.0), abs(a01 * a01 + a11 * a11 + a21 * a21 - 1.0),
              abs(a02 * a02 + a12 * a12 + a22 * a22 - 1.0), abs(a00 * a01 + a10 * a11 + a20 * a21),
              abs(a00 * a02 + a10 * a12 + a20 * a22), abs(a01 * a02 + a11 * a12 + a21 * a22))
    det = a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20)
    if not (off <= ROTATION_TOLERANCE and det > 0.0):  # NaN fails too
        if not all(math.isfinite(v) for row in m for v in row):
            raise TargetError(f"target orientation must be finite, got {m}")
        raise TargetError("target orientation is not a rotation matrix (must be orthonormal with determinant +1)")
    if off > EXACT_ROTATION:
        # Re-orthonormalise what is visibly off, so the kernels' log map sees an exact rotation.
        u, _, vt = np.linalg.svd(a)
        (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = (u @ vt).tolist()
    return None, (a00, a01, a02, a10, a11, a12, a20, a21, a22)  # the quaternion is computed when first asked for
