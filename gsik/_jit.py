"""numba's ``njit`` with a cache that works wherever gsik is installed, else a no-op decorator.

Kernels are compiled once and cached on disk. The cache goes, in numba's order, to ``$NUMBA_CACHE_DIR``, beside the
package (the ``__pycache__`` folders in ``gsik/``, where a regular install already holds kernels compiled while it
was built: see ``setup.py``), or under the user's home. When none of those can be written (a read-only install run
by a service account without a home), gsik caches in the temporary folder instead, and when even that fails it
compiles without a cache; either way it says so once, as a :class:`KernelCacheWarning`.

numba checks a cached kernel only against its own source file, so a kernel that calls (or inlines) a kernel from
another file would keep the old compiled callee after only the callee's file changed (a ``git pull`` in an editable
checkout). A kernel compiled through :func:`njit` is therefore stamped with a hash of every file of its package that
holds jitted code (a file that imports ``njit`` or numba) and of the package's modules those files import (constants
compiled in): any change to any of them invalidates every kernel of the package. The hash is computed once per
process, at the first kernel's import; the files are the same in the build folder and the install, so the kernels
compiled while a regular install was built stay hits.

Without numba (or with ``NUMBA_DISABLE_JIT=1``) the kernels run as plain Python: the same results, far slower.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import sys
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


def _has_nrt_option() -> bool:
    """True if this numba takes the private ``_nrt`` option (``_nrt=False``: a kernel that allocates nothing skips
    the reference counts of the arrays it is given; :mod:`gsik.kernels.kinematics`)."""
    try:
        from numba.core.cpu import CPUTargetOptions
    except ImportError:  # pragma: no cover - a numba whose options moved
        return False
    return hasattr(CPUTargetOptions, "_nrt")


_NRT_OPTION = _numba_njit is not None and _has_nrt_option()


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

    def _package_stamped(base: type) -> type:
        """``base``, numba's locator, for gsik's kernels only: the same folder, and a stamp that also covers the
        package's kernel sources (:func:`package_sources_digest`)."""

        class PackageStamped(base):
            @classmethod
            def from_function(cls, py_func, py_file):
                digest = _package_digest_of(py_func, py_file)
                if digest is None:
                    return None  # not compiled through gsik's njit, or not in a package: numba's own locators
                self = super().from_function(py_func, py_file)
                if self is not None:
                    self._package_digest = digest
                return self

            def get_source_stamp(self):
                return super().get_source_stamp(), self._package_digest

        PackageStamped.__name__ = PackageStamped.__qualname__ = f"PackageStamped{base.__name__}"
        return PackageStamped

    # Before numba's own, in numba's order (NUMBA_CACHE_DIR, beside the package, the home, the temporary folder).
    _caching.CacheImpl._locator_classes[:0] = [
        _package_stamped(base) for base in (_caching.UserProvidedCacheLocator, _caching.InTreeCacheLocator,
                                            _caching.UserWideCacheLocator, _TemporaryCacheLocator)]

_KERNEL_MARK = "_gsik_package_stamped"
# A file that holds jitted code imports gsik's njit (or numba); the modules it imports may hold constants it compiles.
_USES_JIT = re.compile(rb"^[ \t]*(?:from[ \t]+[\w.]*(?:\b_jit|\bnumba)\b[\w.]*[ \t]+import\b|import[ \t]+numba\b)",
                       re.M)
_FROM_IMPORT = re.compile(rb"^[ \t]*from[ \t]+(\.*[\w.]*)[ \t]+import[ \t]+(\([^)]*\)|[^\n]*(?:\\\n[^\n]*)*)", re.M)
_PLAIN_IMPORT = re.compile(rb"^[ \t]*import[ \t]+([\w.]+(?:[ \t]*,[ \t]*[\w.]+)*)", re.M)


