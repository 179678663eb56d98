"""A solve() attempt's prioritised steps with a posture, until it settles, in one compiled call: for
:class:`gsik.control.Controller` (a mixin).

``Attempts._control_steps`` made two Python calls a step around the compiled step
(:meth:`~gsik.control.Controller.step`, then :meth:`gsik.stall.PostureSettle.settled`); a drag's warm solve() makes
two to ten steps a frame. :meth:`ControlSettle.steps_until_settled` runs them as one
:func:`gsik.kernels.settle_steps.settle_steps` call and leaves the controller as those steps would have: the results
are bit for bit the Python loop's (``tests/test_control_settle.py``).
"""

from __future__ import annotations

import numpy as np

from gsik.control_inputs import ControlStats, held_pose
from gsik.kernels import compiled_entry
from gsik.kernels import control as ck
from gsik.kernels import curvature as cv
from gsik.kernels import settle_steps as sk
from gsik.kernels.posture_level import is_full

_new_tuple = tuple.__new__  # a NamedTuple with every field given, without its __new__'s Python call
_NO_CURVATURE = cv.make_curvature(np.zeros((0, 0)), 0)  # what the compiled loop gets when it learns nothing


class ControlSettle:
    """:meth:`steps_until_settled` for :class:`~gsik.control.Controller`, which owns the state it works on."""

    #: False: every attempt's steps through the Python loop (``Attempts._control_steps``, what this is tested
    #: against).
    compiled_settle = True
    #: False: a solve()'s settle steps solve the posture's level with the posture's own normal matrix (Gauss-Newton),
    #: not with the targets' curvature learnt (:mod:`gsik.kernels.curvature`; what benchmarks compare it against).
    learns_curvature = True
    _curvature: cv.Curvature | None = None  # made at the first settle that learns
    _curvature_tested = False  # whether the posture was tested for it (_learning)

    def steps_until_settled(self, q: np.ndarray, W: np.ndarray, R: np.ndarray, p: np.ndarray, lam: np.ndarray,
                            iterations: int, posture, carry: bool = False) -> tuple[ControlStats, int] | None:
        """``(the last step's ControlStats, steps made)``: up to ``iterations`` prioritised steps from ``q`` (n,)
        [rad] at ``W`` (4, 4) (frames ``R``, ``p``; ``lam`` (1,) the adaptive damping), in place, until one holds
        the pose or the posture settles (``posture``: a :class:`gsik.stall.PostureSettle`, whose gain and state
        are adapted; a settling step counts as held), the targets' curvature learnt on the way (``carry``: see
        :meth:`curvature_begin`). ``None``, with nothing changed, where the compiled loop does
        not run them: balance, fixed damping, the Python reference (``compiled_step`` False), no numba, a held
        pose, no step to make.

        Raises:
            numpy.linalg.LinAlgError: A priority level's Jacobian went non-finite (as :meth:`step` raises).
        """
        if not (sk.AVAILABLE and self.compiled_settle and self.compiled_step and self._settings.adaptive_damping) \
                or self._balance is not None or self._held is not None or iterations < 1:
            return None
        call = self._settle_call(q, W, R, p, lam, iterations, posture)
        cur = self._learning()
        code, steps, accepted, held, converged, cost, lagging, step_norm, committed, settled = call(
            W, q, R, p, lam, iterations, bool(self._rest_damping), posture.state, posture.gain,
            posture.move_buffer(q.shape[0]), _NO_CURVATURE if cur is None else cur, cur is not None, carry)
        self._first, self._rest_damping = None, False
        if code != sk.STEPPED:
            self._errors_left = False
            if steps > 1:  # the steps before it held nothing
                self._held, self._last_held = None, False
            raise np.linalg.LinAlgError("a priority level's Jacobian holds a non-finite number")
        self._errors_left = committed
        stats = _new_tuple(ControlStats, (accepted, held, converged, cost, step_norm, lagging))
        self._held = held_pose(q, W, lam[0], converged, cost, lagging) if held else None
        self._last_held = held
        if settled:  # the settle test ended the loop: the step counts as held (a new tuple: cheaper than _replace)
            stats = _new_tuple(ControlStats, (accepted, True, converged, cost, step_norm, lagging))
        return stats, steps

    def share_bounded(self) -> bool:
        """True if the last step's posture share was scaled onto its bound (:func:`gsik.kernels.accept.share_bounded`):
        the posture has further to go than one step takes, so a pose with every target met has not settled yet."""
        return self._work.out[ck.O_SHARE] > self._posture_rows.share[0]

    def _settle_call(self, q, W, R, p, lam, iterations: int, posture):
        """``call(W, q, R, p, lam, iterations, rest, state, gain, last_move)``: :func:`settle_steps`'s compiled
        entry over this controller's :class:`~gsik.kernels.step_inputs.StepInputs` for its restoring steps, made
        once (with its work arrays)."""
        call = self._settle_calls.get(self._restoring)
        if call is None:
            _, inputs = self._step_calls.get(self._restoring) or self._make_step_call(W, q, R, p, lam, float(lam[0]))
            move, before = np.empty_like(q), np.empty_like(q)
            entry = compiled_entry(sk.settle_steps, inputs, W, q, R, p, lam, int(iterations), False, posture.state,
                                   posture.gain, np.empty_like(q), move, before, _NO_CURVATURE, False, False)

            def call(W, q, R, p, lam, iterations, rest, state, gain, last_move, cur, learning, carry):
                return entry(inputs, W, q, R, p, lam, iterations, rest, state, gain, last_move, move, before, cur,
                             learning, carry)

            self._settle_calls[self._restoring] = call
        return call

    def curvature_begin(self, q: np.ndarray, R: np.ndarray, p: np.ndarray, carry: bool, met: bool) -> None:
        """A settle's start at ``q`` (n,) [rad] (world frames ``R``, ``p``; ``met``: every target within its
        tolerances there) for the Python loop: the targets' curvature learnt (:mod:`gsik.kernels.curvature`) swapped
        into the posture's level, from what the last settle learnt (``carry``: a drag's warm solve) or from the
        posture's own normal matrix (:func:`~gsik.kernels.curvature.begin`, where the compiled loop calls it).
        Nothing where none is learnt (:meth:`_learning`)."""
        cur = self._learning()
        if cur is not None:
            self._call(cv.begin, cur, self._posture_rows.normal, carry, met, self._task_model, q, R, p)

    def curvature_learn(self, q: np.ndarray, R: np.ndarray, p: np.ndarray, met: bool) -> None:
        """Learn from the step that left ``q`` (n,) [rad] (world frames ``R``, ``p``; ``met``: every target within
        its tolerances there): the Python loop's :func:`gsik.kernels.curvature.learn`, where the compiled loop calls
        it."""
        cur = self._learning()
        if cur is not None:
            self._call(cv.learn, cur, self._task_model, self._tasks_in.packed_row, self._posture_rows.reference, q,
                       R, p, self._posture_rows.normal, met)

    def curvature_end(self) -> None:
        """A settle's end (the compiled loop's already made it; a step that raised left it): the posture's own
        normal matrix back in its level, for :meth:`step` and any other steps."""
        cur = self._curvature
        if cur is not None and cur.state[cv.S_ON] > 0.0:
            self._call(cv.end, cur, self._posture_rows.normal)

    def _learning(self) -> cv.Curvature | None:
        """This controller's :class:`~gsik.kernels.curvature.Curvature` (made at first), or None where it learns
        none: :attr:`learns_curvature` off, balance, or a posture that is not a full one solved by its normal
        equations (the learned prior; see :mod:`gsik.kernels.curvature` for why not a diagonal one)."""
        if not self.learns_curvature or self._balance is not None:
            return None
        if self._curvature is None and not self._curvature_tested:
            self._curvature_tested = True  # the posture's rows are fixed for a controller: tested once
            normal = self._posture_rows.normal
            if is_full(normal):
                self._curvature = cv.make_curvature(normal, self._work.J.shape[0])
        return self._curvature
