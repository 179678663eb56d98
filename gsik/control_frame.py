"""A drag's prioritised :meth:`gsik.Solver.step` in one compiled call, for :class:`~gsik.solver.Solver` (a mixin).

The general path of a controlled frame (``Solver._control_step``) retargets the controller from the packed rows, calls
:meth:`gsik.control.Controller.step` up to ``tracking_steps`` times, and builds the result from the controller's
report: ~30 µs of Python around ~55 µs of compiled step on bench_drag's pins. :meth:`ControlFrame._frame_step` runs
the same frame as one :func:`gsik.kernels.frame_step.frame_step` call over a :class:`Frame` (made once per
controller, report layout and solver buffers) and keeps only the controller's held-pose bookkeeping in Python; the
result is bit for bit the general path's. A frame the kernel cannot take (balance, a target off the effectors, the
Python reference ``Controller.compiled_step = False``, a held pose whose targets did not move, targets weighted
otherwise than the controller's tasks) returns ``None``, and the general path runs it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik import kernels
from gsik.control_inputs import held_pose
from gsik.kernels import frame_step as fk
from gsik.kernels import step_inputs
from gsik.result import SolveResult, Status
from gsik.result_arrays import ResultArrays

_new_tuple = tuple.__new__  # a NamedTuple with every field given, without its __new__'s Python call
_GATHER, _REST, _LAST_HELD, _HELD, _DECLINED = fk.GATHER, fk.REST, fk.LAST_HELD, fk.HELD, fk.DECLINED  # read as globals
_CONVERGED, _STALLED, _BUDGET_EXHAUSTED = Status.CONVERGED, Status.STALLED, Status.BUDGET_EXHAUSTED


class Frame(NamedTuple):
    """One controller's compiled frame over one solver's buffers, and what it was made for.

    Attributes:
        controller: The :class:`gsik.control.Controller` it steps.
        layout: The controller's report layout it reports (``Controller._layout``: new when its row weights change).
        rows: The controller's task rows in the packed targets (``Controller._rows``).
        restoring: The controller's restoring steps its :class:`~gsik.kernels.step_inputs.StepInputs` hold.
        buffers: The solver's kernel buffers (new after ``set_root``).
        settings: The solver's settings (``tracking_steps``).
        entry: :func:`gsik.kernels.frame_step.frame_step`'s compiled entry.
        inputs: Its :class:`~gsik.kernels.frame_step.FrameInputs`.
        arrays: The :class:`~gsik.result_arrays.ResultArrays` of its values (angles, position and orientation
            errors).
        names: The result's names: every effector, then the other targeted frames.
    """

    controller: object
    layout: tuple
    rows: np.ndarray
    restoring: int
    buffers: object
    settings: object
    entry: object
    inputs: object
    arrays: ResultArrays
    names: tuple[str, ...]


class ControlFrame:
    """:meth:`_frame_step` for :class:`~gsik.solver.Solver`, which owns the state it works on."""

    #: False: every controlled frame through the general path (``Solver._control_step``, what the frame is tested
    #: against; tests that watch ``Controller.step`` turn it off).
    compiled_frame = True
    _frame: Frame | None = None

    def _frame_step(self) -> SolveResult | None:
        """A controlled :meth:`step`'s frame through the compiled call, or ``None`` (nothing changed) when the
        general path must run it."""
        c, flags = self._controller, 0
        if not self.compiled_frame:
            return None
        if c is None:  # new targets: the controller _make_controller(rows=True) would gather them into
            c = self._fitting_controller()
            if c is None:
                return None
            flags = _GATHER
        if not c.compiled_step:
            return None
        f = self._frame
        if f is None or f[0] is not c or f[1] is not c._layout or f[2] is not c._rows or f[3] != c._restoring \
                or f[4] is not self._buffers or f[5] is not self._settings:
            f = self._frame = self._make_frame(c)
            if f is None:
                return None
        _, _, _, _, _, _, entry, inputs, arrays, names = f
        if c._rest_damping:
            flags |= _REST
        if c._last_held:
            flags |= _LAST_HELD
        if c._held is not None:
            flags |= _HELD
        code, steps, _, held, converged, cost, lagging, step_norm, finite, left = entry(inputs, flags)
        if code:  # DECLINED (nothing changed) or NOT_FINITE
            return None if code == _DECLINED else self._frame_refused(c, steps)
        # What the general path's _make_controller, Controller._moved, Controller.step and _stats leave.
        self._controller = c
        c._first, c._rest_damping, c._errors_left, c._last_held = None, False, left, held
        c._held = held_pose(self._q, self._W, self._ws.lam[0], converged, cost, lagging) if held else None
        if not finite:
            return self._control_refused()
        status = _CONVERGED if converged else _STALLED if held else _BUDGET_EXHAUSTED
        out = arrays.take()
        return _new_tuple(SolveResult, (out[2], status, steps, 0, cost, names, out[3], out[4], step_norm, 1))

    def _fitting_controller(self):
        """The last :class:`gsik.control.Controller` if it was made for the current root, packed layout (names,
        weights, priorities), posture and settings, without balance (whose support is made every time): only its
        targets' values may have changed. Else ``None``. Also ``Solver._make_controller``'s test."""
        last, made_for = self._last_controller, self._controller_for
        if last is None or self._balance or made_for[1] is not self._layout or made_for[0] is not self._skeleton.root \
                or made_for[2] is not self._posture or made_for[3] is not self._settings:
            return None
        return last

    def _frame_refused(self, c, steps: int) -> SolveResult:
        """The frame's step ``steps`` of controller ``c`` went non-finite: what the general path leaves, and its
        refusal."""
        self._controller = c
        c._first, c._rest_damping, c._errors_left, c._held = None, False, False, None
        if steps > 1:  # the steps before it held nothing
            c._last_held = False
        return self._control_refused()

    def _make_frame(self, c) -> Frame | None:
        """The :class:`Frame` of controller ``c`` over this solver's buffers, or ``None`` if the compiled frame
        cannot run it."""
        if not step_inputs.AVAILABLE or c._balance is not None or not c._settings.adaptive_damping or c._rows is None:
            return None
        effectors = self._topo.effector_names
        if c._layout is None or c._layout[0] != effectors:
            c._layout = c._report_layout(effectors)  # as Controller.report makes it
        layout = c._layout
        _, names, index, used = layout
        q, W, R, p, lam = self._q, self._W, self._ws.R, self._ws.p, self._ws.lam
        _, step = c._step_calls.get(c._restoring) or c._make_step_call(W, q, R, p, lam, float(lam[0]))
        n, k = len(q), len(names)
        values = np.empty(n + 2 * k)
        packed = self._packed
        inputs = fk.make_frame_inputs(step, packed.position, packed.rotation, packed.row_weight, c._rows, c._tp,
                                      c._tR, c._row_w, index, used, c._e, c._err, c._M, q, W, R, p, lam,
                                      self._q_before, np.empty(n), values, values[n:].reshape(2, k),
                                      int(self._settings.tracking_steps), c._posture is not None)
        arrays = ResultArrays(values, (slice(0, n), slice(n, n + k), slice(n + k, n + 2 * k)))
        return Frame(c, layout, c._rows, c._restoring, self._buffers, self._settings,
                     kernels.compiled_entry(fk.frame_step, inputs, 0), inputs, arrays, names)

    def _control_refused(self) -> SolveResult:
        """A prioritised step gone non-finite, undone as the plain one is: the angles it started from
        (``_q_before``) and their frames back, and a :attr:`Status.REFUSED` result."""
        self._q[:] = self._q_before
        self._refresh_frames()
        return self._control_result(Status.REFUSED, 1, math.inf, 0.0, 1)
