"""A guard against a PySide6 6.12 bug on Python 3.11: ``None`` losing references.

PySide6-Essentials 6.12.0 on Python 3.11 drops one reference to ``None`` on
every call of a Qt method that returns nothing (``widget.update()``,
``label.setText()``, ``QApplication.processEvents()``, ...; measured here:
exactly -1 per call; 6.11.3 is fine). From Python 3.12 ``None`` is immortal
and the missing ``Py_INCREF`` is harmless, but on 3.11 its reference count
starts near 5,000, so after a few thousand such calls, seconds of a running
app, the interpreter aborts with "Fatal Python error: none_dealloc".

:func:`protect_none` makes ``None`` effectively immortal, as Python 3.12
does, by adding 2**40 to its reference count (checked with
``sys.getrefcount``; nothing is changed if the check fails). It only acts on
Python < 3.12 with PySide6 >= 6.12, and only once. The real fix is a PySide6
without the bug (or Python >= 3.12).
"""

from __future__ import annotations

import ctypes
import sys

_BOOST = 1 << 40
_applied = False


def affected() -> bool:
    """True when this interpreter and PySide6 have the bug (Python < 3.12, PySide6 >= 6.12)."""
    if sys.version_info >= (3, 12):
        return False
    try:
        import PySide6
    except ImportError:
        return False
    try:
        major, minor = (int(v) for v in PySide6.__version__.split(".")[:2])
    except ValueError:
        return True
    return (major, minor) >= (6, 12)


def protect_none() -> bool:
    """Apply the guard if needed; True when ``None`` is protected (or needs no protection)."""
    global _applied
    if _applied or not affected():
        return True
    before = sys.getrefcount(None)
    cell = ctypes.c_ssize_t.from_address(id(None))  # ob_refcnt: the first field of every PyObject
    if cell.value < before - 64 or cell.value > before + 64:
        return False  # not the layout we expect (e.g. a debug build): leave it alone
    cell.value += _BOOST
    if sys.getrefcount(None) - before < _BOOST - 64:
        cell.value -= _BOOST
        return False
    _applied = True
    return True
