"""A drag's warm ``solve()`` with its steps in one compiled call beside the same steps through the Python loop.

bench_drag's three controlled drags (the biped on its right foot, pelvis and left foot pinned, both hands round a
0.1 m circle for 300 frames; the start pose as the posture with the hands at priority 0 or 1, or the studio's
natural posture), one ``Solver.solve()`` a frame warm from the last. Each drag runs with
``ControlSettle.compiled_settle`` on (the attempt's steps as one :func:`gsik.kernels.settle_steps.settle_steps`
call) and off (``Attempts._control_steps``' Python loop over ``Controller.step`` and ``PostureSettle.settled``),
alternated ``--repeats`` times in one process. Printed per drag: the median solve [µs] of each run, the
linearisations a frame (mean), and whether both loops gave the same angles bit for bit. Nothing here is asserted by
the tests (``tests/test_control_settle.py`` checks the loops agree).

Run: ``python benchmarks/bench_solve_loop.py [--frames 300] [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_drag  # noqa: E402  (this folder's: the same drag)

DRAGS = {"posture, hands at 0": ("start", 0), "posture, hands at 1 (pins)": ("start", 1),
         "prior, hands at 1 (studio)": ("prior", 1)}


def _run(posture: str, hand_priority: int, frames: int) -> tuple[float, float, str]:
    """``(median warm solve [µs], linearisations a frame, SHA-256 of the angles)`` of one drag."""
    solver, poses = bench_drag._solver(posture, hand_priority)
    if posture == "prior":
        solver.configure(tracking_steps=3)
    targets = [bench_drag._targets(poses, f, hand_priority) for f in range(frames)]
    times, linearisations, digest = [], [], hashlib.sha256()
    for t in targets:
        t0 = time.perf_counter()
        r = solver.solve(t)
        times.append(time.perf_counter() - t0)
        linearisations.append(r.iterations)
        digest.update(r.q.tobytes())
    return float(np.median(times)) * 1e6, float(np.mean(linearisations)), digest.hexdigest()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    from gsik.control_settle import ControlSettle

    load = os.getloadavg()[0]
    runs: dict = {}
    for _ in range(args.repeats):
        for on in (True, False):
            ControlSettle.compiled_settle = on
            for name, (posture, hp) in DRAGS.items():
                runs.setdefault((name, on), []).append(_run(posture, hp, args.frames))
    ControlSettle.compiled_settle = True
    print(f"load {load:.1f} at the start; {args.frames} frames, {args.repeats} alternated runs each\n")
    print("| drag | compiled loop: warm solve µs | Python loop | linearisations a frame | same angles |")
    print("|---|---|---|---|---|")
    for name in DRAGS:
        on, off = runs[(name, True)], runs[(name, False)]
        same = len({r[2] for r in on + off}) == 1
        print(f"| {name} | {' / '.join(f'{r[0]:.0f}' for r in on)} | {' / '.join(f'{r[0]:.0f}' for r in off)} "
              f"| {on[0][1]:.2f} | {'yes' if same else 'NO'} |")


if __name__ == "__main__":
    main()
