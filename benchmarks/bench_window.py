"""Time to window: seconds from starting ``gsik-studio`` until a window is on the X display, cold and warm.

    xvfb-run -a -s "-screen 0 1600x1100x24" python benchmarks/bench_window.py [--repeats 3]

Starts ``python -m gsik_studio`` as a new process and watches the X display with
``xdotool search --onlyvisible`` (Debian package ``xdotool``) for

- the start window (title "gsik studio — starting"), which says what is loading, and
- the main window (title "… — gsik studio"), ready to drag.

Two cases, each a fresh process: ``cold`` with an empty numba cache
(``NUMBA_CACHE_DIR`` a new folder: the kernels compile on first use, as after an
editable install or when the cache does not match), and ``warm`` with the cache the
cold run wrote. A regular ``pip install .`` compiles the kernels while it builds the
package (``setup.py``), so its first start is the warm case. Prints medians.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

START_TITLE = "gsik studio — starting"
MAIN_TITLE = "— gsik studio"


def _visible(title: str) -> bool:
    done = subprocess.run(["xdotool", "search", "--onlyvisible", "--name", title], capture_output=True, text=True)
    return bool(done.stdout.strip())


def time_to_windows(cache: str, timeout: float = 300.0) -> tuple[float, float]:
    """(seconds to the start window, seconds to the main window) for one new ``gsik-studio`` process."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    with tempfile.TemporaryDirectory() as home:
        env["HOME"] = env["XDG_CONFIG_HOME"] = home  # no remembered window geometry or settings
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "gsik_studio"], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        first = main = None
        try:
            while main is None and time.perf_counter() - t0 < timeout and proc.poll() is None:
                if first is None and _visible(START_TITLE):
                    first = time.perf_counter() - t0
                if _visible(MAIN_TITLE):
                    main = time.perf_counter() - t0
                time.sleep(0.05)
        finally:
            proc.terminate()
            err = proc.communicate(timeout=30)[1]
    if main is None:
        raise SystemExit(f"no main window within {timeout:.0f} s (exit code {proc.returncode}): {err[-500:]}")
    return (first if first is not None else main), main


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=3)
    args = p.parse_args()
    if not os.environ.get("DISPLAY") or shutil.which("xdotool") is None:
        sys.exit("bench_window needs an X display (xvfb-run) and xdotool (see the docstring)")
    cold, warm = [], []
    for _ in range(args.repeats):
        cache = tempfile.mkdtemp(prefix="gsik-numba-")
        try:
            cold.append(time_to_windows(cache))
            warm.append(time_to_windows(cache))
        finally:
            shutil.rmtree(cache, ignore_errors=True)
    load = os.getloadavg()[0]
    print(f"gsik-studio time to window, median of {args.repeats} (load {load:.1f}):")
    for name, runs in (("cold (kernels compile)", cold), ("warm (cached kernels) ", warm)):
        first = statistics.median(r[0] for r in runs)
        ready = statistics.median(r[1] for r in runs)
        print(f"  {name}: start window {first:5.1f} s, main window {ready:5.1f} s")


if __name__ == "__main__":
    main()
