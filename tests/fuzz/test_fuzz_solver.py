"""A solver that cannot be poisoned: extreme targets are refused or solved to a finite pose within the limits, a
step that would go non-finite is refused, and the solver always recovers."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gsik
from gsik.kernels import O_FINITE
from gsik.solver import Status
from gsik.targets import MAX_COORDINATE, MAX_WEIGHT

EFFECTORS = ("left_hand", "right_hand", "head", "left_foot", "pelvis")
_any_float = st.floats(allow_nan=True, allow_infinity=True) | st.sampled_from([1e300, -1e300, 1e154, 5e-324, 1e6])


@pytest.fixture(scope="module")
def solver(biped):
    return gsik.Solver(biped)


def _sane(solver, result) -> None:
    sk = solver.skeleton
    assert np.isfinite(result.q).all() and np.isfinite(solver.q).all()
    assert np.all(result.q >= sk.lower - 1e-9) and np.all(result.q <= sk.upper + 1e-9)
    errors = np.concatenate([result.position_errors, result.orientation_errors])
    assert np.isfinite(errors).all() or result.status is Status.REFUSED
    if result.status is Status.CONVERGED:
        assert np.isfinite(errors).all()


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(_any_float, min_size=3, max_size=3), _any_float)
def test_any_target_is_refused_or_gives_a_target_within_the_limits(position, weight):
    try:
        t = gsik.Target(position, weight=weight)
    except gsik.TargetError:
        return
    assert np.all(np.abs(t.position) <= MAX_COORDINATE) and 0 <= t.weight <= MAX_WEIGHT


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.sampled_from(EFFECTORS), st.lists(st.sampled_from([MAX_COORDINATE, -MAX_COORDINATE, 0.0, 1e-300, 3.0]),
                                            min_size=3, max_size=3),
       st.sampled_from([MAX_WEIGHT, 1.0, 1e-300, 0.0]), st.booleans())
def test_extreme_allowed_targets_never_poison_the_solver(solver, effector, position, weight, full_solve):
    target = gsik.Target(position, weight=weight)
    result = solver.solve({effector: target}) if full_solve else solver.step({effector: target})
    _sane(solver, result)
    after = solver.solve({"left_hand": gsik.Target([0.25, 0.2, 1.0])})  # recovers: an easy target converges
    _sane(solver, after)
    assert after.converged


def test_the_issues_poison_is_refused_where_it_enters():
    with pytest.raises(gsik.TargetError, match="within 1e\\+06 m"):
        gsik.Target([1e300, -1e300, 1e300], weight=1e9)
    with pytest.raises(gsik.TargetError, match="at most 1e\\+06"):
        gsik.Target([0.0, 0.0, 1.0], weight=1e9)


def test_a_step_that_would_go_non_finite_is_refused_and_keeps_the_pose(biped):
    solver = gsik.Solver(biped)
    q = solver.q
    huge = np.eye(4)
    huge[:3, :3] *= 1e200  # finite but not a rotation: forward kinematics overflows
    solver.set_world_from_root(huge)
    result = solver.step({"left_hand": gsik.Target([0.2, 0.2, 1.0])})
    assert result.status is Status.REFUSED and result.status.label == "refused"
    np.testing.assert_array_equal(solver.q, q)
    assert np.isfinite(result.q).all()
    solver.set_world_from_root(np.eye(4))
    solver.set_root("left_foot")  # the studio's poisoned state could not switch roots
    assert solver.solve({"left_hand": gsik.Target([0.2, 0.2, 1.0])}).status is not Status.REFUSED
    _sane(solver, solver.step())


def test_a_root_placed_beyond_the_limit_is_refused(biped):
    W = np.eye(4)
    W[0, 3] = 2 * MAX_COORDINATE
    with pytest.raises(gsik.SolverError, match="within 1e\\+06 m"):
        gsik.Solver(biped, world_from_root=W)


@pytest.mark.parametrize("changes, words", [
    (dict(max_iterations=10**20), "between 0 and 10,000"), (dict(sweeps=2**62), "between 0 and 10,000"),
    (dict(damping=10**400), "must be finite"), (dict(orientation_weight=1e300), "at most 1e+06"),
])
def test_settings_beyond_their_caps_are_refused(solver, changes, words):
    with pytest.raises(gsik.SolverError, match=words.replace("+", "\\+")):
        solver.configure(**changes)


def test_settings_are_stored_as_python_numbers(biped):
    s = gsik.Solver(biped, damping=np.float32(0.01), sweeps=np.int64(7), warm_start=np.bool_(True)).settings
    assert (type(s.damping), type(s.sweeps), type(s.warm_start)) == (float, int, bool)


def test_position_errors_do_not_overflow(biped):
    solver = gsik.Solver(biped)
    far = np.eye(4)
    far[:3, 3] = [MAX_COORDINATE, MAX_COORDINATE, MAX_COORDINATE]
    solver.set_world_from_root(far)
    result = solver.step({"left_hand": gsik.Target([-MAX_COORDINATE] * 3)})
    assert np.isfinite(result.position_errors).all() and result.position_errors.max() > 3e6


def test_a_prioritised_step_that_would_go_non_finite_is_refused_too(biped):
    solver = gsik.Solver(biped)
    q = solver.q
    huge = np.eye(4)
    huge[:3, :3] *= 1e200
    solver.set_world_from_root(huge)
    with np.errstate(all="ignore"):
        result = solver.step({"left_hand": gsik.Target([0.2, 0.2, 1.0], priority=0),
                              "head": gsik.Target([0.0, 0.0, 1.6], priority=1)})
    assert np.isfinite(solver.q).all()
    if result.status is Status.REFUSED:
        np.testing.assert_array_equal(solver.q, q)
    solver.set_world_from_root(np.eye(4))
    _sane(solver, solver.solve({"left_hand": gsik.Target([0.2, 0.2, 1.0])}))


def test_the_step_kernel_reports_a_non_finite_step_and_does_not_take_it(biped):
    solver = gsik.Solver(biped)
    solver.set_targets({"left_hand": gsik.Target([0.2, 0.2, 1.0])})
    step, inputs = solver._kernel_inputs()
    q, ws = inputs[5], inputs[6]
    step(*inputs)
    assert ws.stats[O_FINITE] == 1.0
    huge = np.eye(4)
    huge[:3, :3] *= 1e200  # finite but not a rotation: forward kinematics overflows
    solver.set_world_from_root(huge)
    before = q.copy()
    step(*inputs)
    assert ws.stats[O_FINITE] == 0.0
    np.testing.assert_array_equal(q, before)  # the kernel itself left the angles as they were


def test_the_solve_kernel_reports_whether_it_ends_finite(biped):
    solver = gsik.Solver(biped, restarts=0)
    solver.solve({"left_hand": gsik.Target([0.2, 0.2, 1.0])})
    assert solver._ws.stats[O_FINITE] == 1.0
    huge = np.eye(4)
    huge[:3, :3] *= 1e200
    solver.set_world_from_root(huge)
    assert solver.solve().status is Status.REFUSED
    assert solver._ws.stats[O_FINITE] == 0.0
