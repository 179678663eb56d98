"""numba's ``njit`` when numba is installed, else a no-op decorator.

Without numba (or with ``NUMBA_DISABLE_JIT=1``) the kernels run as plain
Python: the same results, far slower.
"""

from __future__ import annotations

try:
    from numba import njit
except ImportError:  # pragma: no cover - exercised only without numba

    def njit(*args, **kwargs):
        if len(args) == 1 and callable(args[0]) and not kwargs:
            return args[0]
        return lambda f: f


__all__ = ["njit"]
