"""Row-view helpers of the kernels (gsik.kernels.rows): each sum is the dot product to rounding, whatever its order."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gsik.kernels.rows import dot_sum, dot_views


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 70), st.integers(0, 2**32 - 1))
def test_the_sums_are_the_dot_product_within_its_rounding_bound(n, seed):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=n) * np.exp(rng.uniform(-20.0, 20.0, size=n))
    b = rng.normal(size=n)
    exact = float(np.sum(a.astype(np.longdouble) * b.astype(np.longdouble)))
    bound = 2.0 * n * np.finfo(float).eps * float(np.abs(a * b).sum())  # any order of the sum stays within it
    assert abs(dot_sum(a, b) - exact) <= bound
    assert abs(dot_views(a, b) - exact) <= bound
