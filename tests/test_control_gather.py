"""What a controlled frame takes as it is rather than building again: a drag's moved targets gathered from the solver's
packed rows and a committed step's errors as that step found them (gsik.kernels.gather), the step's fixed inputs in
one compiled object (gsik.kernels.step_inputs). Each gives what the path it replaces gives, bit for bit, and the
gathers are not used once the pose or the targets changed."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import gsik
import gsik.control
from gsik.control_targets import ControlTargets
from gsik.kernels import accept as ak
from gsik.kernels import gather, step_inputs
from gsik.kernels.control import report_errors
from gsik.prior import bundled_prior, use_prior

from solver_helpers import studio_drag_solver, studio_drag_targets

# Values drawn so that equal, -0.0 against 0.0, NaN and tiny differences all occur.
VALUE = st.sampled_from([0.0, -0.0, 1.0, 1.0 + 2.0 ** -52, -0.5, 1e-300, float("nan"), float("inf")])


@st.composite
def _rows(draw):
    """Packed rows (e of them), a task order over some of them, and the controller's arrays before."""
    e = draw(st.integers(1, 6))
    m = draw(st.integers(1, e))
    index = np.array(draw(st.permutations(range(e)))[:m], dtype=np.int64)

    def array(*shape):
        return np.array(draw(st.lists(VALUE, min_size=math.prod(shape), max_size=math.prod(shape)))).reshape(shape)

    position, rotation, weight = array(e, 3), array(e, 3, 3), array(e, 6)
    tp, tR = array(m, 3), array(m, 3, 3)
    row_w = weight[index].copy()
    if draw(st.booleans()):  # the controller's weights differ in one bit somewhere
        k, j = draw(st.integers(0, m - 1)), draw(st.integers(0, 5))
        row_w[k, j] = -row_w[k, j] if row_w[k, j] == 0.0 else np.nextafter(row_w[k, j], np.inf)
    if draw(st.booleans()):  # the targets already held
        tp, tR = position[index].copy(), rotation[index].copy()
    return position, rotation, weight, index, tp, tR, row_w


@settings(max_examples=400, deadline=None)
@given(_rows())
def test_gathered_targets_are_the_packed_rows_in_task_order_bit_for_bit(case):
    position, rotation, weight, index, tp, tR, row_w = case
    before = tp.tobytes() + tR.tobytes()
    flags, ring = np.ones(4), np.array([3, 1], dtype=np.int64)
    code = gather.gather_targets(position, rotation, weight, index, tp, tR, row_w, flags, ring)
    if weight[index].tobytes() != row_w.tobytes():
        assert code == gather.DECLINED
        assert tp.tobytes() + tR.tobytes() == before and flags[ak.F_VALID] == 1.0 and ring.tolist() == [3, 1]
        return
    assert tp.tobytes() == position[index].tobytes() and tR.tobytes() == rotation[index].tobytes()
    moved = before != tp.tobytes() + tR.tobytes()
    assert code == (gather.MOVED if moved else gather.SAME)
    assert (flags[ak.F_VALID], ring.tolist()) == ((0.0, [0, 0]) if moved else (1.0, [3, 1]))


def test_rows_out_of_the_packed_range_are_declined_with_nothing_written():
    position, rotation, weight = np.ones((2, 3)), np.tile(np.eye(3), (2, 1, 1)), np.ones((2, 6))
    tp, tR, flags, ring = np.zeros((1, 3)), np.zeros((1, 3, 3)), np.ones(4), np.ones(2, dtype=np.int64)
    for row in (-1, 2):
        code = gather.gather_targets(position, rotation, weight, np.array([row]), tp, tR, np.ones((1, 6)), flags,
                                     ring)
        assert code == gather.DECLINED and not tp.any() and not tR.any() and flags.all() and ring.all()


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 5), st.integers(0, 4), st.data())
def test_a_gathered_result_is_the_angles_then_the_used_rows_errors(n, k, data):
    m = data.draw(st.integers(1, 4))
    q = np.arange(n, dtype=float) - 0.5
    err = np.array(data.draw(st.lists(VALUE, min_size=2 * m, max_size=2 * m))).reshape(2, m)
    index = np.array(data.draw(st.lists(st.integers(-1, m - 1), min_size=2 * k, max_size=2 * k)),
                     dtype=np.int64).reshape(2, k)
    out = np.full(n + 2 * k, 7.0)
    squares = gather.gather_result(q, err, index, out)
    assert squares == sum(float(v) * float(v) for v in q)  # summed in order, as the kernel sums them
    want = np.concatenate([q] + [[err[a, i] if i >= 0 else 0.0 for i in index[a]] for a in range(2)])
    assert out.tobytes() == np.asarray(want, dtype=float).tobytes()


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3), min_size=1, max_size=80))
def test_a_steps_norm_is_the_sum_of_its_squares_in_order(values):
    """Every controlled step's norm is one sum (:func:`gsik.kernels.step_inputs.norm`): the squares added in order,
    as Python adds them."""
    a = np.array(values)
    assert step_inputs.norm(a) == math.sqrt(sum(v * v for v in values))


