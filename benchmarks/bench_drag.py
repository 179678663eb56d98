"""The controlled drag beside the plain one (issue 20's figures): step cost, one-step-per-frame tracking, warm solve().

The biped on its right foot; pelvis and left foot held 6-DOF at priority 0; both hands pulled 0.15 m forward
(solved first: that pose is the drag's start and, for the controlled runs, the posture, ``set_posture(start)``),
then dragged position-only round a 0.1 m circle (one turn per 100 frames) for ``--frames`` frames. Per path:

- ``step``: one ``Solver.step()`` a frame: median µs, frames with both hands within 1 mm, frames with both pins
  within 0.1 mm;
- ``solve``: one ``Solver.solve()`` a frame, warm from the last frame: median ms and linearisations.

Paths: plain (every target at priority 0, no posture: the fast kernel), the posture with the hands at priority 0
(targets as hard constraints, posture below) and at 1 (the studio's pins), and the studio's default: pins, hands at
1 and the natural posture (the bundled prior, ``use_prior(solver, bundled_prior("biped"))``: a full precision
matrix), with the studio's ``tracking_steps=3``. ``--before PATH`` runs the same with the
``gsik`` of another checkout in a subprocess and prints both. Nothing here is asserted by the tests.

Run: ``python benchmarks/bench_drag.py [--frames 300] [--before /tmp/settle-before]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

PATHS = {"plain": (None, 0), "posture, hands at 0": ("start", 0), "posture, hands at 1 (pins)": ("start", 1),
         "prior, hands at 1 (studio)": ("prior", 1)}
PULL = np.array([0.0, 0.15, 0.0])  # [m]
RADIUS = 0.1  # [m]
TURN_FRAMES = 100


def _targets(poses: dict, frame: int, hand_priority: int) -> dict:
    from gsik import Target

    angle = 2.0 * np.pi * frame / TURN_FRAMES
    circle = RADIUS * np.array([np.cos(angle) - 1.0, 0.0, np.sin(angle)])
    targets = {n: Target.from_transform(poses[n]) for n in ("pelvis", "left_foot")}
    for hand in ("left_hand", "right_hand"):
        targets[hand] = Target(poses[hand][:3, 3] + PULL + circle, position_only=True, priority=hand_priority)
    return targets


def _solver(posture: str | None, hand_priority: int):
    """``(solver at the drag's start, rest effector poses)``; ``posture``: ``None``, ``"start"`` (the drag's start
    pose, weight 1 per DOF) or ``"prior"`` (the biped's bundled prior: the studio's natural posture)."""
    import gsik
    from gsik.prior import bundled_prior, use_prior

    solver = gsik.Solver(gsik.load_skeleton("biped"))
    poses = solver.effector_poses()
    solver.solve(_targets(poses, 0, 0))
    if posture == "start":
        solver.set_posture(solver.q)
    elif posture == "prior":
        use_prior(solver, bundled_prior("biped"))
        if "tracking_steps" in gsik.solver.setting_names():  # the studio's default (a checkout before it has none)
            solver.configure(tracking_steps=3)
    solver.set_targets(_targets(poses, 0, hand_priority))
    return solver, poses


def _drag(posture: str | None, hand_priority: int, frames: int, solve: bool) -> dict:
    solver, poses = _solver(posture, hand_priority)
    start = solver.q
    solver.step() if not solve else solver.solve()  # build what the path builds once
    solver.set_q(start)
    times, hands, pins, iterations = [], 0, 0, []
    for frame in range(frames):
        targets = _targets(poses, frame, hand_priority)
        t0 = time.perf_counter()
        r = solver.solve(targets) if solve else solver.step(targets)
        times.append(time.perf_counter() - t0)
        e = r.errors()
        hands += max(e["left_hand"][0], e["right_hand"][0]) <= 1e-3
        pins += max(e["pelvis"][0], e["left_foot"][0]) <= 1e-4
        iterations.append(r.iterations)
    return dict(us=1e6 * float(np.median(times)), hands=hands, pins=pins, iterations=float(np.median(iterations)))


def run(frames: int) -> dict:
    """``{path: {"step": ..., "solve": ...}}``."""
    return {name: {"step": _drag(posture, prio, frames, False), "solve": _drag(posture, prio, frames, True)}
            for name, (posture, prio) in PATHS.items()}


def _print(rows: dict, frames: int) -> None:
    print(f"load {os.getloadavg()[0]:.1f}; {frames} frames\n")
    print("| code | path | step µs (x plain) | hands within 1 mm | pins within 0.1 mm | warm solve() ms (x plain) "
          "| linearisations |")
    print("|---|---|---|---|---|---|---|")
    for code, row in rows.items():
        plain = row["plain"]
        for name, r in row.items():
            s, v = r["step"], r["solve"]
            print(f"| {code} | {name} | {s['us']:.0f} ({s['us'] / plain['step']['us']:.1f}x) | {s['hands']}/{frames} "
                  f"| {s['pins']}/{frames} | {v['us'] / 1e3:.2f} ({v['us'] / plain['solve']['us']:.1f}x) "
                  f"| {v['iterations']:.0f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--before", help="a checkout whose gsik to run the same drags with, side by side")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.json:
        print(json.dumps(run(args.frames)))
        return
    rows = {}
    if args.before:
        env = dict(os.environ, PYTHONPATH=os.path.abspath(args.before))
        cmd = [sys.executable, os.path.abspath(__file__), "--json", "--frames", str(args.frames)]
        rows["before"] = json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True,
                                                   cwd=os.path.abspath(args.before)).stdout)
    rows["after"] = run(args.frames)
    _print(rows, args.frames)


if __name__ == "__main__":
    main()
