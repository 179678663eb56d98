"""The strict-priority step by its normal equations (gsik.kernels.range_space): where it takes the step it is the
pivoted QR path's to rounding, and it leaves to that path what it cannot take exactly (a rank-deficient or
ill-conditioned level, a target level meeting the box, a posture locking more DOFs than it holds, a posture not seen
twice); the controller's drag takes it."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_posture_level import _diagonal_factor, _full_factor, posture_problems

from gsik.kernels import priority as priority_kernel
from gsik.kernels import range_space as rs
from gsik.kernels.posture_level import normal_matrix, prioritized_step_posture, prioritized_step_posture_in
from gsik.priority import (BOX_RELATIVE_TOLERANCE, BOX_TOLERANCE, RANK_TOLERANCE, Level, factor_level, pack_levels,
                           prioritized_step_svd)

TOLS = (RANK_TOLERANCE, BOX_TOLERANCE, BOX_RELATIVE_TOLERANCE)


def _both(levels, lo, hi, dampings, normal, bound=0.0, calls=2):
    """``(range path's step, taken by the normal equations, QR path's step)`` of the packed ``levels`` (the posture
    last), the range path called ``calls`` times in one :class:`RangeWork` (its posture is seen from the second)."""
    n = lo.shape[0]
    rows, errors, weights, starts = pack_levels(levels, n)
    dampings = np.array(dampings, dtype=float)
    rw = rs.make_range_work(int(starts[-2]), n)
    wk = priority_kernel.make_work(n, int(priority_kernel.largest_level(starts, len(dampings))))
    dq, below = np.full(n, np.nan), np.zeros(n)
    for _ in range(calls):
        status, share = rs.prioritized_step_range_in(rw, wk, rows, errors, weights, starts, dampings, lo, hi, *TOLS,
                                                     normal, bound, dq, below)
        assert status == priority_kernel.OK
    qr, below_qr = np.full(n, np.nan), np.zeros(n)
    status, share_qr = prioritized_step_posture(rows, errors, weights, starts, dampings, lo, hi, *TOLS, normal, bound,
                                                qr, below_qr)
    assert status == priority_kernel.OK
    assert share == pytest.approx(share_qr, rel=1e-8, abs=1e-12)
    return dq, rw.state[rs.S_TAKEN] > 0.0, qr


def _pins_and_hands(rng, n=30, factor=None, width=1.0):
    """A drag's levels (pins on 14 DOFs, hands on 14 more, overlapping) above a posture, a roomy box."""
    pins = np.zeros((12, n))
    pins[:, :14] = rng.normal(size=(12, 14))
    hands = np.zeros((6, n))
    hands[:, 10:24] = rng.normal(size=(6, 14))
    factor = _full_factor(rng, n) if factor is None else factor
    levels = [Level(pins, rng.normal(size=12) * 1e-3, np.ones(12)), Level(hands, rng.normal(size=6) * 1e-2, np.ones(6)),
              factor_level(rng.normal(size=n) * 0.05, np.zeros(n), factor)]
    return levels, -np.full(n, width), np.full(n, width), normal_matrix(factor)


