"""Strict-priority step benchmark: the compiled kernel beside the NumPy SVD reference, on the biped's real levels.

The biped stands on its right foot (the IK root). Pelvis, head and left foot hold their rest poses at priority 0;
both hands are dragged at priority 1 (0.3 m out, then round a 0.1 m circle, one turn per 100 frames, as a mouse
drags); the posture, the lowest level, is the rest pose (``set_posture()``) or the bundled learned prior
(:func:`gsik.prior.use_prior`: a dense 30 x 30 precision). Printed, one run, medians:

1. Per posture, every full step the controller makes over ``--frames`` frames of ``step()`` (its packed levels,
   box and dampings, recorded after :func:`gsik.kernels.control.step_trial`): the NumPy SVD step
   (:func:`gsik.priority.prioritized_step_svd`), the compiled step (:func:`gsik.priority.prioritized_step`: packing
   and kernel), the kernel alone on levels packed beforehand, and the largest difference between the steps.
2. ``Solver.step()`` of the same drag, prioritised (compiled whole since issue 20: the SVD step can no longer be
   swapped in), and the single-level solve (all five targets at priority 0, no posture: the fast kernel).

Run: ``python benchmarks/bench_priority.py [--frames 300]``. Nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import time

import numpy as np

import gsik.control
from gsik import Solver, Target, load_skeleton
from gsik.benchmark import HELD_AT_LEVEL_0
from gsik.kernels import priority as kernel
from gsik.prior import bundled_prior, use_prior
from gsik.priority import (BOX_RELATIVE_TOLERANCE, BOX_TOLERANCE, RANK_TOLERANCE, Level, pack_levels,
                           prioritized_step, prioritized_step_svd)

#: Where each hand is pulled from its rest position [m] (x: out to the left, y: forward, z: up).
HAND_PULL = {"left_hand": np.array([0.3, 0.0, 0.1]), "right_hand": np.array([0.0, 0.3, 0.0])}
CIRCLE_RADIUS = 0.1  # [m]
CIRCLE_FRAMES = 100


def _drag(poses: dict, frame: int, hand_priority: int) -> dict[str, Target]:
    """The targets of ``frame``: level 0 held at its rest ``poses`` (name: (4, 4)), the hands at ``hand_priority`` on
    their circles."""
    angle = 2.0 * np.pi * frame / CIRCLE_FRAMES
    circle = CIRCLE_RADIUS * np.array([np.cos(angle) - 1.0, 0.0, np.sin(angle)])
    targets = {n: Target.from_transform(poses[n]) for n in HELD_AT_LEVEL_0}
    for hand, pull in HAND_PULL.items():
        T = poses[hand].copy()
        T[:3, 3] += pull + circle
        targets[hand] = Target.from_transform(T, priority=hand_priority)
    return targets


def _solver(sk, posture: str) -> Solver:
    """A solver at rest with the posture ``"none"``, ``"rest"`` or ``"prior"``."""
    solver = Solver(sk)
    if posture == "rest":
        solver.set_posture()
    elif posture == "prior":
        use_prior(solver, bundled_prior("biped"))
    return solver


@contextlib.contextmanager
def _recording(calls: list):
    """Inside the block, every full step of the controller appends ``(levels, lo, hi, dampings)`` to ``calls``."""
    saved = gsik.control.Controller._first_trial

    def recording(self, q, W, R, p, state0, damping):
        dq = saved(self, q, W, R, p, state0, damping)
        wk, starts = self._work, self._tasks_in.starts
        levels = [Level(wk.rows[a:b].copy(), wk.errors[a:b].copy(), wk.weights[a:b].copy())
                  for a, b in zip(starts[:-1], starts[1:])]
        calls.append((levels, wk.lo.copy(), wk.hi.copy(), wk.dampings.copy()))
        return dq

    gsik.control.Controller._first_trial = recording
    try:
        yield
    finally:
        gsik.control.Controller._first_trial = saved


def _record(sk, posture: str, frames: int) -> list[tuple]:
    """Every ``(levels, lo, hi, dampings)`` of the controller's full steps over the drag."""
    calls = []
    solver = _solver(sk, posture)
    poses = solver.effector_poses()
    with _recording(calls):
        for frame in range(frames):
            solver.step(_drag(poses, frame, 1))
    return calls


def _median_us(function, args_list, repeats: int = 5) -> float:
    """Median over every call and ``repeats`` rounds of ``function(*args)`` [µs]."""
    times = []
    for _ in range(repeats):
        for args in args_list:
            t = time.perf_counter_ns()
            function(*args)
            times.append(time.perf_counter_ns() - t)
    return float(np.median(times)) / 1e3


def step_functions(sk, frames: int) -> None:
    print(f"### prioritized_step on the controller's real calls ({frames} frames of the drag)\n")
    print("| posture | calls | NumPy SVD | compiled (packing + kernel) | kernel alone | SVD / compiled "
          "| largest difference |")
    print("|---|---|---|---|---|---|---|")
    for posture in ("rest", "prior"):
        calls = _record(sk, posture, frames)
        packed = []
        for levels, lo, hi, damping in calls:
            dampings = np.array(np.broadcast_to(np.asarray(damping, dtype=float), (len(levels),)))
            packed.append((*pack_levels(levels, sk.n_dofs), dampings, lo, hi, RANK_TOLERANCE, BOX_TOLERANCE,
                           BOX_RELATIVE_TOLERANCE, np.empty(sk.n_dofs)))
        diff = max(float(np.abs(prioritized_step(*c) - prioritized_step_svd(*c)).max()) for c in calls)
        svd = _median_us(prioritized_step_svd, calls, repeats=1)
        compiled = _median_us(prioritized_step, calls)
        alone = _median_us(kernel.prioritized_step, packed)
        print(f"| {posture} | {len(calls)} | {svd:.0f} µs | {compiled:.1f} µs | {alone:.1f} µs "
              f"| {svd / compiled:.1f}x | {diff:.1e} rad |")
    print()


def _step_times(sk, posture: str, hand_priority: int, frames: int) -> float:
    solver = _solver(sk, posture)
    poses = solver.effector_poses()
    solver.step(_drag(poses, 0, hand_priority))  # warm: build the controller
    solver.reset()
    times = []
    for frame in range(frames):
        targets = _drag(poses, frame, hand_priority)
        t = time.perf_counter_ns()
        solver.step(targets)
        times.append(time.perf_counter_ns() - t)
    return float(np.median(times)) / 1e3


def solver_steps(sk, frames: int) -> None:
    print(f"### Solver.step() over the drag ({frames} frames; median)\n")
    print("| solve | rest posture | learned prior |")
    print("|---|---|---|")
    single = _step_times(sk, "none", 0, frames)
    rows = {"prioritised (compiled whole)": [_step_times(sk, posture, 1, frames) for posture in ("rest", "prior")]}
    for label, (rest, prior) in rows.items():
        print(f"| {label} | {rest:.0f} µs ({rest / single:.1f}x single) | {prior:.0f} µs ({prior / single:.1f}x) |")
    print(f"| single level (all at 0, no posture) | {single:.0f} µs | |\n")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=300, help="frames of the drag (default 300)")
    args = parser.parse_args(argv)
    sk = load_skeleton("biped")
    warm = _solver(sk, "rest")
    warm.step(_drag(warm.effector_poses(), 0, 1))  # compile or load every kernel first
    print(f"Load average at start: {os.getloadavg()[0]:.2f} ({os.cpu_count()} CPUs)\n")
    step_functions(sk, args.frames)
    solver_steps(sk, args.frames)
    print(f"Load average at the end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
