"""Artist control benchmark: strict priorities, a preferred posture and balance, beside today's single level.

Printed (Markdown, one run, medians of timings):

1. Priorities. The biped stands on its right foot (the IK root); pelvis,
   head and free (left) foot hold their rest poses at priority 0 while the
   left hand's target is pulled 3 m out to its side and held there for 400
   frames of ``step()``. Per method: the largest priority-0 error over all
   frames, the hand's final error against its best reach (the reach a full
   ``solve()`` of the same priorities finds), the largest joint change over
   the last 100 frames (jitter), and the median step time. "single level" is
   today's method: every target at priority 0 (the fast kernel).
2. Posture. Random poses ``q*`` within the limits; position targets for the
   pelvis, head, hands and free foot taken from ``q*``; ``set_posture(q*)``;
   ``solve()`` from the rest pose. How many return ``q*`` to 1e-3 rad, on the
   first attempt and after ``solve()``'s further attempts.
3. Balance. Balanced on the right foot, the left hand's target pulled 0.8 m
   forward at priority 1, 300 frames of ``step()``, balance on and off: the
   centre of mass's greatest distance outside the right sole (negative: inside).

Run: ``python benchmarks/bench_control.py [--poses 50]``. Nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from gsik import Solver, Target, load_skeleton
from gsik.balance import signed_distance, support_polygon
from gsik.benchmark import HELD_AT_LEVEL_0 as LEVEL_0
from gsik.benchmark import hand_pull_targets as _pull_targets


def priorities(frames: int = 400) -> None:
    sk = load_skeleton("biped")
    print(f"### Priorities: pelvis, head, left foot at 0; left hand pulled 3 m away; {frames} frames of step()\n")
    print("| method | largest priority-0 error | hand error at the end (best reach) | jitter (last 100 frames) "
          "| step time (median) |")
    print("|---|---|---|---|---|")
    best = Solver(sk)
    best_reach = best.solve(_pull_targets(best, [-3.0, 0.0, 0.0], 1)).errors()["left_hand"][0]
    times = {}
    for label, hand_priority in (("strict priorities (hand at 1)", 1), ("single level (today)", 0)):
        solver = Solver(sk)
        targets = _pull_targets(solver, [-3.0, 0.0, 0.0], hand_priority)
        solver.step(targets)  # warm: compile and build once
        solver.reset()
        worst0, history, per = 0.0, [], []
        for _ in range(frames):
            t = time.perf_counter_ns()
            r = solver.step()
            per.append(time.perf_counter_ns() - t)
            errors = r.errors()
            worst0 = max(worst0, *(errors[n][0] for n in LEVEL_0))
            history.append(r.q)
        jitter = np.abs(np.diff(np.array(history[-101:]), axis=0)).max()
        times[label] = float(np.median(per)) / 1e3
        print(f"| {label} | {worst0 * 1e3:.4f} mm ({', '.join(f'{n} {errors[n][0] * 1e3:.3f}' for n in LEVEL_0)} "
              f"mm at the end) | {errors['left_hand'][0]:.4f} m ({best_reach:.4f} m) | {jitter:.1e} rad "
              f"| {times[label]:.0f} µs |")
    ratio = times["strict priorities (hand at 1)"] / times["single level (today)"]
    print(f"\nStep time with priorities / without: {ratio:.1f}x.\n")


def posture(n_poses: int = 50, seed: int = 3) -> None:
    sk = load_skeleton("biped")
    rng = np.random.default_rng(seed)
    first = after = 0
    per = []
    for _ in range(n_poses):
        q_star = rng.uniform(sk.lower, sk.upper)
        solver = Solver(sk, q0=q_star)
        poses = solver.effector_poses()
        targets = {n: Target(poses[n][:3, 3]) for n in ("pelvis", "head", "left_hand", "right_hand", "left_foot")}
        solver.set_posture(q_star)
        solver.set_targets(targets)
        one = Solver(sk, q0=q_star, restarts=0)
        one.set_posture(q_star)
        one.set_targets(targets)
        first += np.abs(one.solve(q0=sk.rest).q - q_star).max() < 1e-3
        t = time.perf_counter_ns()
        r = solver.solve(q0=sk.rest)
        per.append(time.perf_counter_ns() - t)
        after += np.abs(r.q - q_star).max() < 1e-3
    print(f"### Posture: {n_poses} random poses q* within the limits, position targets on pelvis, head, hands and "
          "free foot from q*, set_posture(q*), solve() from rest\n")
    print("| | first attempt | with solve()'s further attempts | solve time (median) |")
    print("|---|---|---|---|")
    print(f"| returns q* to 1e-3 rad | {first}/{n_poses} | {after}/{n_poses} | {np.median(per) / 1e6:.1f} ms |\n")


def balance(frames: int = 300) -> None:
    sk = load_skeleton("biped")
    print(f"### Balance: standing on the right foot, left hand pulled 0.8 m forward at priority 1, {frames} frames\n")
    print("| balance | centre of mass outside the right sole: largest (at the end) | hand error at the end |")
    print("|---|---|---|")
    for on in (True, False):
        solver = Solver(sk)
        solver.set_balance(True)
        for _ in range(100):  # shift the weight over the standing foot first
            solver.step({})
        solver.set_balance(on)
        foot = solver.frame_transforms()[sk.frame_of("right_foot")]
        sole = support_polygon([foot], [sk.soles["right_foot"]])
        hand = solver.effector_poses()["left_hand"][:3, 3] + [0.0, 0.8, 0.0]
        solver.set_targets({"left_hand": Target(hand, priority=1)})
        worst = -np.inf
        for _ in range(frames):
            r = solver.step()
            worst = max(worst, signed_distance(sole, solver.center_of_mass()[:2]))
        end = signed_distance(sole, solver.center_of_mass()[:2])
        print(f"| {'on' if on else 'off'} | {worst * 1e3:+.1f} mm ({end * 1e3:+.1f} mm) "
              f"| {r.errors()['left_hand'][0] * 1e3:.1f} mm |")
    print()


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=50, help="random poses for the posture test (default 50)")
    args = parser.parse_args(argv)
    print(f"Load average at start: {os.getloadavg()[0]:.2f} ({os.cpu_count()} CPUs)\n")
    priorities()
    posture(args.poses)
    balance()


if __name__ == "__main__":
    main()
