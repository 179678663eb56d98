"""A controlled step()'s frame in one compiled call (gsik/control_frame.py, gsik/kernels/frame_step.py): the frame the
general path (``Solver._control_step`` over ``Controller.step``) makes, bit for bit, with the controller left in the
same state; a frame gone non-finite refused; what the compiled frame cannot take left to the general path."""

import numpy as np
import pytest
from solver_helpers import studio_drag_solver, studio_drag_targets

import gsik
from gsik.control_frame import ControlFrame
from gsik.kernels import step_inputs

pytestmark = pytest.mark.skipif(not step_inputs.AVAILABLE, reason="the compiled frame needs numba's compiled code")


def _controller_state(solver) -> tuple:
    """What the controller keeps between frames: its held pose, whether its last step held, whether its errors are
    those its last step left, whether it restarts from the base damping; and the solver's damping."""
    c = solver._controller
    held = None if c._held is None else (c._held[0].tobytes(), c._held[1].tobytes(), c._held[2], c._held[3])
    return held, c._last_held, c._errors_left, c._rest_damping, solver._ws.lam.tobytes()


def _drag(monkeypatch, frame: bool, studio: bool) -> tuple[list, int]:
    """A drag that moves, re-sets, reweights and holds its targets, moves the pose from outside, solves once and
    ends with balance on:
    ``(each frame's result and controller state, frames the compiled frame made)``."""
    made = [0]
    frame_step = ControlFrame._frame_step

    def counted(self):
        result = frame_step(self)
        made[0] += result is not None
        return result

    monkeypatch.setattr(gsik.Solver, "compiled_frame", frame)
    monkeypatch.setattr(gsik.Solver, "_frame_step", counted)
    solver, poses = studio_drag_solver(studio)
    out = []
    for frame_index in range(90):
        targets = studio_drag_targets(poses, frame_index, 0.5 if frame_index % 9 == 4 else 1.0)
        if 50 <= frame_index < 75:  # the same targets: the pose comes to hold
            pass
        elif frame_index % 5 == 3:
            solver.move_target("left_hand", targets["left_hand"].position + 0.01)
        elif frame_index % 7 == 6:
            solver.set_q(np.clip(solver.q + 1e-3, solver.skeleton.lower, solver.skeleton.upper))
        elif frame_index == 40:
            solver.solve(targets)
        elif frame_index == 80:  # balance from here: its steps are Python's
            solver.set_balance(True)
            solver.set_targets(targets)
        else:
            solver.set_targets(targets)
        r = solver.step()
        out.append((r.q.tobytes(), r.position_errors.tobytes(), r.orientation_errors.tobytes(), r.status,
                    r.iterations, r.sweeps, r.residual, r.effector_names, r.step_norm, r.attempts,
                    _controller_state(solver)))
    return out, made[0]


@pytest.mark.parametrize("studio", [False, True], ids=["pins", "studio"])
def test_a_drag_through_the_compiled_frame_is_the_general_path_bit_for_bit(studio, monkeypatch):
    compiled, made = _drag(monkeypatch, True, studio)
    general, none = _drag(monkeypatch, False, studio)
    assert none == 0 and made >= 45  # the frame ran most frames: not a reweighted one, nor one held still
    assert any(state[-1][0] is not None for state in compiled)  # a held pose was kept, and left when targets moved
    for a, b in zip(compiled, general, strict=True):
        assert a == b


@pytest.mark.parametrize("frame", [True, False], ids=["compiled frame", "general path"])
def test_a_frame_whose_step_goes_non_finite_is_refused_and_undone(frame, monkeypatch):
    monkeypatch.setattr(gsik.Solver, "compiled_frame", frame)
    solver, poses = studio_drag_solver(False)
    for frame_index in range(3):
        solver.step(studio_drag_targets(poses, frame_index))
    before, frames = solver.q, solver.world_positions()
    solver.set_targets(studio_drag_targets(poses, 3))
    solver._ws.R[:] = np.nan  # the step's Jacobian goes non-finite
    r = solver.step()
    assert r.status is gsik.Status.REFUSED and r.q.tobytes() == before.tobytes() == solver.q.tobytes()
    assert np.array_equal(solver.world_positions(), frames)  # the frames of the pose kept, evaluated again
    assert (solver._frame is not None) == frame
    assert solver.step(studio_drag_targets(poses, 4)).status is not gsik.Status.REFUSED


def test_what_the_compiled_frame_cannot_take_goes_the_general_path(monkeypatch):
    solver, poses = studio_drag_solver(False)
    targets = studio_drag_targets(poses, 0)
    solver.step(targets)
    elbow = solver.world_positions()[solver.skeleton.frame_of("left_elbow")]
    solver.step({**targets, "left_elbow": gsik.Target(elbow, position_only=True, priority=1)})
    assert solver._frame_step() is None and solver._frame is None  # a task without a packed row
    solver.step(targets)
    solver.step(targets)
    assert solver._frame is not None
    monkeypatch.setattr(gsik.control.Controller, "compiled_step", False)
    solver.set_targets(studio_drag_targets(poses, 1))
    assert solver._frame_step() is None  # the Python reference
    monkeypatch.undo()
    solver = gsik.Solver(gsik.load_skeleton("biped"))  # standing on its right foot
    solver.set_balance(True)
    hand = solver.effector_poses()["left_hand"][:3, 3] + [0.0, 0.3, 0.0]
    for _ in range(3):
        solver.step({"left_hand": gsik.Target(hand, priority=1)})
    assert solver._controller._balance is not None
    assert solver._frame_step() is None  # balance's support is evaluated in Python
