"""A full or diagonal posture's level by its normal equations (gsik.kernels.posture_level): the pivoted QR kernel's
step and the SVD reference's, through locked DOFs, rank-deficient and empty levels above; which factors take that
path."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.kernels import priority as priority_kernel
from gsik.kernels.posture_level import WELL_CONDITIONED, normal_matrix, prioritized_step_posture
from gsik.priority import (BOX_RELATIVE_TOLERANCE, BOX_TOLERANCE, RANK_TOLERANCE, Level, factor_level, pack_levels,
                           posture_factor, prioritized_step_svd)
from solver_helpers import hard_level


def _full_factor(rng, n, condition=30.0):
    """A dense posture factor (n, n) with singular values from 1 to ``1 / condition``, as a learned prior's."""
    U, _ = np.linalg.qr(rng.normal(size=(n, n)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return U @ np.diag(np.geomspace(1.0, 1.0 / condition, n)) @ V.T


def _diagonal_factor(rng, n, condition=30.0):
    """A diagonal posture factor (n, n) with entries from 1 to ``1 / condition`` in random order (pins' or the
    retargeter's per-DOF weights)."""
    return posture_factor(rng.permutation(np.geomspace(1.0, 1.0 / condition, n)) ** 2)


def _steps(levels, lo, hi, dampings, normal):
    """``(normal equations' step, pivoted QR's step)`` (n,) of the packed ``levels``, the posture last."""
    packed = pack_levels(levels, lo.shape[0])
    dampings = np.array(dampings, dtype=float)
    out = []
    for step in (lambda dq: prioritized_step_posture(*packed, dampings, lo, hi, RANK_TOLERANCE, BOX_TOLERANCE,
                                                     BOX_RELATIVE_TOLERANCE, normal, 0.0, dq, dq)[0],
                 lambda dq: priority_kernel.prioritized_step(*packed, dampings, lo, hi, RANK_TOLERANCE, BOX_TOLERANCE,
                                                             BOX_RELATIVE_TOLERANCE, dq)):
        dq = np.full(lo.shape[0], np.nan)
        assert step(dq) == priority_kernel.OK
        out.append(dq)
    return out


@st.composite
def posture_problems(draw):
    """``(levels, lo, hi, dampings, normal)``: up to 3 levels above (some empty, with a duplicated or a zero row, or
    DOFs they do not move), a full or diagonal well-conditioned posture below; boxes from roomy to tight enough that the posture's
    level locks DOFs, some DOFs resting on a bound."""
    n = draw(st.integers(2, 30))  # one DOF's factor is diagonal
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    levels = [hard_level(draw, rng, m, n, 0.1) for m in draw(st.lists(st.integers(0, 8), min_size=0, max_size=3))]
    make = _diagonal_factor if draw(st.booleans()) else _full_factor
    factor = make(rng, n, draw(st.sampled_from([1.0, 30.0, 1e3])))
    levels.append(factor_level(rng.normal(size=n) * 0.3, np.zeros(n), factor))
    width = draw(st.sampled_from([0.01, 0.1, 3.0]))
    lo, hi = -rng.uniform(0.0, width, size=n), rng.uniform(0.0, width, size=n)
    if draw(st.booleans()):
        lo[rng.random(n) < 0.2] = 0.0
    dampings = [draw(st.sampled_from([1e-6, 1e-3]))] * (len(levels) - 1) + [draw(st.sampled_from([0.0, 1e-3, 0.1]))]
    return levels, lo, hi, dampings, normal_matrix(factor)


@settings(max_examples=300, deadline=None)
@given(posture_problems())
def test_the_normal_equations_step_is_the_pivoted_qr_step_and_the_svd_reference(problem):
    levels, lo, hi, dampings, normal = problem
    assert normal.shape == (lo.shape[0], lo.shape[0])
    dq, qr = _steps(levels, lo, hi, dampings, normal)
    assert np.all(dq >= lo) and np.all(dq <= hi)
    np.testing.assert_allclose(dq, qr, rtol=0.0, atol=1e-10)
    np.testing.assert_allclose(dq, prioritized_step_svd(levels, lo, hi, dampings), rtol=0.0, atol=1e-8)


def test_dofs_locked_by_the_posture_s_level_are_on_their_bounds_and_the_rest_solved(rng):
    """Tight boxes: the posture's level locks several DOFs one after another (its basis and normal matrix turned, not
    refactored) and still gives the QR's step; the levels above keep what they achieve alone."""
    n = 30
    pins = np.zeros((12, n))
    pins[:, :14] = rng.normal(size=(12, 14))
    hands = np.zeros((6, n))
    hands[:, 10:24] = rng.normal(size=(6, 14))
    factor = _full_factor(rng, n)
    above = [Level(pins, rng.normal(size=12) * 0.01, np.ones(12)), Level(hands, rng.normal(size=6) * 0.01, np.ones(6))]
    levels = above + [factor_level(rng.normal(size=n), np.zeros(n), factor)]
    lo, hi = -rng.uniform(0.0, 0.05, size=n), rng.uniform(0.0, 0.05, size=n)
    dq, qr = _steps(levels, lo, hi, [1e-6, 1e-6, 1e-3], normal_matrix(factor))
    on_bounds = np.sum((dq == lo) | (dq == hi))
    assert on_bounds >= 3
    np.testing.assert_allclose(dq, qr, rtol=0.0, atol=1e-12)
    alone, _ = _steps(above, lo, hi, [1e-6, 1e-6], np.zeros((0, n)))
    for level in above:
        np.testing.assert_allclose(level.jacobian @ dq, level.jacobian @ alone, atol=1e-9)


def test_a_posture_alone_and_one_below_levels_that_leave_nothing_free(rng):
    n = 7
    factor = _full_factor(rng, n)
    posture = factor_level(rng.normal(size=n) * 0.1, np.zeros(n), factor)
    lo, hi = -np.ones(n), np.ones(n)
    dq, qr = _steps([posture], lo, hi, [1e-3], normal_matrix(factor))  # no level above: the identity basis
    expected = np.linalg.solve(factor.T @ factor + 1e-3 * np.eye(n), factor.T @ posture.error)
    np.testing.assert_allclose(dq, expected, atol=1e-12)
    np.testing.assert_allclose(dq, qr, atol=1e-12)
    full = Level(rng.normal(size=(n, n)), rng.normal(size=n) * 0.01, np.ones(n))
    dq, qr = _steps([full, posture], lo, hi, [1e-6, 1e-3], normal_matrix(factor))
    np.testing.assert_array_equal(dq, qr)  # nothing left free: the levels above only, the same arithmetic


def test_without_a_normal_matrix_the_step_is_the_pivoted_qr_kernel_s_bit_for_bit(rng):
    n = 12
    levels = [Level(rng.normal(size=(4, n)), rng.normal(size=4), np.ones(4)),
              factor_level(rng.normal(size=n), np.zeros(n), posture_factor(rng.uniform(0.5, 2.0, n)))]
    lo, hi = -rng.uniform(0.0, 0.1, size=n), rng.uniform(0.0, 0.1, size=n)
    dq, qr = _steps(levels, lo, hi, [1e-6, 1e-3], np.zeros((0, n)))
    assert dq.tobytes() == qr.tobytes()


def test_only_a_well_conditioned_square_factor_takes_the_normal_equations(rng):
    n = 6
    full = _full_factor(rng, n)
    np.testing.assert_allclose(normal_matrix(full), full.T @ full, atol=1e-15)
    assert normal_matrix(full).flags.c_contiguous
    weights = rng.uniform(0.5, 2.0, n)
    np.testing.assert_allclose(normal_matrix(posture_factor(weights)), np.diag(weights), rtol=1e-15)
    weights[2] = 0.0  # a DOF the posture does not hold: rank-deficient, the pivoted QR's
    assert normal_matrix(posture_factor(weights)).shape == (0, n)
    singular = full.copy()
    singular[-1] = 0.0
    assert normal_matrix(singular).shape == (0, n)
    assert normal_matrix(_full_factor(rng, n, 10.0 / np.sqrt(WELL_CONDITIONED))).shape == (0, n)
    assert normal_matrix(full[:4]).shape == (0, n)
    not_finite = full.copy()
    not_finite[2, 3] = np.nan
    assert normal_matrix(not_finite).shape == (0, n)


def test_posture_rows_keep_the_pivoted_qr_without_a_normal_matrix_and_bound_only_a_full_factor(rng):
    """Built from three fields (as before the normal matrix): an empty normal matrix; a diagonal factor's normal
    matrix is diagonal, its share not bounded; a full one's bounded."""
    from gsik.kernels.control import POSTURE_SHARE, PostureRows, posture_rows

    n = 5
    assert PostureRows(np.zeros(n), np.zeros((0, n)), np.ones(1)).normal.shape[0] == 0
    assert posture_rows(None, np.zeros((0, n))).normal.shape == (0, n)
    diagonal = posture_rows(np.zeros(n), posture_factor(np.full(n, 2.0)))
    np.testing.assert_allclose(diagonal.normal, 2.0 * np.eye(n), rtol=1e-15, atol=0.0)
    assert diagonal.share[0] == 0.0
    full = _full_factor(rng, n)
    rows = posture_rows(np.ones(n), full)
    np.testing.assert_array_equal(rows.factor, full)
    np.testing.assert_allclose(rows.normal, full.T @ full, atol=1e-15)
    assert rows.share[0] == POSTURE_SHARE > 0.0
