"""Build hook: compile gsik's numba kernels while the package is built, so the first start needs no compilation.

Everything else about the package is in pyproject.toml. numba keys its cache on the source's content, the numba
version and the CPU, so the kernels compiled here (the build runs on the installing machine) are loaded at the first
start from the ``__pycache__`` folders in ``gsik/``; anywhere they do not match, numba compiles them as usual.
"""

import os
import subprocess
import sys
import time

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyCompilingKernels(build_py):
    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return  # an editable install compiles into the source tree's cache at first use
        # pip's build isolation finds the build requirements (numba, NumPy) through PYTHONPATH: keep it, after the
        # package just built, or a fresh venv's build cannot import NumPy and compiles nothing.
        inherited = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
        env = {**os.environ, "PYTHONPATH": os.pathsep.join([os.path.abspath(self.build_lib), *inherited])}
        env.pop("NUMBA_CACHE_DIR", None)
        env.pop("NUMBA_DISABLE_JIT", None)
        tell("gsik: compiling the solver's kernels (numba) while the package builds, so the first start needs no "
             "compilation: about 3 minutes on 2 cores (pip says 'still running' meanwhile)")
        start = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "gsik._warmup", "--quiet"], env=env, cwd=self.build_lib)
        if done.returncode != 0:
            tell("warning: gsik's kernels could not be compiled ahead; they will compile at first use")
        else:
            tell(f"gsik: kernels compiled in {time.monotonic() - start:.0f} s")


def tell(text: str) -> None:
    """Say ``text`` to the person installing, on their terminal if there is one.

    pip shows a build's output only with ``-v``: a plain ``pip install .`` would hide it behind "Building wheel ...
    still running". The build runs on the installer's controlling terminal, so ``/dev/tty`` reaches them whatever
    pip does with the output; without a terminal (a CI log) the text goes to stderr, which ``pip -v`` shows.
    """
    try:
        with open("/dev/tty", "w") as tty:
            tty.write(f"\n{text}\n")
    except OSError:
        print(text, file=sys.stderr, flush=True)


setup(cmdclass={"build_py": BuildPyCompilingKernels})
