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
4. Step time, as the studio steps: its default targets (feet and pelvis pinned
   at priority 0, head and hands free at 1, hands position-only) with the left
   hand dragged round a 25 cm circle, one target move and one ``Solver.step()``
   a frame, then held still. Median ``Solver.step()`` time while dragging and
   while held, for today's single level (every target at priority 0: the fast
   kernel), the studio's pins, the pins with a rest posture (weight 1), and the
   pins with the learned prior (:func:`gsik.prior.use_prior`, strength 1). The
   solvers take turns frame by frame, so a change of machine load touches all alike.
   ``--before REV`` adds the prioritised paths again with ``gsik/control.py`` as
   it was at git revision REV (the rest of the package as it is now).

Run: ``python benchmarks/bench_control.py [--poses 50]``. Nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import gsik.solver
from gsik import Solver, Target, load_skeleton
from gsik.balance import signed_distance, support_polygon
from gsik.benchmark import HELD_AT_LEVEL_0 as LEVEL_0
from gsik.benchmark import hand_pull_targets as _pull_targets
from gsik.prior import bundled_prior, use_prior


def priorities(frames: int = 400) -> None:
    sk = load_skeleton("biped")
    print(f"### Priorities: pelvis, head, left foot at 0; left hand pulled 3 m away; {frames} frames of step()\n")
    print("| method | largest priority-0 error | hand error at the end (best reach) | jitter (last 100 frames) "
          "| step time (median, held frames too) |")
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


def _studio_targets(solver: Solver, hand_offset) -> dict[str, Target]:
    """The studio's default targets where the biped stands, the left hand's moved by ``hand_offset`` (3,) [m]."""
    targets = {}
    for name, pose in solver.effector_poses().items():
        if name != solver.root:
            free = name not in ("left_foot", "right_foot", "pelvis")
            targets[name] = Target.from_transform(pose, position_only=name.endswith("_hand"), priority=int(free))
    targets["left_hand"] = targets["left_hand"].replace(position=targets["left_hand"].position + hand_offset)
    return targets


def _control_at(rev: str):
    """``gsik/control.py`` as it was at git revision ``rev``, loaded as a module beside today's."""
    root = Path(__file__).resolve().parents[1]
    text = subprocess.run(["git", "-C", str(root), "show", f"{rev}:gsik/control.py"], check=True,
                          capture_output=True, text=True).stdout
    path = Path(tempfile.mkdtemp()) / "control_before.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("gsik_control_before", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _step_solvers(sk, before: str | None) -> dict[str, tuple[Solver, object]]:
    """``{label: (solver, the gsik.control module it steps with)}``."""
    paths = {"single level (today)": None, "studio pins": None, "pins + rest posture": 1.0,
             "pins + learned prior": "prior"}
    controls = [("", gsik.solver.control)] + ([(f" [{before}]", _control_at(before))] if before else [])
    out = {}
    for suffix, module in controls:
        for label, posture in paths.items():
            if suffix and label.startswith("single"):
                continue
            solver = Solver(sk, sweeps=8)
            if posture == "prior":
                use_prior(solver, bundled_prior("biped"), 1.0)
            elif posture is not None:
                solver.set_posture(None, posture)
            out[label + suffix] = (solver, module)
    return out


def step_times(frames: int = 300, held: int = 100, before: str | None = None) -> None:
    sk = load_skeleton("biped")
    solvers = _step_solvers(sk, before)
    rest = {label: _studio_targets(s, np.zeros(3)) for label, (s, _) in solvers.items()}
    rest["single level (today)"] = {n: t.replace(priority=0) for n, t in rest["single level (today)"].items()}
    per = {label: ([], []) for label in solvers}
    for i in range(-10, frames + held):  # ten warm-up frames (compiling, building), then timed
        a = 2.0 * np.pi * min(max(i, 0), frames) / 100.0
        offset = np.array([0.25 * np.sin(a), 0.15, 0.25 * (np.cos(a) - 1.0)])
        for label, (solver, module) in solvers.items():
            gsik.solver.control = module
            hand = rest[label]["left_hand"]
            solver.set_targets({**rest[label], "left_hand": hand.replace(position=hand.position + offset)})
            t = time.perf_counter_ns()
            solver.step()
            if i >= 0:
                per[label][i >= frames].append(time.perf_counter_ns() - t)
    print(f"### Step time: the studio's targets, the left hand dragged round a 25 cm circle ({frames} frames), "
          f"then held ({held} frames); Solver.step(), median\n")
    print("| path | dragging | vs single level | held | status at the end |")
    print("|---|---|---|---|---|")
    base = float(np.median(per["single level (today)"][0]))
    medians = {}
    for label, (solver, module) in solvers.items():
        gsik.solver.control = module
        drag, still = (float(np.median(x)) for x in per[label])
        medians[label] = drag
        print(f"| {label} | {drag / 1e3:.0f} µs | {drag / base:.1f}x | {still / 1e3:.0f} µs "
              f"| {solver.step().status.name.lower()} |")
    gsik.solver.control = solvers["single level (today)"][1]
    ratio = medians["pins + learned prior"] / medians["pins + rest posture"]
    print(f"\nLearned prior / rest posture while dragging: {ratio:.2f}x (issue 12 asks <= 1.5x).\n")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--poses", type=int, default=50, help="random poses for the posture test (default 50)")
    parser.add_argument("--only-step-time", action="store_true", help="run part 4 (step time) only")
    parser.add_argument("--before", metavar="REV", help="part 4 also with gsik/control.py as at git revision REV")
    args = parser.parse_args(argv)
    print(f"Load average at start: {_load()} ({os.cpu_count()} CPUs)\n")
    if not args.only_step_time:
        priorities()
        posture(args.poses)
        balance()
    step_times(before=args.before)
    print(f"Load average at the end: {_load()}")


def _load() -> str:
    return " / ".join(f"{x:.2f}" for x in os.getloadavg()) + " (1 / 5 / 15 min)"


if __name__ == "__main__":
    main()
