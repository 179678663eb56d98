"""A solve() attempt's prioritised steps in one compiled call (gsik/control_settle.py, gsik/kernels/settle_steps.py):
the steps the Python loop (``Attempts._control_steps`` over ``Controller.step`` and ``PostureSettle.settled``) makes,
bit for bit, with the controller and the solver's learnt posture gain left in the same state; a step gone non-finite
handled the same; what the compiled loop cannot take left to the Python loop."""

import numpy as np
import pytest
from solver_helpers import studio_drag_solver, studio_drag_targets

import gsik
from gsik.control_settle import ControlSettle
from gsik.kernels import settle_steps
from gsik.stall import PostureSettle

pytestmark = pytest.mark.skipif(not settle_steps.AVAILABLE, reason="the compiled loop needs numba's compiled code")


def _state(solver) -> tuple:
    """What a solve leaves for the next: the controller's held pose, whether its last step held, whether its errors
    are those its last step left, whether it restarts from the base damping; the posture gain and contraction the
    attempt learnt (``Attempts._posture_gain``, its controller left out: each drag makes its own); the targets'
    curvature it learnt and the posture's matrix its level holds (gsik/kernels/curvature.py)."""
    c = solver._last_controller
    held = None if c._held is None else (c._held[0].tobytes(), c._held[1].tobytes(), c._held[2], c._held[3])
    learnt = None if c._curvature is None else (c._curvature.B.tobytes(), c._curvature.state.tobytes())
    return held, c._last_held, c._errors_left, c._rest_damping, solver._posture_gain[1:], c.posture_gain.tobytes(), \
        learnt, c._posture_rows.normal.tobytes()


def _drag(monkeypatch, compiled: bool, studio: bool) -> tuple[list, int]:
    """Warm solves along a drag that moves, re-sets, reweights and holds its targets, moves the pose from outside and
    steps between solves: ``(each frame's result and state, attempts the compiled loop made)``."""
    made = [0]
    steps_until_settled = ControlSettle.steps_until_settled

    def counted(self, *args):
        out = steps_until_settled(self, *args)
        made[0] += out is not None
        return out

    monkeypatch.setattr(ControlSettle, "compiled_settle", compiled)
    monkeypatch.setattr(ControlSettle, "steps_until_settled", counted)
    solver, poses = studio_drag_solver(studio)
    out = []
    for frame_index in range(60):
        targets = studio_drag_targets(poses, frame_index, 0.5 if frame_index % 9 == 4 else 1.0)
        if frame_index % 7 == 6:
            solver.set_q(np.clip(solver.q + 1e-3, solver.skeleton.lower, solver.skeleton.upper))
        if frame_index % 11 == 10:
            solver.step(targets)
        r = solver.solve(targets if not 30 <= frame_index < 36 else studio_drag_targets(poses, 30))
        out.append((r.q.tobytes(), r.position_errors.tobytes(), r.orientation_errors.tobytes(), r.status,
                    r.iterations, r.sweeps, r.residual, r.effector_names, r.step_norm, r.attempts, _state(solver)))
    return out, made[0]


@pytest.mark.parametrize("studio", [False, True], ids=["pins", "studio"])
def test_a_drag_of_warm_solves_through_the_compiled_loop_is_the_python_loop_bit_for_bit(studio, monkeypatch):
    compiled, made = _drag(monkeypatch, True, studio)
    python, none = _drag(monkeypatch, False, studio)
    assert none == 0 and made >= 60  # at least one attempt a frame
    assert len({frame[0] for frame in compiled}) >= 40  # the pose moved
    for a, b in zip(compiled, python, strict=True):
        assert a == b


def _non_finite_step(compiled: bool) -> tuple:
    """An attempt's steps from frames gone non-finite (the Jacobian's NaN): the error raised and what the
    controller is left with."""
    solver, poses = studio_drag_solver(False)
    solver.solve(studio_drag_targets(poses, 0))
    solver.set_targets(studio_drag_targets(poses, 1))
    c = solver._make_controller()
    q, R, p, lam = solver.q, np.full_like(solver._ws.R, np.nan), solver._ws.p.copy(), np.array([0.1])
    settle = PostureSettle(1e-3, False, c.posture_gain)
    with pytest.raises(np.linalg.LinAlgError) as raised:
        if compiled:
            c.steps_until_settled(q, solver._W, R, p, lam, 5, settle)
        else:
            c.step(q, solver._W, R, p, lam)
    return str(raised.value), c._held, c._last_held, c._errors_left, c._first, c._rest_damping, lam.tobytes()


def test_a_step_gone_non_finite_raises_and_leaves_the_controller_as_its_python_step_does():
    assert _non_finite_step(True) == _non_finite_step(False)


def test_what_the_compiled_loop_cannot_take_goes_the_python_loop(monkeypatch):
    calls = []
    steps_until_settled = ControlSettle.steps_until_settled
    monkeypatch.setattr(ControlSettle, "steps_until_settled",
                        lambda self, *args: calls.append(steps_until_settled(self, *args)) or calls[-1])
    solver, poses = studio_drag_solver(False)
    solver.solve(studio_drag_targets(poses, 0))
    assert any(c is not None for c in calls)
    calls.clear()
    monkeypatch.setattr(gsik.control.Controller, "compiled_step", False)
    solver.solve(studio_drag_targets(poses, 1))
    assert calls and all(c is None for c in calls)  # the Python reference
    calls.clear()
    monkeypatch.setattr(gsik.control.Controller, "compiled_step", True)
    solver.set_balance(True)
    solver.solve(studio_drag_targets(poses, 2))
    assert solver._last_controller._balance is not None
    assert solver.solve(studio_drag_targets(poses, 3)).iterations > 0
    assert all(c is None for c in calls)  # balance's support is evaluated in Python (no posture settle with it)
