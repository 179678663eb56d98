"""Target construction cost: what a drag pays per mouse move for five oriented targets.

    python benchmarks/bench_targets.py

Prints the median over blocks of the time to make five targets each way, and
one solver step on them for scale. Nothing here is asserted by the tests.
"""

from __future__ import annotations

import time

import numpy as np

from gsik import Solver, Target, load_skeleton
from gsik.rotations import matrix_from_rotvec, quaternion_from_matrix, transform


def per_call_us(fn, calls: int = 2000, blocks: int = 15) -> float:
    """Median over ``blocks`` of the mean time of one ``fn()`` [µs]."""
    fn()
    times = []
    for _ in range(blocks):
        t = time.perf_counter_ns()
        for _ in range(calls):
            fn()
        times.append((time.perf_counter_ns() - t) / calls / 1e3)
    return float(np.median(times))


def main() -> None:
    rng = np.random.default_rng(0)
    Ts = [transform(matrix_from_rotvec(rng.normal(size=3)), rng.normal(size=3)) for _ in range(5)]
    qs = [tuple(quaternion_from_matrix(T[:3, :3]).tolist()) for T in Ts]
    cases = {
        "Target.from_transform(T)": lambda: [Target.from_transform(T) for T in Ts],
        "Target(position, matrix)": lambda: [Target(T[:3, 3], T[:3, :3]) for T in Ts],
        "Target(position, quaternion)": lambda: [Target(T[:3, 3], q) for T, q in zip(Ts, qs)],
        "Target(position)": lambda: [Target(T[:3, 3]) for T in Ts],
    }
    print("five targets, median per call:")
    for name, fn in cases.items():
        us = per_call_us(fn)
        print(f"  {name:30s} {us:7.2f} µs for 5, {us / 5:6.2f} µs each")
    solver = Solver(load_skeleton("biped"))
    targets = {n: Target.from_transform(T) for n, T in solver.effector_poses().items()}
    moved = dict(targets, left_hand=targets["left_hand"].replace(position=targets["left_hand"].position + 0.01))
    solver.step(moved)
    print(f"  for scale, one Solver.step():  {per_call_us(lambda: solver.step(), calls=500):7.2f} µs")


if __name__ == "__main__":
    main()
