"""Dense Cholesky pieces over a block ``[a:b]`` of a square matrix: the factor in place and its two triangular solves.
The range-space step's (:mod:`gsik.kernels.range_space`, :mod:`gsik.kernels.range_posture`) Gram matrices, a level's
Schur complement and the posture's ``C H^-1 C^T``.

They sum as :func:`gsik.kernels.rows.dot_sum` (:data:`~gsik.kernels.rows.SUMS`) and call no other module's kernel.
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels.rows import SUMS, dot_sum


@njit(cache=True, _nrt=False, fastmath=SUMS)
def forward(F, a, b, x):
    """``x[a:b] = F[a:b, a:b]^-1 x[a:b]`` (lower triangular)."""
    for i in range(a, b):
        x[i] = (x[i] - dot_sum(F[i, a:i], x[a:i])) / F[i, i]


@njit(cache=True, _nrt=False, fastmath=SUMS)
def backward(F, a, b, x):
    """``x[a:b] = F[a:b, a:b]^-T x[a:b]``."""
    for i in range(b - 1, a - 1, -1):
        s = x[i]
        for j in range(i + 1, b):
            s -= F[j, i] * x[j]
        x[i] = s / F[i, i]


@njit(cache=True, _nrt=False, fastmath=SUMS)
def factor(A, a, b, least):
    """``A[a:b, a:b]`` (lower triangle read) replaced by its Cholesky factor; False if a pivot is not above
    ``least``."""
    for j in range(a, b):
        d = A[j, j] - dot_sum(A[j, a:j], A[j, a:j])
        if not d > least * least:
            return False
        d = math.sqrt(d)
        A[j, j] = d
        for i in range(j + 1, b):
            A[i, j] = (A[i, j] - dot_sum(A[i, a:j], A[j, a:j])) / d
    return True
