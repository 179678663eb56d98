"""What a solver step or solve returns: :class:`Status` and :class:`SolveResult`."""

from __future__ import annotations

import enum
from typing import NamedTuple

import numpy as np

from gsik import kernels

__all__ = ["SolveResult", "Status", "errors_by_effector", "max_orientation_error", "max_position_error"]


class Status(enum.IntEnum):
    """How a step or a solve ended; the values are the kernels' status codes."""

    #: Every enabled effector is within the position and orientation tolerances.
    CONVERGED = kernels.CONVERGED
    #: Not converged, and the pose no longer changes: the best reach.
    STALLED = kernels.STALLED
    #: The iteration budget ran out while the pose was still improving.
    BUDGET_EXHAUSTED = kernels.BUDGET_EXHAUSTED
    #: The step would have made an angle or an error non-finite: it was refused, the previous pose kept.
    REFUSED = kernels.BUDGET_EXHAUSTED + 1

    @property
    def label(self) -> str:
        """Words for people: "converged", "stalled", "budget exhausted"."""
        return self.name.lower().replace("_", " ")


_STATUSES = tuple(Status)  # by code: a tuple index costs less than Status(code)


class SolveResult(NamedTuple):
    """What a step or a solve produced. Plain data; arrays are read-only copies.

    Attributes:
        q: Joint angles (n_dofs,) [rad] after the call.
        status: :class:`Status`.
        iterations: Gauss-Seidel sweeps of a step; linearisations of a solve,
            all its attempts together.
        sweeps: Gauss-Seidel sweeps in all (of all attempts).
        residual: Projected ``|Ax - b|`` of the last sweep (a step), or the
            weighted squared error ``0.5 e^T W e`` (a solve).
        effector_names: (m,) effectors, in the order of the error arrays.
        position_errors: (m,) distance to each target [m] (0 without a target).
        orientation_errors: (m,) angle to each target orientation [rad] (0
            where the orientation is not used).
        step_norm: Size of the last change of ``q`` [rad].
        attempts: Attempts :meth:`Solver.solve` made (1 for a step; 1 with
            no work when it starts from a settled best reach).
    """

    q: np.ndarray
    status: Status
    iterations: int
    sweeps: int
    residual: float
    effector_names: tuple[str, ...]
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    step_norm: float = 0.0
    attempts: int = 1

    @property
    def converged(self) -> bool:
        return self.status is Status.CONVERGED

    max_position_error = property(lambda self: max_position_error(self), doc="Largest position error [m].")
    max_orientation_error = property(lambda self: max_orientation_error(self),
                                     doc="Largest orientation error [rad].")

    def errors(self) -> dict[str, tuple[float, float]]:
        """``{effector: (position error [m], orientation error [rad])}``."""
        return errors_by_effector(self)


# Summaries of any result holding effector_names, position_errors and orientation_errors
# (NamedTuples cannot share a mixin, so the results share these functions).
def max_position_error(result) -> float:
    """Largest position error [m] of a result."""
    return float(result.position_errors.max(initial=0.0))


def max_orientation_error(result) -> float:
    """Largest orientation error [rad] of a result."""
    return float(result.orientation_errors.max(initial=0.0))


def errors_by_effector(result) -> dict[str, tuple[float, float]]:
    """``{effector: (position error [m], orientation error [rad])}`` of a result."""
    return {n: (float(p), float(o)) for n, p, o in zip(result.effector_names, result.position_errors,
                                                       result.orientation_errors)}
