"""gsik.kernels.settle: a posture settle step's two largest magnitudes, as NumPy's ``np.abs(x).max()``."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from gsik.kernels.settle import largest_pair

_VALUES = st.floats(allow_nan=True, allow_infinity=True, width=64)


@settings(deadline=None)  # the first example may compile a specialisation
@given(arrays(np.float64, st.integers(1, 40), elements=_VALUES), arrays(np.float64, st.integers(1, 40),
                                                                      elements=_VALUES))
def test_each_is_numpys_largest_magnitude_bit_for_bit_a_nan_included(step, moved):
    full, most = largest_pair(step, moved)
    for got, x in ((full, step), (most, moved)):
        expected = float(np.abs(x).max())
        assert np.isnan(got) if np.isnan(expected) else np.float64(got).tobytes() == np.float64(expected).tobytes()


def test_a_nan_anywhere_is_the_result_and_a_negative_zero_counts_as_zero():
    full, most = largest_pair(np.array([1.0, np.nan, 5.0]), np.array([-0.0, -0.0]))
    assert np.isnan(full)
    assert most == 0.0 and not np.signbit(most)
    assert largest_pair(np.array([-3.0, 2.0]), np.array([0.5, -0.75])) == (3.0, 0.75)
