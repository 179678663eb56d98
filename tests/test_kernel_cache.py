"""A cached kernel is recompiled when any kernel source of its package changes, not only its own file.

numba stamps a cached kernel with its own source file only: a caller would keep the compiled code of a callee from
another file after that file changed (a ``git pull`` in an editable checkout). Each case builds a tiny package that
compiles through gsik's ``njit``, runs it in a fresh process (numba reads its cache when a kernel is imported), edits
one file and runs it again in another fresh process.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

FILES = {
    "__init__.py": "",
    # UPPER_CASE constants are compiled into the kernels that use them.
    "constants.py": "SCALE = 2.0\n",
    # A plain module: kernels import a class from it, never compile it in.
    "plain.py": "class Label:\n    text = 'a'\n",
    "callee.py": """
        from gsik._jit import njit

        @njit(cache=True)
        def offset(x):
            return x + 1.0

        @njit(cache=True, inline="always")
        def inlined(x):
            return x * 10.0
        """,
    "caller.py": """
        from gsik._jit import njit
        from tinykernels.callee import inlined, offset
        from tinykernels.constants import SCALE
        from tinykernels.plain import Label

        @njit(cache=True)
        def scaled(x):
            return SCALE * offset(x) + inlined(x)
        """,
}
RUN = ("from tinykernels.caller import scaled; "
       "print(scaled(1.0), sum(scaled.stats.cache_hits.values()), sum(scaled.stats.cache_misses.values()))")


def _write(package: Path, name: str, text: str) -> None:
    (package / name).write_text(textwrap.dedent(text).lstrip())


@pytest.fixture
def package(tmp_path) -> Path:
    folder = tmp_path / "tinykernels"
    folder.mkdir()
    for name, text in FILES.items():
        _write(folder, name, text)
    return folder


def _scaled_of_one(package: Path) -> tuple[float, int, int]:
    """``scaled(1.0)``, cache hits, cache misses of the caller, in a new process that imports the package."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")} | {"PYTHONPATH": str(package.parent)}
    out = subprocess.run([sys.executable, "-c", RUN], capture_output=True, text=True, env=env, cwd=package.parent)
    assert out.returncode == 0, out.stderr[-2000:]
    value, hits, misses = out.stdout.split()
    return float(value), int(hits), int(misses)


def _edit(package: Path, name: str, old: str, new: str) -> None:
    path = package / name
    path.write_text(path.read_text().replace(old, new))


def test_caller_is_cached_and_then_loaded_from_the_cache(package):
    assert _scaled_of_one(package) == (2.0 * 2.0 + 10.0, 0, 1)
    assert _scaled_of_one(package) == (14.0, 1, 0)


@pytest.mark.parametrize("name, old, new, expected", [
    ("callee.py", "x + 1.0", "x + 3.0", 2.0 * 4.0 + 10.0),  # a called kernel in another file
    ("callee.py", "x * 10.0", "x * 20.0", 2.0 * 2.0 + 20.0),  # an inlined kernel in another file
    ("constants.py", "2.0", "5.0", 5.0 * 2.0 + 10.0),  # a constant compiled in, from a module without kernels
])
def test_changing_another_file_the_kernel_compiles_in_recompiles_it(package, name, old, new, expected):
    _scaled_of_one(package)  # compiled and cached
    _edit(package, name, old, new)
    assert _scaled_of_one(package) == (expected, 0, 1)
    assert _scaled_of_one(package) == (expected, 1, 0)


def test_changing_a_module_no_kernel_compiles_in_keeps_the_cache(package):
    _scaled_of_one(package)
    _edit(package, "plain.py", "'a'", "'b'")
    assert _scaled_of_one(package) == (14.0, 1, 0)
