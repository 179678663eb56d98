"""A solve() attempt's prioritised steps with a posture, until the posture settles, in one compiled call.

A drag's warm :meth:`gsik.Solver.solve` with a posture makes two to ten prioritised steps a frame, and each made two
Python calls around its compiled step (:meth:`gsik.control.Controller.step`: held, committed, creeping; then
:meth:`gsik.stall.PostureSettle.settled`): ~15 µs a step. :func:`settle_steps` runs that loop
(``Attempts._control_steps``) bit for bit: the same compiled step
(:func:`gsik.kernels.step_inputs.control_step_in`), the same judgement of it as ``Controller._committed``, and the same
settle test (:func:`gsik.kernels.settle.settled`). The Python around it (:mod:`gsik.control_settle`) keeps the
controller's held-pose bookkeeping.
"""

from __future__ import annotations

from gsik._jit import njit
from gsik.kernels import curvature, priority, step_inputs
from gsik.kernels.settle import CONVERGED, settled

#: :func:`settle_steps`'s first result: the steps ran (the rest of the tuple holds), or a level's Jacobian went
#: non-finite at step ``steps`` (the controller raises, as its step does).
STEPPED, NOT_FINITE = 0, 2

#: False without numba or with ``NUMBA_DISABLE_JIT``: every attempt takes the Python loop.
AVAILABLE = step_inputs.AVAILABLE


@njit(cache=True)
def settle_steps(s, W, q, R, p, lam, iterations, rest, state, gain, last_move, move, before, cur, learning, carry):
    """Up to ``iterations`` prioritised steps of a controller with a posture (``s``: its
    :class:`~gsik.kernels.step_inputs.StepInputs`) from ``q`` (n,) [rad] at ``W`` (4, 4), in place on ``q``, ``R``,
    ``p`` and ``lam`` (1,), until one holds the pose or settles the posture (:func:`gsik.kernels.settle.settled` on
    ``state``, ``gain`` (1,) and ``last_move`` (n,); ``move`` and ``before`` (n,) are work arrays). ``rest``: the
    first step restarts from the base damping. ``learning``: the curvature ``cur`` is swapped into the posture's level
    (``s.posture.normal``) from the start (:func:`gsik.kernels.curvature.begin`, ``carry``: from what the last
    settle learnt), each step updates it (:func:`~gsik.kernels.curvature.learn`), and the posture's own is back
    at the end (:func:`~gsik.kernels.curvature.end`).

    Returns ``(code, steps, accepted, held, converged, cost, lagging, step_norm, committed, settled)`` of the last
    step (``code`` :data:`STEPPED` or :data:`NOT_FINITE`): ``held`` as the controller judged it (the pose it holds
    is kept), ``settled`` whether the settle test ended the loop (the step then counts as held), ``committed``
    whether its errors are those it left."""
    accepted = held = converged = lagging = committed = done = False
    cost = step_norm = 0.0
    steps = 0
    n = q.shape[0]
    if learning:
        curvature.begin(cur, s.posture.normal, carry, state[CONVERGED] > 0.0, s.task_model, q, R, p)
    for steps in range(1, iterations + 1):
        for d in range(n):
            before[d] = q[d]
        if rest:
            lam[0], rest = s.base, False
        end = step_inputs.control_step_in(s, W, q, R, p, lam, lam[0])
        if end[0] != priority.OK:
            curvature.end(cur, s.posture.normal)
            return NOT_FINITE, steps, False, False, False, 0.0, False, 0.0, False, False
        committed = end[1] > 0.0
        converged, cost, lagging = end[3] > 0.0, end[4], end[5] > 0.0
        accepted, held, step_norm = step_inputs.judged_in(s, end, True)  # a posture is on
        if learning:
            curvature.learn(cur, s.task_model, s.tasks.packed_row, s.posture.reference, q, R, p, s.posture.normal,
                            converged)
        if held:
            break
        for d in range(n):
            move[d] = q[d] - before[d]
        if settled(state, gain, s.cache.dq0, move, last_move, converged):
            done = True
            break
    curvature.end(cur, s.posture.normal)
    return STEPPED, steps, accepted, held, converged, cost, lagging, step_norm, committed, done
