"""Where a warm controlled solve()'s work goes: steps and strict-priority solves a frame, on bench_drag's drags.

Each controlled path of ``bench_drag.py`` (posture with the hands at 0, pins, the studio's prior), one warm
``solve()`` a frame, run through the controller's Python branches (``Controller.compiled_step = False``: the same
steps as the compiled call, bit for bit, ``tests/test_fallback_kernels.py``), which count: steps (linearisations),
strict-priority solves (a step's full step, and every restoring step, target levels' step alone and correction of its
fallback), trials (forward kinematics and level state). With ``Controller.settle_refusals`` on (a solve()'s worse
step that settles the posture refused without retries, one restoring step) and off (the solve before that change).
Counts, not times: they do not depend on the machine's load.

Run: ``python benchmarks/bench_solve_work.py [--frames 150]``.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import bench_drag

import gsik.control

COUNTED = {"_first_trial": "steps", "_linearise": "fallback solves", "_trial": "fallback trials"}


def count(frames: int) -> dict:
    """``{path: {settle_refusals: {what: per frame}}}`` over ``frames`` frames of each controlled path."""
    counts = collections.Counter()
    controller = gsik.control.Controller
    originals = {name: getattr(controller, name) for name in COUNTED}

    def counting(name):
        def counted(self, *args):
            counts[COUNTED[name]] += 1
            return originals[name](self, *args)
        return counted

    controller.compiled_step = False
    for name in COUNTED:
        setattr(controller, name, counting(name))
    rows = {}
    try:
        for path, (posture, priority) in bench_drag.PATHS.items():
            if posture is None:
                continue
            rows[path] = {}
            for on in (False, True):
                controller.settle_refusals = on
                counts.clear()
                bench_drag._drag(posture, priority, frames, True)
                per = {k: v / frames for k, v in counts.items()}
                per["solves"] = per.get("steps", 0.0) + per.get("fallback solves", 0.0)
                rows[path][on] = per
    finally:
        for name, f in originals.items():
            setattr(controller, name, f)
        controller.compiled_step = True
        controller.settle_refusals = True
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=150)
    args = ap.parse_args()
    print(f"{args.frames} frames a path, per frame (settle_refusals off -> on)\n")
    print("| path | steps | strict-priority solves | of which the fallback's | fallback trials |")
    print("|---|---|---|---|---|")
    for path, row in count(args.frames).items():
        cells = [f"{row[False].get(k, 0.0):.2f} -> {row[True].get(k, 0.0):.2f}"
                 for k in ("steps", "solves", "fallback solves", "fallback trials")]
        print(f"| {path} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
