"""First start after install versus a warm start: seconds from a fresh interpreter to the first solved pose.

Builds the package as ``pip install .`` does (kernels compiled while it is built, see ``setup.py``), installs it into
fresh folders and times, in new processes with a fresh home and no ``NUMBA_*`` settings:

- ``first start``: the first process after install;
- ``warm start``: the next process, with the cache the first one found or wrote;
- the same two with the compiled kernels removed from the install, which is what a first start cost before the build
  compiled them.

Usage: ``python benchmarks/bench_startup.py [--repeats 3]``. Prints medians over the repeats.
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
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# A crouch as in the README: pelvis, head and a hand 7 cm down (hands position-only: the biped has no wrists).
FIRST_SOLVE = ("import sys; sys.path.insert(0, {site!r}); import gsik; "
               "s = gsik.Solver(gsik.load_skeleton('biped')); "
               "t = {{n: gsik.Target.from_transform(T) for n, T in s.effector_poses().items()}}; "
               "t.update({{n: t[n].replace(position=t[n].position - [0.0, 0.0, 0.07]) for n in ('pelvis', 'head', 'right_hand')}}); "
               "t.update({{n: t[n].replace(position_only=True) for n in ('left_hand', 'right_hand')}}); "
               "assert s.solve(t).converged")


def _start_seconds(site: Path, home: Path) -> float:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")} | {"HOME": str(home)}
    start = time.perf_counter()
    subprocess.run([sys.executable, "-I", "-c", FIRST_SOLVE.format(site=str(site))], check=True, env=env, cwd=home)
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(tmp / "wheel"), str(ROOT)],
                       check=True)
        build = time.perf_counter() - t0
        wheel = next((tmp / "wheel").glob("*.whl"))
        rows = {}
        for label, keep_kernels in (("kernels compiled at install (now)", True), ("no kernels in the install (before)", False)):
            first, warm = [], []
            for r in range(args.repeats):
                site, home = tmp / f"site-{label[:2]}-{r}", tmp / f"home-{label[:2]}-{r}"
                home.mkdir()
                subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(site),
                                str(wheel)], check=True)
                if not keep_kernels:
                    for f in (site / "gsik").rglob("*.nb[ic]"):
                        f.unlink()
                first.append(_start_seconds(site, home))
                warm.append(_start_seconds(site, home))
                shutil.rmtree(site)
            rows[label] = (statistics.median(first), statistics.median(warm))
    print(f"conditions: load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores, medians of {args.repeats}; "
          f"wheel build (includes compiling the kernels): {build:.1f} s")
    print(f"{'install':38s} {'first start [s]':>16s} {'warm start [s]':>15s} {'first / warm':>13s}")
    for label, (first, warm) in rows.items():
        print(f"{label:38s} {first:16.2f} {warm:15.2f} {first / warm:12.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
