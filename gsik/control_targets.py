"""How a :class:`gsik.control.Controller` takes new target values and reports its tasks' errors.

A mixin of :class:`~gsik.control.Controller`, which owns the state it works on. Targets come in as
:class:`~gsik.control_inputs.FrameTask` (:meth:`~ControlTargets.retarget`), as ``{name: gsik.Target}``
(:meth:`~ControlTargets.retarget_targets`) or, on a drag's every frame, gathered from the solver's packed rows in one
compiled call (:meth:`~ControlTargets.retarget_rows`, :func:`gsik.kernels.gather.gather_targets`). A result's errors
are those the last step left when it committed the pose they are for, else evaluated
(:func:`gsik.kernels.kinematics.effector_errors`), then gathered (:func:`gsik.kernels.gather.gather_result`, by
:func:`gsik.kernels.control.report_errors`' rule).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gsik.control_inputs import _ordered, row_weights
from gsik.kernels import accept as ak
from gsik.kernels import gather
from gsik.kernels import kinematics as kernels
from gsik.kernels import target_state as ts


class ControlReport(NamedTuple):
    """What :meth:`ControlTargets.report` reports.

    Attributes:
        names: Every effector, then the other targeted frames (k names).
        values: One new array (n + 2k,): the angles (n,) [rad], then the k names' position [m] and orientation
            [rad] errors.
        finite: Every angle is finite (and the sum of their squares too): False after a step gone non-finite.
    """

    names: tuple[str, ...]
    values: np.ndarray
    finite: bool


_new_tuple = tuple.__new__  # a NamedTuple with every field given, without its __new__'s Python call


class ControlTargets:
    """Retargeting and error reports, for :class:`gsik.control.Controller`."""

    #: ``(the ControlTasks it was made for, (2, m) True where a task does not use its position / orientation row)``
    _unused: tuple = (None, None)

    def retarget(self, tasks) -> None:
        """New target values for the same structure (``structure(...) == self.key``): no rebuild while dragging."""
        ordered = _ordered(tasks)
        self._target_weights = None
        self._retarget(np.array([t.position for t in ordered]).reshape(-1, 3),
                       np.array([t.rotation for t in ordered]).reshape(-1, 3, 3),
                       np.array([t.row_weight for t in ordered]).reshape(-1, 6))

    def retarget_targets(self, targets, orientation_weight: float) -> None:
        """:meth:`retarget` from ``{name: gsik.Target}`` (the same names and priorities as the tasks built for)."""
        ts = [targets[n] for n in self.names]
        weights = [(t.weight, t.uses_orientation) for t in ts]
        if weights == self._target_weights and orientation_weight == self._orientation_weight:
            row_w = self._row_w  # the same row weights: no array to build (a drag moves targets, not weights)
        else:
            row_w = np.array([row_weights(t, orientation_weight) for t in ts], dtype=float).reshape(-1, 6)
        self._retarget(  # a Target's position and rotation are float64: their bytes joined, the (m, 3), (m, 3, 3)
            np.frombuffer(b"".join([t.position.tobytes() for t in ts])).reshape(-1, 3),
            np.frombuffer(b"".join([t.rotation.tobytes() for t in ts])).reshape(-1, 3, 3), row_w)
        self._target_weights, self._orientation_weight = weights, orientation_weight

    def use_rows(self, row_of: dict) -> None:
        """Where :meth:`retarget_rows` finds each task's target: its row in a solver's packed targets
        (``row_of``: ``{effector name: row}``); nowhere (``retarget_rows`` declines) when a task is not an effector."""
        rows = [row_of.get(n, -1) for n in self.names]
        self._rows = None if -1 in rows else np.array(rows, dtype=np.int64)

    def retarget_rows(self, packed) -> bool:
        """:meth:`retarget_targets` from a solver's packed targets (:class:`gsik.kernels.TargetArrays`, the rows
        :meth:`use_rows` named, holding the targets' values), in one compiled call. Returns False, with nothing
        changed, if a task is not an effector, or its row is out of the packed range or weighted otherwise than
        the controller's task (the caller then retargets from the targets themselves)."""
        if self._rows is None:
            return False
        code = self._call(gather.gather_targets, packed.position, packed.rotation, packed.row_weight, self._rows,
                          self._tp, self._tR, self._row_w, self._cache.flags, self._window.ring)
        if code == gather.DECLINED:
            return False
        if code == gather.MOVED:  # the kernel dropped the cached levels and the stall window; the rest here
            self._moved()
        return True

    def _retarget(self, tp: np.ndarray, tR: np.ndarray, row_w: np.ndarray) -> None:
        """Target positions (m, 3) [m], orientations (m, 3, 3) and row weights (m, 6), in task order."""
        same_w = _same(row_w, self._row_w)
        if same_w and _same(tp, self._tp) and _same(tR, self._tR):
            return  # the same targets again (a held drag): what the last steps learnt still holds
        self._tp[:], self._tR[:] = tp, tR  # in place: the kernels' inputs hold them
        if not same_w:
            self._row_w = row_w
            self._thresholds()
        self._cache.flags[ak.F_VALID] = 0.0
        self._window.ring[:] = 0
        self._moved()

    def _moved(self) -> None:
        """What new target values end besides the cached levels and the stall window: a held pose, the last
        step's errors, and the damping it learnt (a held pose's was learnt on the old targets: start afresh)."""
        self._held, self._errors_left = None, False
        self._rest_damping = self._last_held

    def errors(self, R: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Position [m] and orientation [rad] error (m,) of each task (0 where a row is unused)."""
        err = self._used_errors(R, p)
        return err[0], err[1]

    def _used_errors(self, R: np.ndarray, p: np.ndarray) -> np.ndarray:
        """(2, m) :meth:`errors`, a new array."""
        self._task_errors(R, p)
        made_for, unused = self._unused
        if made_for is not self._tasks_in:  # (2, m) the rows no target uses, for these row weights
            unused = np.stack([self._row_w[:, 0] <= 0.0, self._row_w[:, 3] <= 0.0])
            self._unused = (self._tasks_in, unused)
        return np.where(unused, 0.0, self._err)  # one call: cheaper than two masked assignments

    def report(self, effector_names: tuple[str, ...], q, R, p, left: bool = False) -> ControlReport:
        """The :class:`ControlReport` of every effector (0 without a target), then the other targeted frames, at
        the angles ``q`` (n,) [rad] and frames ``R``, ``p``. ``left``: this is the pose the last step left (the
        caller knows nothing moved it since), so the errors that step evaluated there are reported as they are."""
        if self._layout is None or self._layout[0] != effector_names:
            self._layout = self._report_layout(effector_names)
        _, names, _, used = self._layout
        n = len(q)
        values = np.empty(n + 2 * len(names))
        if left and self._errors_left:
            err = self._work.err
        else:  # evaluated here, then gathered by the same rule (report_errors'): no NumPy call on the angles
            self._task_errors(R, p)
            err = self._err
        squares = self._call(gather.gather_result, q, err, used, values)
        return _new_tuple(ControlReport, (names, values, math.isfinite(squares)))

    def _report_layout(self, effector_names: tuple[str, ...]) -> tuple:
        """``(effector_names, result names, task of each (k,) or -1, task of each error (2, k) or -1 where the
        task does not use that row)``: what :meth:`report` reports, for these row weights."""
        names = effector_names + tuple(n for n in self.names if n not in effector_names)
        where = {n: k for k, n in enumerate(self.names)}
        index = np.array([where.get(n, -1) for n in names], dtype=np.int64)
        w = self._row_w  # report_errors' rule: a task's error where it uses the row, else 0
        used = [[k if k >= 0 and w[k, r] > 0.0 else -1 for k in index.tolist()] for r in (0, 3)]
        return effector_names, names, index, np.array(used, dtype=np.int64).reshape(2, len(names))

    def _task_errors(self, R, p) -> None:
        self._call(kernels.effector_errors, R, p, self._tasks_in.frame, self._tp, self._tR, self._tasks_in.row_weight,
                   self._e, self._err, self._M)

    def target_cost(self, R, p) -> float:
        """Weighted squared error ``0.5 e^T W e`` of every target at frames ``R``, ``p``: one compiled call
        (:func:`gsik.kernels.target_state.target_cost`), NumPy's ``0.5 * float((e * e * row_w).sum())`` bit for bit."""
        tasks = self._tasks_in
        if self._e.shape[0] <= ts.MAX_TERMS:
            return self._call(ts.target_cost, R, p, tasks.frame, self._tp, self._tR, tasks.row_weight, self._e,
                              self._err, self._M)
        self._task_errors(R, p)  # more tasks than the compiled sum takes (40): NumPy's own
        e = self._e.reshape(-1, 6)
        squares = e * e  # as ``e ** 2``, then in place: the same values and sum, bit for bit, without two arrays
        squares *= self._row_w
        return 0.5 * float(squares.sum())

    def target_state(self, R, p, stage_angle: float) -> tuple[bool, bool]:
        """``(every orientation error within stage_angle [rad], every target within the position and orientation
        tolerances)`` at frames ``R``, ``p`` (a row a task does not use counts 0, a NaN error is within nothing): one
        compiled call (:func:`gsik.kernels.target_state.target_state`)."""
        tasks, s = self._tasks_in, self._settings
        return self._call(ts.target_state, R, p, tasks.frame, self._tp, self._tR, tasks.row_weight, self._e, self._err,
                          self._M, float(stage_angle), float(s.position_tolerance), float(s.orientation_tolerance))

    def converged(self, R, p) -> bool:
        """True if every target is within the position and orientation tolerances."""
        return self.target_state(R, p, math.inf)[1]


def _same(a: np.ndarray, b: np.ndarray | None) -> bool:
    """True if ``b`` holds the very values of ``a`` (bit for bit: a cheaper test than ``np.array_equal``)."""
    return a is b or (b is not None and a.shape == b.shape and a.tobytes() == b.tobytes())
