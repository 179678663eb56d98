"""A drag's prioritised frame in one compiled call: gather the moved targets, step, report.

A :meth:`gsik.Solver.step` with priorities, a posture or balance made ~6 Python calls around its compiled step: the
targets gathered from the packed rows (:func:`gsik.kernels.gather.gather_targets`), up to ``tracking_steps``
steps (:func:`gsik.kernels.step_inputs.control_step`) each judged in Python (held, creeping, lagging), the steps'
norm, and the result's angles and errors (:func:`gsik.kernels.gather.gather_result` or
:func:`gsik.kernels.control.report_errors`). :func:`frame_step` runs the same, bit for bit, over a
:class:`FrameInputs` (the controller's :class:`~gsik.kernels.step_inputs.StepInputs` and the solver's persistent
arrays: one object to unbox), and writes the result's angles and errors into ``values``. The Python around it
(:mod:`gsik.control_frame`) keeps the controller's held pose and damping bookkeeping.
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels import control as ck
from gsik.kernels import gather, priority
from gsik.kernels import step_inputs
from gsik.kernels.accept import norm, share_bounded

#: :func:`frame_step`'s ``flags``: gather the targets from the packed rows first (the controller was not retargeted
#: since the targets were set); the controller restarts from the base damping (``Controller._rest_damping``); its
#: last step held the pose (``Controller._last_held``: new targets then restart from the base damping); it holds a
#: held pose (``Controller._held``: a frame whose targets did not move is left to the Python path).
GATHER, REST, LAST_HELD, HELD = 1, 2, 4, 8
#: :func:`frame_step`'s first result: stepped (the rest of the tuple holds), declined (nothing changed: the Python
#: path runs the frame), or a level's Jacobian went non-finite (the angles are to be restored).
STEPPED, DECLINED, NOT_FINITE = 0, 1, 2

#: What a :class:`FrameInputs` holds.
FIELDS = ("step", "position", "rotation", "row_weight", "rows", "tp", "tR", "row_w", "index", "used", "e", "err", "M",
          "q", "W", "R", "p", "lam", "q_before", "diff", "values", "reported", "tracking_steps", "posture_on")

#: False without numba or with ``NUMBA_DISABLE_JIT``: every frame takes the Python path.
AVAILABLE = step_inputs.AVAILABLE

if AVAILABLE:
    from numba.core import types
    from numba.experimental import structref

    from gsik.kernels.borrow import borrow

    @structref.register
    class FrameInputsType(types.StructRef):
        """The numba type of a :class:`FrameInputs`: its fields' types as given (no literals)."""

        def preprocess_fields(self, fields):
            return tuple((name, types.unliteral(typ)) for name, typ in fields)

    class FrameInputs(structref.StructRefProxy):
        """A controller's :class:`~gsik.kernels.step_inputs.StepInputs` and the arrays a frame reads and writes
        (:data:`FIELDS`)."""

    structref.define_proxy(FrameInputs, FrameInputsType, list(FIELDS))

    @njit(cache=True)
    def make_frame_inputs(step, position, rotation, row_weight, rows, tp, tR, row_w, index, used, e, err, M, q, W, R,
                          p, lam, q_before, diff, values, reported, tracking_steps, posture_on):
        """A :class:`FrameInputs` of these (made by compiled code, which is cached)."""
        return FrameInputs(step, position, rotation, row_weight, rows, tp, tR, row_w, index, used, e, err, M, q, W, R,
                           p, lam, q_before, diff, values, reported, tracking_steps, posture_on)

    @njit(cache=True)
    def frame_step(f, flags):
        """One prioritised frame over ``f`` (:class:`FrameInputs`), ``flags`` (:data:`GATHER` ...): the targets
        gathered (with :data:`GATHER`), ``f.q`` saved to ``f.q_before``, then up to ``f.tracking_steps`` steps
        (another while the last was committed, did not hold and left a target lagging), and the result's values
        (n + 2k,) into ``f.values``: the angles, then the errors :meth:`gsik.control.Controller.report` reports
        (``f.reported``: a (2, k) view of them).

        Returns ``(code, steps, accepted, held, converged, cost, lagging, step_norm, finite, errors_left)`` of the
        last step (``code`` :data:`STEPPED`, :data:`DECLINED` or :data:`NOT_FINITE`); ``step_norm`` [rad] is the
        whole change of the angles, ``finite`` whether their squares' sum is, ``errors_left`` whether the reported
        errors are those the last step left (committed)."""
        return _frame(f, flags)

    @njit(cache=True, _nrt=False)
    def _frame(f, flags):
        """:func:`frame_step`'s frame, the fields of ``f`` and its step inputs read without reference counting
        (:func:`gsik.kernels.borrow.borrow`)."""
        s = borrow(f, "step")
        cache, window = borrow(s, "cache"), borrow(s, "window")
        rest = (flags & REST) != 0
        if flags & GATHER:
            code = gather.gather_targets(borrow(f, "position"), borrow(f, "rotation"), borrow(f, "row_weight"),
                                         borrow(f, "rows"), borrow(f, "tp"), borrow(f, "tR"), borrow(f, "row_w"),
                                         cache.flags, window.ring)
            if code == gather.DECLINED or (code == gather.SAME and (flags & HELD) != 0):
                return DECLINED, 0, False, False, False, 0.0, False, 0.0, False, False
            if code == gather.MOVED:
                rest = (flags & LAST_HELD) != 0
        elif flags & HELD:
            return DECLINED, 0, False, False, False, 0.0, False, 0.0, False, False
        q, W, R, p, lam = borrow(f, "q"), borrow(f, "W"), borrow(f, "R"), borrow(f, "p"), borrow(f, "lam")
        q_before, posture_on = borrow(f, "q_before"), borrow(f, "posture_on")
        for d in range(q.shape[0]):
            q_before[d] = q[d]
        if rest:
            lam[0] = borrow(s, "base")
        steps = 0
        accepted = held = converged = lagging = committed = False
        cost = step_norm = 0.0
        for steps in range(1, borrow(f, "tracking_steps") + 1):
            end = step_inputs.control_step_in(s, W, q, R, p, lam, lam[0])
            if end[0] != priority.OK:
                return NOT_FINITE, steps, False, False, False, 0.0, False, 0.0, False, False
            committed = end[1] > 0.0
            converged, cost, lagging = end[3] > 0.0, end[4], end[5] > 0.0
            accepted, held, step_norm = step_inputs.judged_in(s, end, posture_on)
            if not lagging or held or not accepted:
                break
        # Not converged while the posture's share of a step is bounded: it has further to go (Solver._control_step)
        wk = borrow(s, "wk")
        converged = converged and not share_bounded(borrow(s, "posture"), wk)
        if steps > 1:
            diff = borrow(f, "diff")
            for d in range(q.shape[0]):
                diff[d] = q[d] - q_before[d]
            step_norm = norm(diff)
        n, values = q.shape[0], borrow(f, "values")
        if committed:
            squares = gather.gather_result(q, wk.err, borrow(f, "used"), values)
        else:
            squares = 0.0
            for d in range(n):
                values[d] = q[d]
                squares += q[d] * q[d]
            ck.report_errors(R, p, borrow(s, "tasks"), borrow(f, "index"), borrow(f, "e"), borrow(f, "err"),
                             borrow(f, "M"), borrow(f, "reported"))
        return STEPPED, steps, accepted, held, converged, cost, lagging, step_norm, math.isfinite(squares), committed
