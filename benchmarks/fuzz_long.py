"""The long fuzz run: the CI suite's fuzzing (tests/fuzz) at thousands of cases, with counts and figures.

    python benchmarks/fuzz_long.py [--files 2000] [--solver 5000] [--kills 200] [--frames 200000] [--seed 0]

Prints, per reader, how many mutated files were read, refused (a GsikError naming the file) and crashed (anything
else: must be 0); the solver's extreme-input calls and how many left a non-finite or out-of-limits pose (must be 0);
how many SIGKILLed saves left a torn file (must be 0) and what the next save left behind; the bombs' CPU time and
memory, each read in a fresh process; and the memory of reading a large BVH file. Exit status 1 if any count that
must be 0 is not.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))

import fuzzing  # noqa: E402  (the tests' fuzzing engine, shared on purpose)


def run_readers(n: int, seed: int) -> int:
    crashes = 0
    print(f"## Mutated files ({n} per reader, seed {seed})\n")
    print("| reader | read | refused | crashed | slowest [ms] |\n|---|---:|---:|---:|---:|")
    for kind in ("pose", "skeleton", "bvh", "urdf"):
        out = fuzzing.fuzz(kind, n, seed)
        crashes += len(out.crashes)
        print(f"| {kind} | {out.read} | {out.refused} | {len(out.crashes)} | {out.slowest * 1e3:.1f} |")
        for text, problem, exc in out.crashes[:3]:
            print(f"|   crash: {problem}: {str(exc)[:100]!r} | | | | |")
    return crashes


def run_solver(n: int, seed: int) -> int:
    print(f"\n## Solver on extreme input ({n} calls, seed {seed})\n")
    counts = fuzzing.fuzz_solver(n, seed)
    for key, value in counts.items():
        print(f"- {key}: {value}")
    return counts["poisoned"]


def run_kills(n: int, seed: int) -> int:
    """SIGKILL a forked writer ``n`` times mid-save; count torn files and what the next save leaves."""
    from gsik.io.files import atomic_write_text
    old, new = "old\n" * 100_000, "new\n" * 120_000
    rng = random.Random(seed)
    torn = 0
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "pose.yaml"
        atomic_write_text(path, old)
        left = []
        for _ in range(n):
            fuzzing.kill_during_saves(path, old, new, rng)
            torn += path.read_text() not in (old, new)
            left.append(sum(f.endswith(".tmp") for f in os.listdir(folder)))
        atomic_write_text(path, "done\n")
        after = sum(f.endswith(".tmp") for f in os.listdir(folder))
    print(f"\n## Killed saves\n\n- {n} saves killed with SIGKILL: {torn} torn files; temporary files present after a "
          f"kill: at most {max(left)} (each next save removes the dead writers'); after the final save: {after}")
    return torn + after


def run_bombs() -> int:
    code = f"import sys; sys.path.insert(0, {str(ROOT / 'tests' / 'fuzz')!r}); import fuzzing; fuzzing.print_bomb_figures()"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    if run.returncode != 0:
        last = (run.stderr.strip().splitlines() or [f"exit status {run.returncode}"])[-1]
        print(f"\n## Bombs\n\nthe bomb reader crashed: {last[:300]}")
        return 1
    figures = json.loads(run.stdout.strip().splitlines()[-1])
    print("\n## Bombs (a fresh process; CPU time, then tracemalloc peak in a second read)\n")
    print("| file | reader | CPU [ms] | traced peak [MB] | outcome |\n|---|---|---:|---:|---|")
    for b in figures["bombs"]:
        print(f"| {b['file']} | {b['reader']} | {b['cpu_s'] * 1e3:.1f} | {b['traced_peak_mb']:.2f} | "
              f"{b['outcome'][:70]} |")
    print(f"\nProcess peak RSS {figures['rss_peak_mb']:.0f} MB, growth while reading the bombs "
          f"{figures['rss_growth_mb']:.0f} MB.")
    return 0


def run_bvh_memory(frames: int) -> None:
    code = f"import sys; sys.path.insert(0, {str(ROOT / 'tests' / 'fuzz')!r}); import fuzzing; " \
           f"fuzzing.print_bvh_figures({frames})"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=900)
    f = json.loads(run.stdout.strip().splitlines()[-1])
    print(f"\n## A large BVH file\n\n- {f['frames']:,} frames x {f['channels']} channels, {f['file_mb']:.0f} MB of "
          f"text: parsed in {f['seconds']:.2f} s, peak memory growth {f['growth_mb']:.0f} MB "
          f"({f['growth_mb'] / f['file_mb']:.1f}x the file)")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", type=int, default=2000, help="mutated files per reader")
    ap.add_argument("--solver", type=int, default=5000, help="solver calls on extreme input")
    ap.add_argument("--kills", type=int, default=200, help="SIGKILLed saves")
    ap.add_argument("--frames", type=int, default=200_000, help="frames of the large BVH file")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(f"# gsik fuzz run ({time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.1f})\n")
    bad = run_readers(args.files, args.seed)
    if hasattr(fuzzing, "fuzz_solver"):
        bad += run_solver(args.solver, args.seed)
    if hasattr(os, "fork"):
        bad += run_kills(args.kills, args.seed)
    bad += run_bombs()
    run_bvh_memory(args.frames)
    print(f"\nmax RSS of this process: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
