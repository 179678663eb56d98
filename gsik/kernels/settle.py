""":class:`gsik.stall.PostureSettle`'s test of each step of a solve()'s posture settle, in one compiled call.

The test reads two largest magnitudes a step (each ``float(np.abs(x).max())`` bit for bit, a NaN propagating) and,
for a posture move, the secant of it and the last one (three dot products, summed in index order). It is one
function, :func:`settled`, over a state array (:data:`TOLERANCE` ...) and the last move, so that the Python loop of
steps (:meth:`gsik.attempts.Attempts._control_steps`) and the compiled one (:mod:`gsik.kernels.settle_steps`) take
the same decisions bit for bit.
"""

from __future__ import annotations

from gsik._jit import njit

#: The least share of the posture's Gauss-Newton step a solve's step takes (:class:`~gsik.stall.PostureSettle`'s
#: secant gain).
MIN_POSTURE_GAIN = 0.1
#: Two posture moves measure the curvature along one direction when the square of their cosine is at least this
#: (within 25 degrees of one line): others turned, and their ratio says nothing about the step's length.
COLLINEAR = 0.81
#: A warm attempt's steps contracting by at least this factor a step converge linearly: the next full step is
#: estimated as the last one times the contraction (:class:`~gsik.stall.PostureSettle`).
CONTRACTION = 0.5

#: Where :func:`settled`'s state (:data:`STATE_SIZE`,) holds: the settle tolerance [rad]; every target within its
#: tolerances after the last step (1/0); a warm attempt (1/0); the contraction carried from the last attempt; the
#: last one measured; the largest DOF [rad] of the last step taken whole (0 before one); the last move is a posture
#: move kept for the next secant (1/0).
TOLERANCE, CONVERGED, WARM, CARRIED, CONTRACTION_NOW, LAST_FULL, HAS_MOVE = range(7)
STATE_SIZE = 7


@njit(cache=True, _nrt=False)
def _largest(x) -> float:
    """``max |x_i|`` of a non-empty (n,) array; NaN if any ``x_i`` is (as NumPy's maximum)."""
    m = abs(x[0])
    for i in range(1, x.shape[0]):
        a = abs(x[i])
        if a > m or a != a:
            m = a
    return m


@njit(cache=True, _nrt=False)
def largest_pair(step, moved) -> tuple:
    """``(max |step_i|, max |moved_i|)`` [rad] of a step's full step (n,) and the change it made (n,) (each
    non-empty; NaN for an array holding one)."""
    return _largest(step), _largest(moved)


@njit(cache=True, _nrt=False)
def _predicted(state, full: float, last: float) -> bool:
    """True if the next step's full step, this one's largest DOF ``full`` [rad] times the contraction (its ratio to
    the last whole step's ``last``, or the carried one if larger), passes the warm settle test."""
    if not last > 0.0:
        return False
    contraction = full / last
    if state[CARRIED] > contraction:  # Python's max(full / last, carried)
        contraction = state[CARRIED]
    return contraction <= CONTRACTION and contraction * full <= state[TOLERANCE]


@njit(cache=True, _nrt=False)
def _secant(state, gain, moved, last_move) -> None:
    """The gain (1,) from this posture move (n,) [rad] and the last one (``last_move``, when ``state`` keeps one),
    when they lie along one line; ``moved`` is kept in ``last_move``."""
    if state[HAS_MOVE] > 0.0:
        dot = mm = ll = 0.0
        for i in range(moved.shape[0]):
            dot += moved[i] * last_move[i]
            mm += moved[i] * moved[i]
            ll += last_move[i] * last_move[i]
        if dot * dot >= COLLINEAR * mm * ll and dot < ll:  # along one line, mu = dot / ll below 1
            g = gain[0] / (1.0 - dot / ll)
            g = g if g > MIN_POSTURE_GAIN else MIN_POSTURE_GAIN  # Python's min(1, max(MIN_POSTURE_GAIN, g))
            gain[0] = g if g < 1.0 else 1.0
    for i in range(moved.shape[0]):
        last_move[i] = moved[i]
    state[HAS_MOVE] = 1.0


@njit(cache=True, _nrt=False)
def settled(state, gain, step, moved, last_move, converged: bool) -> bool:
    """True if this step settles the posture (:class:`gsik.stall.PostureSettle`'s rules); adapts the gain (1,) in
    place from this step's move and the last one's (``last_move`` (n,), rewritten).

    Args:
        state: (:data:`STATE_SIZE`,) the test's state, updated.
        step: (n,) the full prioritised step computed at the step's start pose [rad], whether it was taken whole,
            halved or refused.
        moved: (n,) the change of the angles the step made [rad] (0 if refused).
        converged: Every target is within its tolerances after the step.
    """
    within = state[CONVERGED] > 0.0 and converged
    state[CONVERGED] = 1.0 if converged else 0.0
    full, most = _largest(step), _largest(moved)
    whole = full > 0.0 and most >= 0.5 * full  # not halved twice, nor refused
    last = state[LAST_FULL]
    if whole:  # a step not taken whole (halved, refused, the targets' levels alone) keeps the last whole one
        state[LAST_FULL] = full
        if last > 0.0:
            state[CONTRACTION_NOW] = full / last
    warm = state[WARM] > 0.0
    if not within:
        state[HAS_MOVE] = 0.0
        return warm and converged and whole and _predicted(state, full, last)
    if whole:  # a posture move
        _secant(state, gain, moved, last_move)
    if not warm:
        return full <= state[TOLERANCE] * gain[0]
    return full <= state[TOLERANCE] or (whole and _predicted(state, full, last))