@settings(max_examples=300, deadline=None)
@given(posture_problems(), st.sampled_from([0.0, 10.0]))
def test_the_step_is_the_pivoted_qr_step_and_the_svd_reference_whichever_path_takes_it(problem, bound):
    """Boxes from roomy to tight enough that the posture's level locks DOFs; a full posture inverted where its share
    is bounded (a bound of 10 rad leaves these steps whole, the SVD reference's)."""
    levels, lo, hi, dampings, normal = problem
    dq, _, qr = _both(levels, lo, hi, dampings, normal, bound)
    assert np.all(dq >= lo) and np.all(dq <= hi)
    np.testing.assert_allclose(dq, qr, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(dq, prioritized_step_svd(levels, lo, hi, dampings), rtol=0.0, atol=1e-8)


@pytest.mark.parametrize("kind", ["full", "diagonal", "uniform"])
def test_a_drag_s_levels_are_solved_by_the_normal_equations_and_agree_with_the_qr(rng, kind):
    n = 30
    factor = {"full": lambda: _full_factor(rng, n), "diagonal": lambda: _diagonal_factor(rng, n),
              "uniform": lambda: np.eye(n)}[kind]()
    levels, lo, hi, normal = _pins_and_hands(rng, n, factor)
    for bound in (0.0, 1e-3, 10.0):  # a share bound applies to the normal equations' step as to the QR's
        dq, taken, qr = _both(levels, lo, hi, [1e-6, 1e-6, 1e-3], normal, bound)
        assert taken == (bound > 0.0 or kind != "full")  # a full one unbounded: a settle's, left to the QR path
        np.testing.assert_allclose(dq, qr, rtol=0.0, atol=1e-11)


def test_what_it_cannot_take_exactly_it_leaves_to_the_qr_path(rng):
    n = 30
    levels, lo, hi, normal = _pins_and_hands(rng, n)
    dampings = [1e-6, 1e-6, 1e-3]
    _, taken, _ = _both(levels, lo, hi, dampings, normal, bound=10.0, calls=1)
    assert not taken  # a posture seen once: the next step may bring another (a settle's curvature), not inverted
    tight = np.full(n, 1e-4)  # the target levels' steps meet the box: the QR's active set locks DOFs
    dq, taken, qr = _both(levels, -tight, tight, dampings, normal, bound=10.0)
    assert not taken
    np.testing.assert_array_equal(dq, qr)
    duplicated = [Level(np.vstack([lv.jacobian, lv.jacobian[:1]]), np.append(lv.error, lv.error[0]),
                        np.append(lv.weights, 1.0)) for lv in levels[:1]] + levels[1:]
    dq, taken, qr = _both(duplicated, lo, hi, dampings, normal, bound=10.0)  # rank-deficient: the QR decides the rank
    assert not taken
    np.testing.assert_array_equal(dq, qr)
    nearly = levels[0].jacobian[:6] + 1e-6 * rng.normal(size=(6, n))  # the hands' rows nearly the pins'
    close = [levels[0], Level(nearly, levels[1].error, levels[1].weights), levels[2]]
    # ill-conditioned: the QR, not the normal equations' squared condition number
    dq, taken, qr = _both(close, lo, hi, dampings, normal, bound=10.0)
    assert not taken
    np.testing.assert_array_equal(dq, qr)


@pytest.mark.parametrize("kind", ["full", "diagonal", "uniform"])
def test_the_posture_s_level_locks_dofs_at_the_box_as_the_qr_s_active_set_does(rng, kind):
    """DOFs only the posture moves, boxed short of its step one more at a time: up to LOCKS locked DOFs the normal
    equations take the step, each DOF where the QR's active set locks it; past that the QR path does."""
    n = 30
    factor = {"full": lambda: _full_factor(rng, n), "diagonal": lambda: _diagonal_factor(rng, n),
              "uniform": lambda: np.eye(n)}[kind]()
    levels, lo, hi, normal = _pins_and_hands(rng, n, factor)
    rows, errors, weights, starts = pack_levels(levels, n)
    dampings = np.array([1e-6, 1e-6, 1e-3])
    free, _, _ = _both(levels, lo, hi, dampings, normal, bound=10.0)
    own = 24 + np.argsort(-np.abs(free[24:]))  # the DOFs no target row moves, the posture's longest moves first
    locks_seen = set()
    for k in range(1, 7):
        box_lo, box_hi = lo.copy(), hi.copy()
        for d in own[:k]:  # each boxed at a third of its free move: it blocks
            box_lo[d], box_hi[d] = min(free[d] / 3.0, 0.0), max(free[d] / 3.0, 0.0)
        dq, taken, qr = _both(levels, box_lo, box_hi, dampings, normal, bound=10.0)
        wk = priority_kernel.make_work(n, int(priority_kernel.largest_level(starts, 3)))
        prioritized_step_posture_in(wk, rows, errors, weights, starts, dampings, box_lo, box_hi, *TOLS, normal, 10.0,
                                    np.zeros(n), np.zeros(n))
        locks = int(wk.locked.sum())  # the QR's active set
        locks_seen.add(locks)
        assert taken == (1 <= locks <= rs.LOCKS)
        np.testing.assert_allclose(dq, qr, rtol=0.0, atol=1e-11)
        assert np.sum((dq == box_lo) | (dq == box_hi)) >= locks
    assert {1, rs.LOCKS, rs.LOCKS + 1} <= locks_seen  # one lock, the most held, one more: the QR's


def test_a_posture_that_changes_is_inverted_again_only_once_it_holds(rng):
    """A matrix or damping seen once is left to the QR path; seen twice in a row, it is inverted and the steps are
    taken again. Where the share is not bounded (a settle, which swaps the targets' curvature into the posture's level
    every step) a full posture is never inverted."""
    levels, lo, hi, normal = _pins_and_hands(rng)
    rows, errors, weights, starts = pack_levels(levels, 30)
    rw = rs.make_range_work(int(starts[-2]), 30)
    wk = priority_kernel.make_work(30, int(priority_kernel.largest_level(starts, 3)))
    dq, below = np.zeros(30), np.zeros(30)
    other = normal_matrix(_full_factor(rng, 30))
    steps = ((normal, 1e-3, 0), (normal, 1e-3, 1), (normal, 1e-3, 2), (other, 1e-3, 2), (other, 1e-3, 3),
             (normal, 1e-3, 3), (normal, 1e-2, 3), (normal, 1e-2, 4))
    for P, damping, taken in steps:
        dampings = np.array([1e-6, 1e-6, damping])
        rs.prioritized_step_range_in(rw, wk, rows, errors, weights, starts, dampings, lo, hi, *TOLS, P, 10.0, dq,
                                     below)
        assert rw.state[rs.S_TAKEN] == taken
        qr = np.zeros(30)
        prioritized_step_posture(rows, errors, weights, starts, dampings, lo, hi, *TOLS, P, 10.0, qr, np.zeros(30))
        np.testing.assert_allclose(dq, qr, rtol=0.0, atol=1e-11)
    for _ in range(3):  # unbounded (a settle's steps): never inverted, the QR path's
        rs.prioritized_step_range_in(rw, wk, rows, errors, weights, starts, dampings, lo, hi, *TOLS, other, 0.0, dq,
                                     below)
    assert rw.state[rs.S_TAKEN] == 4 and rw.state[rs.S_INVERTED] == 0.0


def test_the_controller_s_drag_steps_by_the_normal_equations():
    """The studio's drag (pins, hands at 1, the bundled prior): most of its steps by the normal equations."""
    from solver_helpers import studio_drag_solver, studio_drag_targets

    solver, poses = studio_drag_solver(True)
    for frame in range(20):
        solver.step(studio_drag_targets(poses, frame))
    state = solver._controller._work.range_work.state
    assert state[rs.S_TAKEN] >= 10


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_the_conditioning_test_is_the_trace_bound_of_the_gram_matrix(seed):
    rng = np.random.default_rng(seed)
    m = int(rng.integers(1, 19))
    rows = rng.normal(size=(m, 30)) * np.exp(rng.uniform(-4.0, 0.0, size=(m, 1)))  # rows of mixed scales
    F = np.linalg.cholesky(rows @ rows.T)
    bound = 1.0 / np.sqrt(np.trace(np.linalg.inv(rows @ rows.T)))  # 1 / sqrt(trace(K^-1)) <= sigma_min(rows)
    assert bound <= np.linalg.svd(rows, compute_uv=False).min() * (1.0 + 1e-9)
    X = np.zeros((18, 18))
    assert rs._conditioned(F, m, X, bound * (1.0 - 1e-6))
    assert not rs._conditioned(F, m, X, bound * (1.0 + 1e-6))
    inverse = np.linalg.inv(F)  # what it sums: F^-1, row by row into X
    np.testing.assert_allclose(np.tril(X[:m, :m]), inverse, rtol=1e-9, atol=1e-9 * np.abs(inverse).max())
