"""numba's ``njit`` with a cache that works wherever gsik is installed, else a no-op decorator.

Kernels are compiled once and cached on disk. The cache goes, in numba's order, to ``$NUMBA_CACHE_DIR``, beside the
package (the ``__pycache__`` folders in ``gsik/``, where a regular install already holds kernels compiled while it
was built: see ``setup.py``), or under the user's home. When none of those can be written (a read-only install run
by a service account without a home), gsik caches in the temporary folder instead, and when even that fails it
compiles without a cache; either way it says so once, as a :class:`KernelCacheWarning`.

Without numba (or with ``NUMBA_DISABLE_JIT=1``) the kernels run as plain Python: the same results, far slower.
"""

from __future__ import annotations

import os
import tempfile
import warnings


class KernelCacheWarning(UserWarning):
    """The compiled-kernel cache is somewhere slower or less lasting than usual (said once per process)."""


try:
    from numba import njit as _numba_njit
    from numba.core import caching as _caching
except ImportError:  # pragma: no cover - exercised only without numba
    _numba_njit = None

_warned: set[str] = set()


def _warn_once(key: str, message: str) -> None:
    if key not in _warned:
        _warned.add(key)
        warnings.warn(message, KernelCacheWarning, stacklevel=3)


def temporary_cache_dir() -> str:
    """The per-user folder gsik caches kernels in when neither the package folder nor the home can be written."""
    return os.path.join(tempfile.gettempdir(), f"gsik-numba-cache-{os.getuid() if hasattr(os, 'getuid') else 'user'}")


if _numba_njit is not None:

    class _TemporaryCacheLocator(_caching._SourceFileBackedLocatorMixin, _caching._CacheLocator):
        """A per-user folder in the temporary folder: the last resort before no cache at all."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = os.path.join(temporary_cache_dir(), self.get_suitable_cache_subpath(py_file))

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            self = super().from_function(py_func, py_file)  # None where the folder cannot be written
            if self is not None:
                _warn_once("temp", "gsik: numba can write its cache neither beside the package nor under the home "
                                   f"folder; caching compiled kernels in {temporary_cache_dir()}")
            return self

    if _TemporaryCacheLocator not in _caching.CacheImpl._locator_classes:
        _caching.CacheImpl._locator_classes.append(_TemporaryCacheLocator)


def njit(*args, **kwargs):
    """``numba.njit`` (same arguments); ``cache=True`` falls back to no cache, with one warning, where none can be
    written."""
    if _numba_njit is None:  # pragma: no cover - exercised only without numba
        if len(args) == 1 and callable(args[0]) and not kwargs:
            return args[0]
        return lambda f: f
    if len(args) == 1 and callable(args[0]):
        return _compile(args[0], kwargs)
    return lambda f: _compile(f, kwargs)


def _compile(func, options: dict):
    try:
        return _numba_njit(**options)(func)
    except RuntimeError as exc:
        if not options.get("cache") or "no locator available" not in str(exc):
            raise
        _warn_once("none", f"gsik: no folder can hold numba's cache ({exc}); kernels compile at every start")
        return _numba_njit(**{**options, "cache": False})(func)


__all__ = ["KernelCacheWarning", "njit", "temporary_cache_dir"]
