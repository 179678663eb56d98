"""Row-view helpers of the strict-priority kernel (:mod:`gsik.kernels.priority`): dots, sweeps and a Householder
reflection over rows of 2-d arrays, each a counted loop over 1-d views.

LLVM vectorises those loops (sweeps) or pipelines them (dots in four sums). Hand-unrolled ``while`` loops measured
40 ns a call whatever the length, and loops indexing the 2-d arrays about twice the views' time, at the kernel's
lengths (tens).
"""

from __future__ import annotations

from gsik._jit import njit

#: The floating-point freedom of :func:`dot_sum` and the kernels that sum as it does: sums reassociated (LLVM
#: vectorises the reduction) and multiplies fused into adds. Nothing is assumed about NaN or infinity, so the
#: kernels' finiteness checks hold. Only for kernels that call no other module's kernel: numba compiles a callee
#: that sets no ``fastmath`` with its caller's, so a shared kernel would round as whoever compiled it first.
SUMS = {"reassoc", "contract"}


@njit(cache=True, inline="always")
def dot1(X, i, x, start, stop):
    """``X[i, start:stop] @ x[start:stop]``."""
    return dot_views(X[i, start:stop], x[start:stop])


@njit(cache=True, inline="always")
def dot(X, i, Y, j, start, stop):
    """``X[i, start:stop] @ Y[j, start:stop]``."""
    return dot_views(X[i, start:stop], Y[j, start:stop])


@njit(cache=True, inline="always")
def dot_views(a, b):
    """``a @ b`` (views of one length) in four sums: one chain of dependent adds would bound it."""
    n = a.shape[0]
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    for t in range(n // 4):
        d = 4 * t
        s0 += a[d] * b[d]
        s1 += a[d + 1] * b[d + 1]
        s2 += a[d + 2] * b[d + 2]
        s3 += a[d + 3] * b[d + 3]
    for d in range(n - n % 4, n):
        s0 += a[d] * b[d]
    return (s0 + s1) + (s2 + s3)


@njit(cache=True, inline="always", fastmath=SUMS)
def dot_sum(a, b):
    """``a @ b`` ((n,) views) as one plain sum, which :data:`SUMS` lets LLVM vectorise: ~2.5x faster than
    :func:`dot_views` at 30 in a kernel compiled with :data:`SUMS` (the four sums keep LLVM from vectorising);
    the last bits depend on the machine's vector width."""
    s = 0.0
    for d in range(a.shape[0]):
        s += a[d] * b[d]
    return s


@njit(cache=True, inline="always")
def axpy(X, i, a, Y, j, start, stop):
    """``X[i, start:stop] += a * Y[j, start:stop]``."""
    add(X[i, start:stop], a, Y[j, start:stop])


@njit(cache=True, inline="always")
def axpy1(x, a, Y, j, start, stop):
    """``x[start:stop] += a * Y[j, start:stop]``."""
    add(x[start:stop], a, Y[j, start:stop])


@njit(cache=True, inline="always")
def rank1(X, i, a, w, start, stop):
    """``X[i, start:stop] += a * w[start:stop]``."""
    add(X[i, start:stop], a, w[start:stop])


@njit(cache=True, inline="always")
def add(x, a, y):
    """``x += a * y`` (views of one length)."""
    for d in range(x.shape[0]):
        x[d] += a * y[d]


@njit(cache=True, inline="always")
def reflect(X, r0, v, vj, beta, first, stop, start, end, w):
    """Rows ``r0 + first ... r0 + stop - 1`` of ``X`` times ``I - beta v v^T`` from the left, in columns
    ``start:end`` (``v = V[vj, first:stop]``, ``w`` (end,) scratch): ``w = v^T X``, then ``X -= beta v w``, both
    sweeps over contiguous rows."""
    for c in range(start, end):
        w[c] = 0.0
    for i in range(first, stop):
        if v[vj, i] != 0.0:  # a zero adds exactly nothing
            axpy1(w, v[vj, i], X, r0 + i, start, end)
    for i in range(first, stop):
        if v[vj, i] != 0.0:
            rank1(X, r0 + i, -beta * v[vj, i], w, start, end)
