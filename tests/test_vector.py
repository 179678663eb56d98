"""The weighted sum of rows in vector registers (gsik.kernels.vector): the loop it replaces, bit for bit, at every
width and tail; rows of weight 0 skipped; only the contiguous arrays it reads as such."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik._jit import njit
from gsik.kernels.rows import SUMS
from gsik.kernels.vector import combine_rows

numba = pytest.importorskip("numba")


@njit(cache=False, _nrt=False)
def _combined(w, X, out):
    combine_rows(w, X, out)


@njit(cache=False, _nrt=False, fastmath=SUMS)
def _loop(w, X, out):
    """The loop combine_rows replaces (range_space before it): a sweep a row, multiply-adds fused as SUMS fuses."""
    for i in range(w.shape[0]):
        if w[i] != 0.0:
            for c in range(out.shape[0]):
                out[c] += w[i] * X[i, c]


def _case(seed: int, k: int, m: int):
    rng = np.random.default_rng(seed)
    w = rng.normal(size=k) * (rng.random(k) < 0.7)  # some rows of weight 0
    X = rng.normal(size=(k + 2, m + 5)) * np.exp(rng.uniform(-5.0, 5.0, size=(k + 2, 1)))
    return w, X, rng.normal(size=m)


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(0, 40), st.integers(0, 70))
def test_it_is_the_loop_it_replaces_bit_for_bit(seed, k, m):
    """Every width (the four 8-wide registers' blocks of 32, the masked tail) and count of rows, ``X`` wider and
    taller than what is read: the same bits as the fused loop, and the sum to rounding."""
    w, X, start = _case(seed, k, m)
    out, ref = start.copy(), start.copy()
    _combined(w, X, out)
    _loop(w, X, ref)
    np.testing.assert_array_equal(out, ref)
    exact = start.astype(np.longdouble) + w.astype(np.longdouble) @ X[:k, :m].astype(np.longdouble)
    bound = 2.0 * (k + 1) * np.finfo(float).eps * (np.abs(start) + np.abs(w) @ np.abs(X[:k, :m]))
    assert np.all(np.abs(out - exact.astype(float)) <= bound)


def test_without_numba_it_is_the_same_sum():
    """The Python function (what runs with ``NUMBA_DISABLE_JIT``): the same sum, to rounding."""
    w, X, start = _case(7, 9, 37)
    out, ref = start.copy(), start.copy()
    combine_rows(w, X, out)
    _combined(w, X, ref)
    np.testing.assert_allclose(out, ref, rtol=1e-13, atol=1e-13)


def test_a_row_of_weight_zero_adds_nothing_not_even_its_nan():
    X = np.ones((3, 10))
    X[1, 4] = np.nan
    out = np.zeros(10)
    _combined(np.array([1.0, 0.0, 2.0]), X, out)
    np.testing.assert_array_equal(out, np.full(10, 3.0))
    _combined(np.array([1.0, 1.0, 2.0]), X, out)
    assert np.isnan(out[4]) and np.isfinite(np.delete(out, 4)).all()


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="nothing is compiled with NUMBA_DISABLE_JIT")
@pytest.mark.parametrize("layout", ["strided rows", "Fortran order"])
def test_an_array_it_cannot_read_as_contiguous_is_refused_when_compiled(layout):
    """Rows it would read past their stride: no compiled code at all, rather than wrong sums."""
    X = np.ones((4, 16))[:, ::2] if layout == "strided rows" else np.asfortranarray(np.ones((4, 8)))
    with pytest.raises(numba.core.errors.TypingError):
        _combined(np.ones(4), X, np.zeros(8))
