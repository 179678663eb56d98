"""Walk benchmark: accuracy, continuity and cost of the root-swapping walk for several solver budgets.

For each budget (settings, solver steps per frame) the biped walks the same
plan; printed per budget: the largest joint jump at a root swap against the
median elsewhere, the stance-foot slide while it is the root, the footprint
error at each plant, the largest and 95th-percentile tracking error, sweeps
and wall time per frame. Markdown, for the README or a note.

Run: ``python benchmarks/bench_walk.py [--steps 8] [--fps 60]``.
Nothing here is asserted by the tests: timings on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gsik.anim.gait import WalkParameters, measure_walk, walk
from gsik.io.skeleton_yaml import load_skeleton
from gsik.solver import SolverSettings

#: (label, settings, solver steps per frame); the second is walk()'s default.
BUDGETS = (
    ("defaults, 1 step/frame", SolverSettings(), 1),
    ("defaults, 2 steps/frame", SolverSettings(), 2),
    ("defaults, 4 steps/frame", SolverSettings(), 4),
    ("paper PGS k=10, 1 step/frame", SolverSettings.paper(sweeps=10), 1),
    ("paper PGS k=20, 4 steps/frame", SolverSettings.paper(sweeps=20), 4),
    ("paper PGS k=20, 10 steps/frame", SolverSettings.paper(sweeps=20), 10),
)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=8, help="steps of the walk (default 8)")
    parser.add_argument("--fps", type=float, default=60.0, help="frames per second (default 60)")
    args = parser.parse_args(argv)
    sk = load_skeleton("biped")
    params = WalkParameters(n_steps=args.steps, fps=args.fps)
    walk(sk, WalkParameters(n_steps=1))  # compile the kernels before timing
    print(f"### Walk: biped, {params.n_steps} steps of {params.step_length} m at {params.cadence:g} steps/min, "
          f"{params.fps:g} fps\n")
    print("| solver | swap jump / median | stance slide (root) | footprint error | max / p95 tracking error "
          "| sweeps per frame | time per frame |")
    print("|---|---|---|---|---|---|---|")
    for label, settings, spf in BUDGETS:
        start = time.perf_counter()
        result = walk(sk, params, settings=settings, steps_per_frame=spf)
        elapsed = time.perf_counter() - start
        m = measure_walk(result)
        c = m.continuity
        p95 = float(np.percentile(result.position_errors.max(axis=1), 95))
        print(f"| {label} | {c.max_swap_jump * 1e3:.1f} / {c.median_jump * 1e3:.1f} mm ({c.ratio:.2f}x) "
              f"| {m.root_slide:.1e} m | {m.max_plant_error * 1e3:.3f} mm "
              f"| {m.max_tracking_error * 1e3:.2f} / {p95 * 1e3:.2f} mm | {m.mean_sweeps:.0f} "
              f"| {1e3 * elapsed / m.n_frames:.2f} ms |")


if __name__ == "__main__":
    main()
