"""Time and memory of refusing each hostile file (tests/fuzz/hostile.py), each in a fresh process.

    python benchmarks/bench_hostile.py [--only SUBSTRING]

For every case: the reader, the wall and CPU time of the refusal, the peak of Python's allocations during it
(tracemalloc, a second read) and the growth of the process's peak resident size over a baseline taken after the
imports (the figure the issue bounds: refused within 2 s and 200 MB above baseline). Prints a table, then the worst
of each column; exit status 1 if a case was not refused with a GsikError or went past either bound.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))

import hostile  # noqa: E402  (the tests' hostile files, shared on purpose)

#: The issue's bounds on a refusal.
MAX_SECONDS = 2.0
MAX_GROWTH_MB = 200.0

_MEASURE = """
import json, resource, sys, time, tracemalloc
sys.path.insert(0, {fuzz!r})
import gsik, hostile
reader, path = sys.argv[1], sys.argv[2]
hostile.readers()  # imports every reader first: the baseline holds them
baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
wall, cpu = time.perf_counter(), time.process_time()
exc = hostile.refusal(reader, path)
wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
growth = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - baseline) / 1024
tracemalloc.start()
hostile.refusal(reader, path)
peak = tracemalloc.get_traced_memory()[1] / 2**20
print(json.dumps(dict(wall=wall, cpu=cpu, growth_mb=growth, traced_mb=peak, refused=isinstance(exc, gsik.GsikError),
                      message=str(exc)[:100])))
"""


def issue_cases(folder: Path) -> list[hostile.Case]:
    """The issue's own sizes (tens of MB on disk): written here, not in the tests."""
    files = {"star_1M.bvh": ("bvh", hostile._star(1_000_000)), "deep_100k.bvh": ("bvh", hostile._deep(100_000)),
             "chain_100k.urdf": ("urdf", hostile._urdf_chain(100_000))}
    out = []
    for name, (reader, text) in files.items():
        (folder / name).write_text(text)
        out.append(hostile.Case(name, reader, str(folder / name), "the limit is"))
    return out


def measure(case: hostile.Case) -> dict:
    """One case's figures, from a fresh interpreter."""
    code = _MEASURE.format(fuzz=str(ROOT / "tests" / "fuzz"))
    run = subprocess.run([sys.executable, "-c", code, case.reader, case.path], capture_output=True, text=True,
                         timeout=600)
    if run.returncode != 0:
        return dict(wall=float("nan"), cpu=float("nan"), growth_mb=float("nan"), traced_mb=float("nan"),
                    refused=False, message=run.stderr.strip().splitlines()[-1][:100])
    return json.loads(run.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", default="", help="run only the cases whose name holds this text")
    parser.add_argument("--issue-sizes", action="store_true", help="also the issue's full-size files: a 42 MB "
                        "BVH star of 1,000,000 joints, a BVH and a URDF 100,000 deep")
    args = parser.parse_args()
    failed = 0
    worst = dict(wall=0.0, cpu=0.0, growth_mb=0.0, traced_mb=0.0)
    with tempfile.TemporaryDirectory() as folder:
        cases = hostile.make_cases(folder) + (issue_cases(Path(folder)) if args.issue_sizes else [])
        cases = [c for c in cases if args.only in c.name]
        print(f"{'case':34} {'reader':9} {'wall s':>7} {'cpu s':>7} {'RSS +MB':>8} {'traced MB':>9}  refusal")
        for case in cases:
            f = measure(case)
            ok = f["refused"] and f["wall"] <= MAX_SECONDS and f["growth_mb"] <= MAX_GROWTH_MB
            failed += not ok
            for k in worst:
                worst[k] = max(worst[k], f[k])
            print(f"{case.name[:34]:34} {case.reader:9} {f['wall']:7.3f} {f['cpu']:7.3f} {f['growth_mb']:8.1f} "
                  f"{f['traced_mb']:9.1f}  {'' if ok else 'FAILED '}{f['message'][:60]}")
    print(f"\n{len(cases)} cases; worst: wall {worst['wall']:.3f} s, cpu {worst['cpu']:.3f} s, RSS growth "
          f"{worst['growth_mb']:.1f} MB, traced {worst['traced_mb']:.1f} MB (bounds: {MAX_SECONDS} s, "
          f"{MAX_GROWTH_MB:.0f} MB); {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
