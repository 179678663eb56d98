"""The prioritised path's stall detector: steps that only creep are a settled pose.

A target beyond reach by a hair (a head turned about its own centre on a straight spine, a pole off the circle its
joint can swing on) is approached ever more slowly: each step is better, so the acceptance rule
(:mod:`gsik.acceptance`) keeps taking them, and the studio's frame loop would run at full load for minutes for a
change no one can see. :class:`StallDetector` calls such a run of steps a stall.
"""

from __future__ import annotations

import collections
import math

import numpy as np

#: A stall is judged over this many steps, taken or refused (a run of refusals while the damping climbs is one) ...
STALL_WINDOW = 6
#: ... in which no unmet level's weighted error norm fell by this fraction of that norm at its tolerances ...
STALL_PROGRESS = 0.05
#: ... nor by this fraction of its own size: at that pace it would need over a hundred frames to move by one
#: tolerance, or some 200 to halve (a pole 0.3 m off, its joint swinging 2 mm a frame, still closes in).
STALL_SHRINK = 0.02


class StallDetector:
    """The levels' error norms over the last steps, and whether they creep.

    Args:
        tolerance_norms: (K,) each level's weighted error norm ``sqrt(0.5 e^T W e)`` with every error at its
            tolerance (0 for a level without tolerances, the posture: only its own size counts).
    """

    def __init__(self, tolerance_norms: np.ndarray):
        self._enough = (STALL_PROGRESS * np.asarray(tolerance_norms, dtype=float)).tolist()
        # (unmet levels (K,) bool, every level's error norm (K,)) after each of the last steps taken, as plain
        # Python values: for a handful of levels a loop over them costs a fraction of NumPy's calls.
        self._history: collections.deque = collections.deque(maxlen=STALL_WINDOW + 1)

    def reset(self) -> None:
        """Forget the steps so far (the targets or the pose changed from outside)."""
        self._history.clear()

    def creeps(self, unmet: np.ndarray, costs: np.ndarray) -> bool:
        """True if over the last :data:`STALL_WINDOW` steps (taken or refused) no unmet level gained enough.

        Args:
            unmet: (K,) True where a level is still to be met (none: never a stall); an array or a list.
            costs: (K,) the levels' weighted squared errors ``0.5 e^T W e`` after this step.
        """
        unmet = [bool(u) for u in (unmet.tolist() if isinstance(unmet, np.ndarray) else unmet)]
        if not any(unmet) or (self._history and self._history[-1][0] != unmet):
            self._history.clear()  # a level met or unmet anew starts the count again
        if not any(unmet):
            return False
        norms = [math.sqrt(c) if c >= 0.0 else math.nan
                 for c in (costs.tolist() if isinstance(costs, np.ndarray) else map(float, costs))]
        self._history.append((unmet, norms))
        if len(self._history) <= STALL_WINDOW:
            return False
        before = self._history[0][1]
        for k, u in enumerate(unmet):
            # "not (gain < enough)": a NaN gain is progress unknown, never a creep.
            if u and not before[k] - norms[k] < max(self._enough[k], STALL_SHRINK * before[k]):
                return False
        return True


def unmet_levels(met: np.ndarray, posture_on: bool) -> list[bool]:
    """(L + 1,) True for each level still to be met, from ``met`` (L + 1,): the posture (when on) always is."""
    unmet = [not m for m in np.asarray(met, dtype=bool).tolist()]
    unmet[-1] = bool(posture_on)
    return unmet


class PostureSettle:
    """Whether a prioritised solve's posture has settled, in its own terms: the change its next step would make.

    With every target within its tolerances, a prioritised step is the posture's Gauss-Newton step in the targets'
    tangent null space: its largest change of one DOF [rad] estimates how far the posture's optimum still is. The
    constraints' curvature (the targets' multipliers times their second derivatives), which the step ignores, makes
    the steps a linear contraction (bench_drag with a posture of weight 1: each step 2-7x shorter than the last), so
    the estimate is short by about ``1 / (1 - theta)``; near a fold of the targets' reach the steps may instead
    reverse (the studio's drag, arms nearly straight), and no step settles. The posture has settled when a step
    computed with the targets within their tolerances at its start, and ending with them there, changes no DOF by
    more than the tolerance: the attempt ends there instead of going on until a step gains under
    ``settle_tolerance`` (a met target's in-band correction, part of every full step, costs the posture more than
    that near its optimum: refusals while the damping climbs, until :class:`StallDetector` calls a stall).

    Args:
        tolerance: The largest change of one DOF [rad] of a step that settles the posture (0: never).
        converged: Every target is within its tolerances at the start pose.
    """

    def __init__(self, tolerance: float, converged: bool):
        self._tolerance = tolerance
        self._converged = converged

    def settled(self, step: np.ndarray, converged: bool) -> bool:
        """True if this step settles the posture.

        Args:
            step: (n_dofs,) the full prioritised step computed at the step's start pose [rad], whether it was taken
                whole, halved or refused.
            converged: Every target is within its tolerances after the step.
        """
        was, self._converged = self._converged, converged
        return was and converged and float(np.max(np.abs(step), initial=0.0)) <= self._tolerance