def _drag(monkeypatch, fresh: bool, studio: bool = False, frames: int = 40) -> list:
    """Every frame's result of a controlled drag (feet and pelvis pinned, hands at 1 round a circle, a posture)
    with events between frames: a target moved in place, the same targets again, the pose set from outside, a
    weight changed. ``fresh``: the paths the gathers replace (targets from the ``Target`` objects, errors
    evaluated again)."""
    if fresh:
        monkeypatch.setattr(ControlTargets, "retarget_rows", lambda self, packed: False)
        monkeypatch.setattr(gsik.Solver, "compiled_frame", False)  # its gather and report are compiled in
        report = ControlTargets.report
        monkeypatch.setattr(ControlTargets, "report", lambda self, names, q, R, p, left=False: report(
            self, names, q, R, p, False))
    solver, poses = studio_drag_solver(studio)
    out = []
    for frame in range(frames):
        targets = studio_drag_targets(poses, frame, 0.5 if frame % 9 == 4 else 1.0)
        if frame % 5 == 3:
            solver.move_target("left_hand", targets["left_hand"].position + 0.01)
        elif frame % 7 == 6:
            solver.set_q(solver.q + 1e-3)
        elif frame % 11 != 10:  # else the same targets again
            solver.set_targets(targets)
        out.append(solver.step())
    return out


@pytest.mark.parametrize("studio", [False, True], ids=["pins", "studio"])
def test_a_drag_with_the_gathers_is_the_drag_without_them_bit_for_bit(studio, monkeypatch):
    gathered = _drag(monkeypatch, False, studio)
    with monkeypatch.context() as m:
        fresh = _drag(m, True, studio)
    for a, b in zip(gathered, fresh):
        assert a.q.tobytes() == b.q.tobytes()
        assert a.position_errors.tobytes() == b.position_errors.tobytes()
        assert a.orientation_errors.tobytes() == b.orientation_errors.tobytes()
        assert (a.status, a.iterations, a.residual, a.step_norm, a.effector_names) == \
            (b.status, b.iterations, b.residual, b.step_norm, b.effector_names)


def test_a_steps_norm_is_the_whole_moves_norm(monkeypatch):
    """One step a frame reports its own norm, several the norm of their sum: both the in-order norm of the change."""
    solver = gsik.Solver(gsik.load_skeleton("biped"), tracking_steps=3)
    poses = solver.effector_poses()
    use_prior(solver, bundled_prior("biped"))
    iterations = set()
    for frame in range(30):
        before = solver.q
        targets = {n: gsik.Target.from_transform(poses[n]) for n in ("pelvis", "left_foot")}
        targets["left_hand"] = gsik.Target(poses["left_hand"][:3, 3] + [0.0, 0.0, 0.03 * (frame % 4)], priority=1,
                                           position_only=True)
        r = solver.step(targets)
        moved = r.q - before
        assert r.step_norm == math.sqrt(sum(v * v for v in moved.tolist()))
        iterations.add(r.iterations)
    assert {1, 2} <= iterations


def _pinned() -> tuple:
    """A solver with pins, hands at 1 and a posture, stepped once; its controller; its targets."""
    solver = gsik.Solver(gsik.load_skeleton("biped"))
    poses = solver.effector_poses()
    solver.set_posture(solver.q)
    targets = {n: gsik.Target.from_transform(poses[n]) for n in ("pelvis", "left_foot")}
    targets["left_hand"] = gsik.Target(poses["left_hand"][:3, 3] + [0.0, 0.05, 0.05], position_only=True, priority=1)
    solver.step(targets)
    return solver, solver._controller, targets


def _report(solver, left: bool) -> bytes:
    report = solver._controller.report(solver.effector_names, solver._q, solver._ws.R, solver._ws.p, left)
    assert report.finite
    return report.values.tobytes()


def test_a_committed_steps_errors_are_reported_as_a_fresh_evaluation_finds_them():
    solver, c, targets = _pinned()
    assert c._errors_left  # the step was committed by the compiled path
    assert _report(solver, True) == _report(solver, False)


def test_a_fresh_report_is_report_errors_evaluation_bit_for_bit():
    # Controller.report evaluates the errors (effector_errors) and gathers them by report_errors' rule, which the
    # compiled frame still calls: the two read alike, a position-only target's unused rows 0.
    solver, c, targets = _pinned()
    solver.set_q(solver.q + 0.02)  # from outside: nothing left by a step
    n, names = len(solver.q), c.report(solver.effector_names, solver._q, solver._ws.R, solver._ws.p).names
    index = c._layout[2]
    expected = np.empty((2, len(names)))
    report_errors(solver._ws.R, solver._ws.p, c._tasks_in, index, c._e.copy(), c._err.copy(), np.zeros((3, 3)),
                  expected)
    values = np.frombuffer(_report(solver, False))
    assert values[:n].tobytes() == solver._q.tobytes()
    assert values[n:].tobytes() == expected.ravel().tobytes()
    assert np.count_nonzero(expected[0]) == 3 and expected[1, names.index("left_hand")] == 0.0


