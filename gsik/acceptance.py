"""Whether a prioritised step is kept: the levels' states compared in priority order.

:class:`gsik.control.Controller` evaluates every level (the targets of each
priority, balance, the posture last) at the current pose and at a trial pose
as a :class:`LevelState`, and keeps the trial only if :func:`compare` finds it
better. The rule is lexicographic with two allowances, each bounded so that a
held target settles instead of wobbling or creeping:

- A level *met* (its targets within half their tolerances) before and after
  counts as unchanged, so a lower level may improve while it floats inside
  that band. Leaving the band is worse, entering it better, at any cost
  (position and orientation errors trade inside one cost). A met level's
  tightening, by more than its ``floors`` cost, makes the step better only
  when nothing below it changes: a met level's gain never pays for a lower
  level's loss.
- A level that is not met counts as unchanged while it stays within
  ``settle`` (a fraction) of its *anchor*, the least cost it had since a level
  above it, or itself, last improved (:func:`anchored`); so small losses never
  add up step after step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

BETTER, SAME, WORSE = "better", "same", "worse"


class LevelState(NamedTuple):
    """The levels at one pose.

    Attributes:
        costs: (L + 1,) weighted squared error ``0.5 e^T W e`` of each level in priority order, the posture's last.
        met: (L + 1,) True where a level is within its band (the posture never is).
        anchors: (L + 1,) the cost each level is held to (:func:`anchored`).
        converged: Every target is within the position and orientation tolerances.
        target_cost: Weighted squared error of all targets.
        error: (6 m,) the targets' error rows (target minus current), for the linearised levels.
        lagging: A target is off by more than :data:`gsik.control.TRACKING_ERROR` times its tolerance.
    """

    costs: np.ndarray
    met: np.ndarray
    anchors: np.ndarray
    converged: bool
    target_cost: float
    error: np.ndarray
    lagging: bool = False


def anchored(state: LevelState, before: LevelState | None = None, decided: int = 0) -> LevelState:
    """``state`` with its anchors: the least cost of each level since a level above it, or itself, improved.

    Args:
        state: The levels at the pose just accepted (its own anchors ignored).
        before: The state the step started from (``None``: a pose with no history, anchored at its own costs).
        decided: The level whose improvement accepted the step; it and the levels below start afresh.
    """
    anchors = state.costs.copy() if before is None else np.minimum(before.anchors, state.costs)
    anchors[decided:] = state.costs[decided:]
    return state._replace(anchors=anchors)


def compare(before: LevelState, after: LevelState, settle: float, floors: np.ndarray,
            upto: int | None = None) -> tuple[str, int]:
    """``(BETTER | SAME | WORSE, deciding level)`` of ``after`` against ``before`` (see the module's rule).

    Args:
        before: The state the step starts from, with its anchors.
        after: The trial's state.
        settle: Fraction of a level's anchor it may rise by and still count as unchanged.
        floors: (L + 1,) least fall of a met level's cost that counts as tightening.
        upto: Compare the levels above this one only (``None``: all).
    """
    tightened = loosened = False
    upto = len(floors) if upto is None else upto
    # Plain floats: a loop over NumPy scalars costs more than the whole comparison.
    levels = zip(before.costs[:upto].tolist(), before.anchors.tolist(), after.costs.tolist(), before.met.tolist(),
                 after.met.tolist(), floors.tolist())
    for k, (c0, anchor, c1, met0, met1, floor) in enumerate(levels):
        if met0 and met1:
            tightened = tightened or c1 < c0 - floor
            loosened = loosened or c1 > c0 + floor
            continue
        if met0 != met1:
            return (BETTER if met1 else WORSE), k
        if c1 > anchor * (1.0 + settle) + 1e-300:
            return WORSE, k
        if c1 < c0 * (1.0 - settle):
            return BETTER, k
    return (BETTER if tightened and not loosened else SAME), upto
