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

from gsik.kernels import settle
from gsik.kernels.settle import COLLINEAR, CONTRACTION, MIN_POSTURE_GAIN  # noqa: F401  (re-exported)

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
    """A prioritised solve's posture: the share of its Gauss-Newton step each step takes, and whether it has settled.

    With every target within its tolerances, a prioritised step is the posture's Gauss-Newton step in the targets'
    tangent null space. That step ignores the constraints' curvature (the targets' multipliers times their second
    derivatives): along the step the posture's true curvature is ``h`` times the one the step assumes, and steps
    taking a share ``g`` of it shrink or swing by ``mu = 1 - g h`` a step (bench_drag: ``mu`` 0.1-0.5 with a posture
    of weight 1; -1, a swing without end, with the studio's prior and the arms nearly straight, near a fold of the
    hands' reach). Two consecutive posture moves ``m1``, ``m2`` along one line (:data:`COLLINEAR`) measure
    ``mu = m2.m1 / m1.m1`` (a secant along the step), and the gain becomes ``g / (1 - mu)``, the share that would
    have closed in at once (at most 1, at least :data:`MIN_POSTURE_GAIN`); the gain is written in place into the
    controller's ``posture_gain``. A move is a posture move when it is at least half its step's full step (not a
    halved trial, nor the target levels' step alone) and every target is within its tolerances at both its ends.

    The posture has settled when a step computed with the targets within their tolerances at its start, and ending
    with them there, estimates the posture's remaining change (its full step over the gain it was made with) at no
    DOF above the tolerance [rad]: the attempt ends there instead of going on until a step gains under
    ``settle_tolerance`` (near its optimum a met target's in-band correction, part of every full step, costs the
    posture more than that: refusals while the damping climbs, until :class:`StallDetector` calls a stall).

    A warm attempt (a solve()'s first, starting where the last solve converged and its last attempt with this
    controller ended, as a drag's solve() a frame does: ``contraction`` given) reads its steps as a secant-tuned
    iteration. Its gain is the share that closes in at once, so the step itself, not the step over the gain,
    estimates the remaining change (the test: no DOF of the full step above the tolerance). And it skips the
    verifying step: a step taken whole and ending with every target within its tolerances settles the posture when
    its full step times the contraction (the larger of its ratio to the last whole step's and ``contraction``, the
    last ratio the previous attempt measured: a slow mode the first steps hide) passes that test, the contraction at
    most :data:`CONTRACTION` (:meth:`_predicted`). A cold attempt (``None``) keeps the test above, bit for bit.

    Args:
        tolerance: The largest remaining change of one DOF [rad] of a settled posture (0: never settled).
        converged: Every target is within its tolerances at the start pose.
        gain: (1,) the controller's posture gain, adapted in place.
        contraction: A warm attempt's starting contraction (the ratio of consecutive whole steps' largest DOFs the
            last attempt measured last, 0 if none), or ``None`` for a cold attempt. :attr:`contraction` is the
            last one measured (for the next warm attempt).
    """

    def __init__(self, tolerance: float, converged: bool, gain: np.ndarray, contraction: float | None = None):
        self.gain = gain
        #: (STATE_SIZE,) the test's state, read and written by :func:`gsik.kernels.settle.settled`
        self.state = state = np.zeros(settle.STATE_SIZE)
        state[settle.TOLERANCE], state[settle.CONVERGED] = tolerance, converged
        state[settle.WARM] = contraction is not None
        state[settle.CARRIED] = state[settle.CONTRACTION_NOW] = contraction or 0.0
        self._last_move = np.zeros(0)  # the last posture move (n_dofs,) [rad]: move_buffer(n)

    @property
    def converged(self) -> bool:
        """Every target within its tolerances after the last step (at the start pose before one)."""
        return bool(self.state[settle.CONVERGED])

    @property
    def contraction(self) -> float:
        """The ratio of the last two whole steps' largest DOFs measured last (or the one carried in)."""
        return float(self.state[settle.CONTRACTION_NOW])

    def settled(self, step: np.ndarray, moved: np.ndarray, converged: bool) -> bool:
        """True if this step settles the posture; adapts the gain from this step's move and the last one's
        (:func:`gsik.kernels.settle.settled`: the compiled loop of steps takes the same test).

        Args:
            step: (n_dofs,) the full prioritised step computed at the step's start pose [rad], whether it was taken
                whole, halved or refused.
            moved: (n_dofs,) the change of the angles the step made [rad] (0 if refused).
            converged: Every target is within its tolerances after the step.
        """
        return settle.settled(self.state, self.gain, step, moved, self.move_buffer(moved.shape[0]), converged)

    def move_buffer(self, n: int) -> np.ndarray:
        """(n,) where :func:`gsik.kernels.settle.settled` keeps the last posture move [rad] (made at the first
        step)."""
        if self._last_move.shape[0] != n:
            self._last_move = np.zeros(n)
        return self._last_move