def test_errors_left_are_not_reported_after_the_targets_or_the_pose_changed():
    solver, c, targets = _pinned()
    stale = _report(solver, True)
    solver.move_target("left_hand", targets["left_hand"].position + 0.02)
    assert solver._make_controller(rows=True) is c and not c._errors_left  # gathered: the last errors are stale
    assert _report(solver, True) == _report(solver, False) != stale
    solver.step()
    assert c._errors_left
    q = solver.q
    q[0] += 0.01
    solver.set_q(q)  # from outside: the solver's result for this pose evaluates the errors again
    r = solver._control_result(gsik.Status.CONVERGED, 1, 0.0, 0.0, 1)
    names, values, _ = c.report(solver.effector_names, solver._q, solver._ws.R, solver._ws.p)
    assert np.concatenate([r.q, r.position_errors, r.orientation_errors]).tobytes() == values.tobytes()
    assert r.position_errors.tobytes() != np.frombuffer(stale)[len(q):len(q) + len(names)].tobytes()


def test_a_held_step_reports_its_errors_afresh():
    solver, c, targets = _pinned()
    for _ in range(200):  # until the pose holds: a held step returns without a trial
        if solver.step().status is gsik.Status.STALLED or c._held is not None:
            break
    assert c._held is not None
    solver.step()
    assert not c._errors_left
    assert _report(solver, True) == _report(solver, False)


def test_a_target_off_the_effectors_is_retargeted_from_the_targets(monkeypatch):
    """An elbow target has no packed row: the controller declines to gather and takes the targets themselves."""
    solver, c, targets = _pinned()
    elbow = solver.world_positions()[solver.skeleton.frame_of("left_elbow")]
    targets["left_elbow"] = gsik.Target(elbow, position_only=True, priority=1)
    solver.step(targets)
    c = solver._controller
    assert c._rows is None and not c.retarget_rows(solver._packed)
    targets["left_elbow"] = gsik.Target(elbow + 0.01, position_only=True, priority=1)
    solver.set_targets(targets)
    solver._make_controller(rows=True)
    assert c._tp[list(c.names).index("left_elbow")].tolist() == (elbow + 0.01).tolist()


@pytest.mark.skipif(not step_inputs.AVAILABLE, reason="StepInputs needs numba's compiled code")
def test_a_step_through_step_inputs_is_the_kernel_given_every_argument(biped):
    """The same pose, frames, damping and every buffer of the controller (cache, stall window, work), step after
    step from random poses, as :func:`gsik.kernels.accept.control_step` called with its 23 arguments."""
    runs = []
    for direct in (False, True):
        rng = np.random.default_rng(4)
        solver, c, targets = _pinned()
        head, mid, tail = c.step_arguments()
        q, W, R, p, lam = solver._q, solver._W, solver._ws.R, solver._ws.p, solver._ws.lam
        inputs = step_inputs.make_step_inputs(*head, *mid, *tail)
        state = []
        for k in range(12):
            if k % 4 == 0:
                solver.set_q(np.clip(solver.q + rng.normal(0.0, 0.05, len(q)), biped.lower, biped.upper))
            if direct:
                ak.control_step(*head, W, *mid, q, R, p, lam, 1e-3, *tail)
            else:
                step_inputs.control_step(inputs, W, q, R, p, lam, 1e-3)
            buffers = [q, R, p, lam, *c._cache, *c._window, *c._work[:-2], *c._work.priority, *c._work.range_work]
            state.append(b"".join(np.ascontiguousarray(a).tobytes() for a in buffers))
        runs.append(state)
    assert runs[0] == runs[1]
    assert len(set(runs[0])) > 1  # the steps moved


def test_without_step_inputs_a_drag_steps_the_same(monkeypatch):
    """Where numba's compiled code is off the controller calls the kernel with every argument: the same drag."""
    with_inputs = _drag(monkeypatch, False, frames=12)
    monkeypatch.setattr(step_inputs, "AVAILABLE", False)
    without = _drag(monkeypatch, False, frames=12)
    for a, b in zip(with_inputs, without):
        assert a.q.tobytes() == b.q.tobytes() and a.position_errors.tobytes() == b.position_errors.tobytes()
        assert (a.status, a.step_norm) == (b.status, b.step_norm)


@pytest.mark.parametrize("left", [True, False])
def test_a_controlled_step_that_leaves_a_non_finite_angle_is_refused_and_undone(monkeypatch, left):
    """The report says whether the angles are finite (gathered with the errors the step left, or not): a step that
    went non-finite is undone, the pose the last finite one."""
    solver, c, targets = _pinned()
    before = solver.q

    def poisoned(self, q, W, R, p, lam):
        q[3] = math.nan
        self._errors_left = left
        return gsik.control.ControlStats(True, False, True, 0.0, 0.0)

    monkeypatch.setattr(gsik.control.Controller, "step", poisoned)
    monkeypatch.setattr(gsik.Solver, "compiled_frame", False)  # the general path (the frame: test_control_frame)
    r = solver.step()
    assert r.status is gsik.Status.REFUSED and r.q.tobytes() == before.tobytes() == solver.q.tobytes()
    assert not c.report(solver.effector_names, np.full(len(before), math.inf), solver._ws.R, solver._ws.p).finite
