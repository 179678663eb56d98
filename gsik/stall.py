"""The prioritised path's stall detector: steps that only creep are a settled pose.

A target beyond reach by a hair (a head turned about its own centre on a straight spine, a pole off the circle its
joint can swing on) is approached ever more slowly: each step is better, so the acceptance rule
(:mod:`gsik.acceptance`) keeps taking them, and the studio's frame loop would run at full load for minutes for a
change no one can see. :class:`StallDetector` calls such a run of steps a stall.
"""

from __future__ import annotations

import collections

import numpy as np

#: A stall is judged over this many steps taken ...
STALL_WINDOW = 10
#: ... in which no unmet target level's weighted error norm fell by this fraction of that norm at its tolerances,
#: nor of its own size: at that pace it would need hundreds of frames to move by one tolerance or to halve.
STALL_PROGRESS = 0.05


class StallDetector:
    """The target levels' error norms over the last steps, and whether they creep.

    Args:
        tolerance_norms: (L,) each target level's weighted error norm ``sqrt(0.5 e^T W e)`` with every error at
            its tolerance.
    """

    def __init__(self, tolerance_norms: np.ndarray):
        self._enough = STALL_PROGRESS * np.asarray(tolerance_norms, dtype=float)
        # (unmet levels (L,) bool, every target level's error norm (L,)) after each of the last steps taken.
        self._history: collections.deque = collections.deque(maxlen=STALL_WINDOW + 1)

    def reset(self) -> None:
        """Forget the steps so far (the targets or the pose changed from outside)."""
        self._history.clear()

    def creeps(self, met: np.ndarray, costs: np.ndarray, taken: bool) -> bool:
        """True if over the last :data:`STALL_WINDOW` steps taken no unmet target level gained enough.

        Args:
            met: (L,) True where a target level is within its band (all met: never a stall).
            costs: (L,) the target levels' weighted squared errors ``0.5 e^T W e`` after this step.
            taken: The step was taken (a refused step adds nothing, but within a creep it is part of it).
        """
        unmet = ~np.asarray(met, dtype=bool)
        if not unmet.any() or (self._history and not np.array_equal(self._history[-1][0], unmet)):
            self._history.clear()  # a level met or unmet anew starts the count again
        if not unmet.any():
            return False
        norms = np.sqrt(costs)
        if taken or not self._history:
            self._history.append((unmet, norms))
        before = self._history[0][1]
        enough = np.maximum(self._enough, STALL_PROGRESS * before)
        return len(self._history) > STALL_WINDOW and bool(np.all((before - norms)[unmet] < enough[unmet]))
