"""The strict-priority step: limits kept, higher levels untouched by lower ones, posture as the last level."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.priority import Level, posture_level, prioritized_step


def _levels(rng, n, sizes):
    return [Level(rng.normal(size=(m, n)), rng.normal(size=m), rng.uniform(0.1, 2.0, size=m)) for m in sizes]


def _box(rng, n, width):
    return -rng.uniform(0.0, width, size=n), rng.uniform(0.0, width, size=n)


problems = st.tuples(st.integers(0, 2**32 - 1), st.integers(3, 12), st.lists(st.integers(1, 6), min_size=1, max_size=4),
                     st.floats(0.01, 3.0))


def _problem(problem):
    """``(rng, n, lo, hi, levels)`` of a drawn problem."""
    seed, n, sizes, width = problem
    rng = np.random.default_rng(seed)
    lo, hi = _box(rng, n, width)
    return rng, n, lo, hi, _levels(rng, n, sizes)


@settings(max_examples=200, deadline=None)
@given(problems)
def test_step_never_leaves_the_box(problem):
    rng, n, lo, hi, levels = _problem(problem)
    levels = levels + [posture_level(rng.normal(size=n), rng.normal(size=n), rng.uniform(0, 1, n))]
    dq = prioritized_step(levels, lo, hi, 1e-3)
    assert np.all(dq >= lo) and np.all(dq <= hi)


@settings(max_examples=200, deadline=None)
@given(problems)
def test_lower_levels_never_change_what_a_higher_level_achieves(problem):
    _, _, lo, hi, levels = _problem(problem)
    for k in range(len(levels)):
        alone = prioritized_step(levels[: k + 1], lo, hi, 1e-3)
        below = prioritized_step(levels, lo, hi, 1e-3)
        for j in range(k + 1):
            np.testing.assert_allclose(levels[j].jacobian @ below, levels[j].jacobian @ alone, atol=1e-9)


def test_one_level_without_bounds_is_damped_least_squares(rng):
    J, e, w = rng.normal(size=(5, 8)), rng.normal(size=5), rng.uniform(0.5, 2.0, size=5)
    dq = prioritized_step([Level(J, e, w)], np.full(8, -1e9), np.full(8, 1e9), 1e-2)
    expected = np.linalg.solve(J.T @ (w[:, None] * J) + 1e-2 * np.eye(8), J.T @ (w * e))
    np.testing.assert_allclose(dq, expected, atol=1e-10)


def test_a_feasible_level_is_met_within_the_box_when_one_dof_is_blocked(rng):
    J, e = rng.normal(size=(3, 8)), rng.normal(size=3) * 0.1
    lo, hi = np.full(8, -1.0), np.full(8, 1.0)
    free = prioritized_step([Level(J, e, np.ones(3))], lo, hi, 1e-12)
    blocked = int(np.argmax(np.abs(free)))
    lo[blocked], hi[blocked] = (0.0, abs(free[blocked]) / 2) if free[blocked] > 0 else (-abs(free[blocked]) / 2, 0.0)
    dq = prioritized_step([Level(J, e, np.ones(3))], lo, hi, 1e-12)
    assert lo[blocked] <= dq[blocked] <= hi[blocked]
    np.testing.assert_allclose(J @ dq, e, atol=1e-9)


def test_posture_alone_reaches_the_reference_with_a_full_precision_matrix(rng):
    n = 6
    B = rng.normal(size=(n, n))
    P = B @ B.T + 0.1 * np.eye(n)
    q, mu = rng.normal(size=n) * 0.1, rng.normal(size=n) * 0.1
    dq = prioritized_step([posture_level(q, mu, P)], np.full(n, -1.0), np.full(n, 1.0), 1e-12)
    np.testing.assert_allclose(q + dq, mu, atol=1e-9)


def test_posture_below_a_task_minimises_the_precision_norm_in_the_null_space(rng):
    n = 7
    B = rng.normal(size=(n, n))
    P = B @ B.T + 0.1 * np.eye(n)
    q, mu = np.zeros(n), rng.normal(size=n) * 0.1
    task = Level(rng.normal(size=(3, n)), rng.normal(size=3) * 0.1, np.ones(3))
    dq = prioritized_step([task, posture_level(q, mu, P)], np.full(n, -5.0), np.full(n, 5.0), 1e-12)
    np.testing.assert_allclose(task.jacobian @ dq, task.error, atol=1e-9)
    null = np.linalg.svd(task.jacobian)[2][3:].T
    np.testing.assert_allclose(null.T @ P @ (q + dq - mu), 0.0, atol=1e-9)


def test_zero_posture_weights_leave_the_step_alone(rng):
    n = 5
    task = Level(rng.normal(size=(2, n)), rng.normal(size=2), np.ones(2))
    lo, hi = np.full(n, -1.0), np.full(n, 1.0)
    with_posture = prioritized_step([task, posture_level(np.zeros(n), np.ones(n), np.zeros(n))], lo, hi, 1e-3)
    np.testing.assert_allclose(with_posture, prioritized_step([task], lo, hi, 1e-3), atol=1e-12)
