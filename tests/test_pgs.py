"""Projected Gauss-Seidel on its own: it solves bounded SPD systems and never leaves the box."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.pgs import projected_gauss_seidel, solve_bounded


def spd(rng, n, cond=100.0):
    Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return Q @ np.diag(np.geomspace(1.0, 1.0 / cond, n)) @ Q.T


def kkt_violation(A, b, x, lo, hi):
    g = A @ x - b  # gradient of 0.5 x^T A x - b^T x
    free = (x > lo + 1e-12) & (x < hi - 1e-12)
    v = np.abs(g[free]).max(initial=0.0)
    v = max(v, np.clip(-g[x <= lo + 1e-12], 0, None).max(initial=0.0))  # at lower bound: g >= 0
    v = max(v, np.clip(g[x >= hi - 1e-12], 0, None).max(initial=0.0))  # at upper bound: g <= 0
    return v


def test_unbounded_pgs_converges_to_the_linear_solution():
    rng = np.random.default_rng(0)
    A = spd(rng, 12, cond=10)
    b = rng.normal(size=12)
    x, info = projected_gauss_seidel(A, b, sweeps=500)
    np.testing.assert_allclose(x, np.linalg.solve(A, b), atol=1e-8)
    assert info.sweeps < 500  # stopped by a tolerance test, not the limit


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 30))
@settings(max_examples=100, deadline=None)
def test_pgs_never_leaves_the_box_and_meets_kkt(seed, n):
    rng = np.random.default_rng(seed)
    A = spd(rng, n, cond=20)
    b = rng.normal(size=n) * 3
    lo = -rng.uniform(0, 1, n)
    hi = rng.uniform(0, 1, n)
    x0 = rng.normal(size=n) * 5  # even a start far outside the box
    for sweeps in (1, 3, 2000):
        x, _ = projected_gauss_seidel(A, b, lo, hi, x0=x0, sweeps=sweeps)
        assert np.all(x >= lo) and np.all(x <= hi)
    assert kkt_violation(A, b, x, lo, hi) < 1e-6


@given(seed=st.integers(0, 2**32 - 1))
@settings(max_examples=100, deadline=None)
def test_subspace_solve_is_exact_on_ill_conditioned_systems(seed):
    rng = np.random.default_rng(seed)
    n = 30
    A = spd(rng, n, cond=1e6)
    b = rng.normal(size=n)
    lo, hi = -np.full(n, 0.5), np.full(n, 0.5)
    x, _ = solve_bounded(A, b, lo, hi)
    assert np.all(x >= lo) and np.all(x <= hi)
    assert kkt_violation(A, b, x, lo, hi) < 1e-8


def test_termination_tests_each_stop_the_sweeps():
    rng = np.random.default_rng(3)
    A = spd(rng, 10, cond=10)
    b = rng.normal(size=10)
    _, info = projected_gauss_seidel(A, b, sweeps=7, residual_tolerance=0, update_tolerance=0)
    assert info.sweeps == 7  # test 1: the iteration limit
    _, info = projected_gauss_seidel(A, b, sweeps=1000, residual_tolerance=1e-3, update_tolerance=0)
    assert info.sweeps < 1000 and info.residual < 1e-3  # test 2: |Ax - b|
    _, info = projected_gauss_seidel(A, b, sweeps=1000, residual_tolerance=0, update_tolerance=1e-4)
    assert info.sweeps < 1000 and info.update < 1e-4  # test 3: |dx|
    x_prev = np.linalg.solve(A, b)
    _, info = projected_gauss_seidel(A, b, x0=x_prev, x_prev=x_prev, sweeps=1000, residual_tolerance=0,
                                     update_tolerance=0, stall_tolerance=1e-6)
    assert info.sweeps == 1  # test 4: the same answer as the previous frame
