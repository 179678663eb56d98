"""The targets' state at a pose in one compiled call (gsik.kernels.target_state): the weighted cost is NumPy's sum bit
for bit, and the stage and tolerance tests are the Python tests on the controller's errors."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from solver_helpers import random_q, studio_drag_solver, studio_drag_targets

from gsik._jit import python_function
from gsik.kernels import target_state as ts
from gsik.targets import Target

# Values drawn so that zeros of both signs, NaN, infinities, subnormals and near-overflow squares all occur.
SPECIAL = st.sampled_from([0.0, -0.0, 1.0, -1.0 - 2.0 ** -52, 3e-160, 5e-324, 1e154, 2e154, float("nan"), float("inf")])


def _numpy_cost(e: np.ndarray, w: np.ndarray) -> float:
    """What ``Controller.target_cost`` computed in NumPy before: ``e`` (6 m,), ``w`` (m, 6)."""
    with np.errstate(over="ignore", invalid="ignore"):  # the special values overflow, inf * 0 is NaN
        squares = e.reshape(-1, 6) * e.reshape(-1, 6)
        squares *= w
        return float(squares.sum())


def _bits(x: float) -> bytes:
    return np.float64(x).tobytes()


@settings(max_examples=150, deadline=None)
@given(m=st.integers(1, ts.MAX_TERMS // 6), seed=st.integers(0, 2 ** 32 - 1), spread=st.integers(0, 12))
def test_weighted_squares_sum_is_numpys_sum_bit_for_bit(m, seed, spread):
    """Any number of tasks it takes (a block of 6 to 128 terms, two above), errors over ``spread``
    decades, weights with zeros: the compiled sum and its Python form are NumPy's, bit for bit."""
    rng = np.random.default_rng(seed)
    e = rng.standard_normal(6 * m) * 10.0 ** rng.uniform(-spread, 1, 6 * m)
    w = rng.uniform(0.0, 3.0, (m, 6)) * (rng.uniform(size=(m, 6)) > 0.3)
    expected = _bits(_numpy_cost(e, w))
    assert _bits(ts.weighted_squares_sum(e, w)) == expected
    assert _bits(python_function(ts.weighted_squares_sum)(e, w)) == expected


@settings(max_examples=150, deadline=None)
@given(data=st.data(), m=st.integers(1, 30))
def test_weighted_squares_sum_of_special_values(data, m):
    """Zeros of both signs, NaN, infinities and overflowing squares give NumPy's bits (NaN: a NaN)."""
    e = np.array(data.draw(st.lists(SPECIAL, min_size=6 * m, max_size=6 * m)))
    w = np.abs(np.array(data.draw(st.lists(SPECIAL, min_size=6 * m, max_size=6 * m)))).reshape(m, 6)
    expected, got = _numpy_cost(e, w), ts.weighted_squares_sum(e, w)
    assert (math.isnan(got) and math.isnan(expected)) or _bits(got) == _bits(expected)


def test_weighted_squares_sum_is_not_a_running_sum():
    """The pairwise order matters: on these 40 terms a running sum differs from NumPy's, and the kernel does not."""
    rng = np.random.default_rng(7)
    e, w = rng.standard_normal(240) * 10.0 ** rng.uniform(-8, 3, 240), np.ones((40, 6))
    running = sum((e * e).tolist())
    assert running != _numpy_cost(e, w)
    assert ts.weighted_squares_sum(e, w) == _numpy_cost(e, w)


def _controller():
    """A studio drag's solver (pins on pelvis and left foot, hands at priority 1, the start pose as the posture) at
    one frame, and its controller."""
    solver, poses = studio_drag_solver(studio=False)
    solver.set_targets(studio_drag_targets(poses, 5))
    return solver, solver._make_controller()


def test_target_cost_is_the_numpy_cost_at_random_poses():
    """At random poses the compiled cost is NumPy's over the controller's errors, bit for bit, and leaves the errors
    ``effector_errors`` writes."""
    solver, c = _controller()
    rng = np.random.default_rng(3)
    for _ in range(40):
        solver.set_q(random_q(solver.skeleton, rng))
        R, p = solver._ws.R, solver._ws.p
        cost = c.target_cost(R, p)
        left = c._e.copy(), c._err.copy()
        c._task_errors(R, p)  # effector_errors alone
        assert c._e.tobytes() == left[0].tobytes() and c._err.tobytes() == left[1].tobytes()
        assert _bits(cost) == _bits(0.5 * _numpy_cost(c._e, c._row_w))


def test_target_cost_above_the_compiled_sums_terms_is_numpys(monkeypatch):
    """More terms than the compiled sum takes (NaN there): the controller sums them in NumPy, the same value."""
    assert math.isnan(ts.weighted_squares_sum(np.ones(6 * 41), np.ones((41, 6))))
    most = ts.MAX_TERMS // 6  # tasks
    assert ts.weighted_squares_sum(np.ones(6 * most), np.ones((most, 6))) == 6 * most
    solver, c = _controller()
    R, p = solver._ws.R, solver._ws.p
    compiled = c.target_cost(R, p)
    monkeypatch.setattr(ts, "MAX_TERMS", 0)
    assert _bits(c.target_cost(R, p)) == _bits(compiled)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), stage=st.sampled_from([0.0, 0.3, 1.0, math.inf, float("nan")]),
       tolerance=st.sampled_from([1e-4, 0.05, 0.5, 10.0]), position_only=st.booleans(), poisoned=st.booleans())
def test_target_state_is_the_python_tests_on_the_errors(seed, stage, tolerance, position_only, poisoned):
    """The stage test (every used orientation error within the angle) and the tolerance test are those the solver
    made in Python on :meth:`errors` (0 where a row is unused; a NaN angle or error passes nothing)."""
    solver, _ = _controller()
    rng = np.random.default_rng(seed)
    solver.configure(position_tolerance=tolerance, orientation_tolerance=tolerance * 2.0)
    if position_only:  # the orientation rows unused: the stage test passes whatever the angles
        solver.set_targets({n: Target(t.position, position_only=True, priority=t.priority)
                            for n, t in solver.targets.items()})
    c = solver._make_controller()
    solver.set_q(random_q(solver.skeleton, rng) if rng.uniform() < 0.8 else solver.q)
    R, p = solver._ws.R.copy(), solver._ws.p.copy()
    if poisoned:  # a non-finite frame under one target: NaN errors there
        R[c._tasks_in.frame[rng.integers(len(c.names))], 0, 0] = np.nan
    pos, ori = c.errors(R, p)
    s = solver.settings
    expected = (all(e <= stage for e in ori.tolist()),
                all(e <= s.position_tolerance for e in pos.tolist())
                and all(e <= s.orientation_tolerance for e in ori.tolist()))
    assert c.target_state(R, p, stage) == expected
    assert c.converged(R, p) == expected[1]
