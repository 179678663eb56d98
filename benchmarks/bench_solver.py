"""Solver benchmarks: the paper's Table 1, tracking and reach. Prints Markdown for the README.

    python benchmarks/bench_solver.py [--quick]
"""

import sys

from gsik.benchmark import report

if __name__ == "__main__":
    quick = "--quick" in sys.argv
    print(report(repeats=500 if quick else 3000, frames=120 if quick else 600, problems=50 if quick else 1000))
