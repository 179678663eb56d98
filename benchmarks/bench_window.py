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

The studio also says when each start-up stage ended (``GSIK_STUDIO_TIMES``, see
:mod:`gsik_studio.starting`); the breakdown lists the seconds each stage took,
from the process's start to the first frame of the main window.

``--baseline DIR`` runs the same on other sources in the same run, interleaved
(for before/after figures): ``DIR`` is put first on ``PYTHONPATH`` and holds
``gsik_studio`` and ``gsik`` packages, e.g. links to ``app/`` and ``gsik/`` of
a ``git worktree`` of the older commit.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time

START_TITLE = "gsik studio — starting"
MAIN_TITLE = "— gsik studio"
#: The stages the studio marks, in order (gsik_studio.starting.mark), with what each covers.
STAGES = {
    "python and qt": "Python, gsik_studio, PySide6, QApplication",
    "start window": "start window shown",
    "view": "import PyVista, pyvistaqt (VTK), the 3D scene's modules",
    "solver": "import gsik + numba kernels, Document()",
    "kernels": "two solver steps",
    "window built": "MainWindow() (Qt widgets, 3D scene)",
    "first frame": "shown, first render",
}


def _visible(title: str) -> bool:
    done = subprocess.run(["xdotool", "search", "--onlyvisible", "--name", title], capture_output=True, text=True)
    return bool(done.stdout.strip())


def _read_marks(stream, t0: float, marks: dict, lines: list) -> None:
    """Collect ``gsik-studio-time <stage> <epoch>`` lines as ``{stage: seconds since t0}``; keep the rest."""
    for line in stream:
        if line.startswith("gsik-studio-time "):
            stage, _, when = line[len("gsik-studio-time "):].rpartition(" ")
            marks[stage] = float(when) - t0
        else:
            lines.append(line)


def time_to_windows(cache: str, timeout: float = 300.0, path: str | None = None
                    ) -> tuple[float, float, dict[str, float]]:
    """(seconds to the start window, seconds to the main window, ``{stage: seconds since start when it ended}``)
    for one new ``gsik-studio`` process (its sources first looked up in ``path`` when given)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, GSIK_STUDIO_TIMES="1")
    if path:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, (path, env.get("PYTHONPATH"))))
    marks: dict[str, float] = {}
    lines: list[str] = []
    with tempfile.TemporaryDirectory() as home:
        env["HOME"] = env["XDG_CONFIG_HOME"] = home  # no remembered window geometry or settings
        t0_epoch, t0 = time.time(), time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "gsik_studio"], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        reader = threading.Thread(target=_read_marks, args=(proc.stderr, t0_epoch, marks, lines), daemon=True)
        reader.start()
        first = main = None
        try:
            while main is None and time.perf_counter() - t0 < timeout and proc.poll() is None:
                if first is None and _visible(START_TITLE):
                    first = time.perf_counter() - t0
                if _visible(MAIN_TITLE):
                    main = time.perf_counter() - t0
                time.sleep(0.05)
            while "first frame" not in marks and proc.poll() is None and time.perf_counter() - t0 < timeout:
                time.sleep(0.05)
        finally:
            proc.terminate()
            proc.wait(timeout=30)
            reader.join(timeout=5)
    if main is None:
        raise NoWindow(f"no main window within {timeout:.0f} s (exit code {proc.returncode}): {''.join(lines)[-500:]}")
    return (first if first is not None else main), main, marks


class NoWindow(RuntimeError):
    """A studio process showed no main window."""


def timed_start(cache: str, path: str | None, attempts: int = 3) -> tuple[float, float, dict[str, float]]:
    """:func:`time_to_windows`, tried again (saying so on stderr) when a process shows no window: on a shared
    machine an X connection is now and then refused."""
    for attempt in range(1, attempts + 1):
        try:
            return time_to_windows(cache, path=path)
        except NoWindow as exc:
            print(f"bench_window: attempt {attempt} of {attempts} failed: {exc}", file=sys.stderr)
    raise SystemExit(f"bench_window: no main window in {attempts} attempts")


def breakdown(runs: list[dict[str, float]]) -> list[tuple[str, float]]:
    """Median seconds each stage took (from the end of the one before; the first from the process's start)."""
    out, before = [], 0.0
    for stage in STAGES:
        ends = [r[stage] for r in runs if stage in r]
        if not ends:
            continue
        end = statistics.median(ends)
        out.append((stage, end - before))
        before = end
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--baseline", metavar="DIR", help="also time the sources in DIR (see the docstring)")
    args = p.parse_args()
    if not os.environ.get("DISPLAY") or shutil.which("xdotool") is None:
        sys.exit("bench_window needs an X display (xvfb-run) and xdotool (see the docstring)")
    trees = {"": None} if not args.baseline else {"baseline, ": args.baseline, "this tree, ": None}
    runs = {(tree, case): [] for tree in trees for case in ("cold", "warm")}
    loads = []
    for _ in range(args.repeats):
        for tree, path in trees.items():
            cache = tempfile.mkdtemp(prefix="gsik-numba-")
            try:
                for case in ("cold", "warm"):  # warm: with the cache the cold run wrote
                    loads.append(os.getloadavg()[0])
                    runs[tree, case].append(timed_start(cache, path))
            finally:
                shutil.rmtree(cache, ignore_errors=True)
    print(f"gsik-studio time to window, median of {args.repeats} (load {statistics.median(loads):.1f}, "
          f"from {min(loads):.1f} to {max(loads):.1f}):")
    label = {"cold": "cold (kernels compile)", "warm": "warm (cached kernels) "}
    cases = [(f"{tree}{label[case]}", r) for (tree, case), r in runs.items()]
    for name, runs in cases:
        first = statistics.median(r[0] for r in runs)
        ready = statistics.median(r[1] for r in runs)
        print(f"  {name}: start window {first:5.1f} s, main window {ready:5.1f} s")
    for name, runs in cases:
        print(f"  breakdown, {name.strip()} (seconds per stage, median):")
        for stage, seconds in breakdown([r[2] for r in runs]):
            print(f"    {stage:<13} {seconds:5.2f} s  {STAGES[stage]}")


if __name__ == "__main__":
    main()
