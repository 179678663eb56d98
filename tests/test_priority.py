"""The strict-priority step: limits kept, higher levels untouched by lower ones, posture as the last level; the
compiled step equal to the NumPy SVD reference."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.priority import Level, pack_levels, posture_level, prioritized_step, prioritized_step_svd
from solver_helpers import hard_level


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


# -- the compiled step against the NumPy SVD reference -----------------------------------------------------------
@st.composite
def hard_problems(draw):
    """``(levels, lo, hi, damping)``: up to 30 DOFs and 4 levels, some empty, some with a duplicated or a zero row
    (rank-deficient), some leaving DOFs unmoved; boxes from roomy to so tight that most steps lock DOFs, some DOFs
    resting on a bound (as joints at their limits do at the rest pose). Rows are random otherwise, so what a level
    sees of its rows beyond the higher levels' is well conditioned."""
    n = draw(st.integers(1, 30))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    levels = []
    for m in draw(st.lists(st.integers(0, 8), min_size=1, max_size=4)):
        levels.append(hard_level(draw, rng, m, n))
    width = draw(st.sampled_from([0.01, 0.3, 3.0]))
    lo, hi = _box(rng, n, width)
    if draw(st.booleans()):
        lo[rng.random(n) < 0.3] = 0.0
        hi[rng.random(n) < 0.3] = 0.0
    return levels, lo, hi, draw(st.sampled_from([1e-3, 1e-6]))


@settings(max_examples=300, deadline=None)
@given(hard_problems())
def test_compiled_step_equals_the_svd_reference(problem):
    levels, lo, hi, damping = problem
    np.testing.assert_allclose(prioritized_step(levels, lo, hi, damping),
                               prioritized_step_svd(levels, lo, hi, damping), rtol=0.0, atol=1e-8)


@settings(max_examples=200, deadline=None)
@given(hard_problems())
def test_compiled_step_stays_in_the_box_and_keeps_every_higher_level(problem):
    levels, lo, hi, damping = problem
    alone = [prioritized_step(levels[: k + 1], lo, hi, damping) for k in range(len(levels))]
    for k, dq in enumerate(alone):
        assert np.all(dq >= lo) and np.all(dq <= hi)
        for j in range(k):
            np.testing.assert_allclose(levels[j].jacobian @ dq, levels[j].jacobian @ alone[j], rtol=0.0, atol=1e-9)


def test_per_level_damping_matches_the_reference(rng):
    levels, (lo, hi) = _levels(rng, 9, [3, 2, 4]), _box(rng, 9, 0.5)
    dampings = [1e-2, 1e-4, 1e-3]
    np.testing.assert_allclose(prioritized_step(levels, lo, hi, dampings),
                               prioritized_step_svd(levels, lo, hi, dampings), atol=1e-12)


def test_no_levels_or_only_empty_ones_give_no_step():
    lo, hi = -np.ones(4), np.ones(4)
    empty = Level(np.zeros((0, 4)), np.zeros(0), np.zeros(0))
    np.testing.assert_array_equal(prioritized_step([], lo, hi, 1e-3), np.zeros(4))
    np.testing.assert_array_equal(prioritized_step([empty, empty], lo, hi, 1e-3), np.zeros(4))


def test_a_level_of_zero_rows_gives_no_step_along_the_directions_it_does_not_see():
    lo, hi = -np.ones(3), np.ones(3)
    zero = Level(np.zeros((2, 3)), np.array([0.1, -0.5]), np.ones(2))
    np.testing.assert_array_equal(prioritized_step([zero], lo, hi, 1e-3), np.zeros(3))
    last_dof_unseen = Level(np.array([[1.0, 2.0, 0.0]]), np.array([0.3]), np.ones(1))
    dq = prioritized_step([last_dof_unseen], lo, hi, 1e-3)
    assert dq[2] == 0.0
    np.testing.assert_allclose(dq, prioritized_step_svd([last_dof_unseen], lo, hi, 1e-3), atol=1e-12)


def test_sparse_levels_as_the_drag_has_them_equal_the_svd_reference(rng):
    """Pins on a few DOFs, hands on others, a diagonal posture below (a nonzero per row): the kernel factors only
    the directions each level sees and multiplies only nonzeros, with the same step as the dense reference."""
    n = 16
    pins = np.zeros((6, n))
    pins[:, :7] = rng.normal(size=(6, 7))
    hands = np.zeros((3, n))
    hands[:, 4:12] = rng.normal(size=(3, 8))
    levels = [Level(pins, rng.normal(size=6) * 0.1, np.ones(6)), Level(hands, rng.normal(size=3) * 0.1, np.ones(3)),
              posture_level(rng.normal(size=n) * 0.1, np.zeros(n), rng.uniform(0.5, 2.0, n))]
    for width in (3.0, 0.02):  # roomy, and tight enough that DOFs lock
        lo, hi = _box(rng, n, width)
        np.testing.assert_allclose(prioritized_step(levels, lo, hi, [1e-6, 1e-6, 1e-3]),
                                   prioritized_step_svd(levels, lo, hi, [1e-6, 1e-6, 1e-3]), atol=1e-10)


def test_a_non_finite_jacobian_raises_as_the_svd_does(rng):
    J = rng.normal(size=(3, 5))
    J[1, 2] = np.nan
    level = Level(J, np.ones(3), np.ones(3))
    with pytest.raises(np.linalg.LinAlgError):
        prioritized_step_svd([level], -np.ones(5), np.ones(5), 1e-3)
    with pytest.raises(np.linalg.LinAlgError, match="non-finite"):
        prioritized_step([level], -np.ones(5), np.ones(5), 1e-3)


def test_packed_levels_keep_each_level_s_rows_in_order(rng):
    levels = _levels(rng, 4, [2, 0, 3])
    packed = pack_levels(levels, 4)
    np.testing.assert_array_equal(packed.starts, [0, 2, 2, 5])
    np.testing.assert_array_equal(packed.rows, np.vstack([level.jacobian for level in levels]))
    np.testing.assert_array_equal(packed.errors, np.concatenate([level.error for level in levels]))
    np.testing.assert_array_equal(packed.weights, np.concatenate([level.weights for level in levels]))


def test_a_dof_resting_on_its_limit_that_a_level_leaves_alone_stays_free_for_the_levels_below(rng):
    # Level 0 does not move DOF 2 (at its lower limit 0); in the rotated basis its step there is rounding (1e-17, either
    # sign), which must not lock it: level 1 then bends it to 0.5.
    n = 5
    rotation = np.linalg.qr(rng.normal(size=(n, n)))[0]
    J0 = rng.normal(size=(3, n))
    J0[:, 2] = 0.0
    J0 = (J0 @ rotation) @ rotation.T
    J1 = np.eye(n)[[2]]
    lo, hi = np.array([-1.0, -1.0, 0.0, -1.0, -1.0]), np.ones(n)
    levels = [Level(J0, rng.normal(size=3) * 0.1, np.ones(3)), Level(J1, np.array([0.5]), np.ones(1))]
    for step in (prioritized_step, prioritized_step_svd):
        np.testing.assert_allclose(step(levels, lo, hi, 1e-9)[2], 0.5, atol=1e-6)