def _package_digest_of(py_func, py_file: str) -> str | None:
    """The digest of the kernel sources of ``py_func``'s top-level package, or ``None`` where it has none (a
    function not compiled through :func:`njit`, a script's function, a file outside its package's folder)."""
    if not getattr(py_func, _KERNEL_MARK, False):
        return None
    package = sys.modules.get(py_func.__module__.partition(".")[0])
    if getattr(package, "__path__", None) is None or not getattr(package, "__file__", None):
        return None
    root = os.path.dirname(os.path.abspath(package.__file__))
    if not os.path.abspath(py_file).startswith(root + os.sep):
        return None
    return package_sources_digest(root)


@functools.lru_cache(maxsize=None)
def package_sources_digest(root: str) -> str:
    """SHA-256 (hex) of the package in folder ``root``: the relative path and bytes of each ``.py`` file that holds
    jitted code, and of each module of the package such a file imports. Computed once per folder and process."""
    texts = {}
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d != "__pycache__" and not d.startswith(".")]
        for name in files:
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                with open(path, "rb") as f:
                    texts[path[len(root) + 1:]] = f.read()
    kernels = {path for path, text in texts.items() if (b"_jit" in text or b"numba" in text) and _USES_JIT.search(text)}
    covered = kernels | {dep for path in kernels for dep in _imported_files(path, texts[path], root) if dep in texts}
    digest = hashlib.sha256()
    for path in sorted(covered):
        digest.update(path.replace(os.sep, "/").encode() + b"\0" + texts[path] + b"\0")
    return digest.hexdigest()


def _imported_files(path: str, text: bytes, root: str) -> set[str]:
    """The files, relative to the package folder ``root`` (some may not exist), of the modules of its own package
    that ``text``, the source at ``path`` (relative to ``root``), imports, or imports constants from (an UPPER_CASE
    name): what jitted code in ``text`` can compile in. A class or function imported from a plain module is not
    compiled in (numba compiles only jitted functions, and checks a type by its signature)."""
    top, here = os.path.basename(root), [p for p in os.path.dirname(path).split(os.sep) if p]
    modules = []  # each a module's path inside the package, as a list of names
    for module, names in _FROM_IMPORT.findall(text):
        module = module.decode()
        name = module.lstrip(".")
        dots = len(module) - len(name)
        if dots:
            if dots - 1 > len(here):
                continue
            parts = here[:len(here) - (dots - 1)] + [p for p in name.split(".") if p]
        elif name.split(".")[0] == top:
            parts = name.split(".")[1:]
        else:
            continue
        names = [n for n in re.findall(r"\w+", names.decode()) if n != "as"]
        modules += [parts + [n] for n in names]  # a submodule
        if any(n.isupper() for n in names):  # a constant, which numba compiles in (a class or function is not)
            modules.append(parts)
    for dotted in _PLAIN_IMPORT.findall(text):
        modules += [m.split(".")[1:] for m in re.findall(r"[\w.]+", dotted.decode()) if m.split(".")[0] == top]
    files = set()
    for parts in modules:
        files.add(os.path.join(*parts, "__init__.py"))
        if parts:
            files.add(os.path.join(*parts[:-1], parts[-1] + ".py"))
    return files


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


def python_function(kernel):
    """The plain Python function behind ``kernel`` (a kernel itself without numba or with ``NUMBA_DISABLE_JIT``):
    for sizes worked out at set-up, where compiling would cost more than the call."""
    return getattr(kernel, "py_func", kernel)


def _compile(func, options: dict):
    if options.get("cache"):
        setattr(func, _KERNEL_MARK, True)  # stamped with the package's kernel sources (see the module's docstring)
    if not _NRT_OPTION:  # a private option numba may drop: the same results, reference counted
        options = {k: v for k, v in options.items() if k != "_nrt"}
    try:
        return _numba_njit(**options)(func)
    except RuntimeError as exc:
        if not options.get("cache") or "no locator available" not in str(exc):
            raise
        _warn_once("none", f"gsik: no folder can hold numba's cache ({exc}); kernels compile at every start")
        return _numba_njit(**{**options, "cache": False})(func)


__all__ = ["KernelCacheWarning", "njit", "python_function", "temporary_cache_dir"]
