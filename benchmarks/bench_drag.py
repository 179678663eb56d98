"""The controlled drag beside the plain one (issue 20's figures): step cost, one-step-per-frame tracking, warm solve().

The biped on its right foot; pelvis and left foot held 6-DOF at priority 0; both hands pulled 0.15 m forward
(solved first: that pose is the drag's start and, for the controlled runs, the posture, ``set_posture(start)``),
then dragged position-only round a 0.1 m circle (one turn per 100 frames) for ``--frames`` frames. Per path:

- ``step``: one ``Solver.step()`` a frame: median µs, frames with both hands within 1 mm, frames with both pins
  within 0.1 mm, frames whose last controlled step needed restoring steps (a posture's move broke a met level);
- ``solve``: one ``Solver.solve()`` a frame, warm from the last frame: median ms, linearisations and µs per
  linearisation (each frame's time over its linearisations; beside the step's µs a frame); where the
  settings have ``posture_tolerance``, the quality of its settle test against a drag solved with it off (0: a solve
  goes on until a step gains under ``settle_tolerance``): the largest joint-angle difference [rad] and effector
  difference [mm] over every frame and joint, and the range of the posture's cost ratio (frames whose posture cost
  with it off is at least 1e-3); where the controller has ``settle_refusals``, the same figures against the drag
  with it off (a worse step that settles the posture retried, three restoring steps: the solve before that change).

Paths: plain (every target at priority 0, no posture: the fast kernel), the posture with the hands at priority 0
(targets as hard constraints, posture below) and at 1 (the studio's pins), and the studio's default: pins, hands at
1 and the natural posture (the bundled prior, ``use_prior(solver, bundled_prior("biped"))``: a full precision
matrix), with the studio's ``tracking_steps=3``. ``--before PATH`` runs the same with the
``gsik`` of another checkout in a subprocess and prints both. ``--rounds K`` drags every path K times in turn and
adds the range of the K rounds' multiples of plain to the step and solve columns (the first round's figures
first). Before the first round every path is dragged ``--warmup`` frames untimed (default 30). Nothing here is
asserted by the tests.

Run: ``python benchmarks/bench_drag.py [--frames 300] [--rounds 3] [--warmup 30] [--before /tmp/settle-before]``.
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
WARMUP_FRAMES = 30  # untimed frames of every path before the first round (run())


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


def _drag(posture: str | None, hand_priority: int, frames: int, solve: bool, **settings) -> dict:
    solver, poses = _solver(posture, hand_priority)
    solver.configure(**settings)
    start = solver.q
    solver.step() if not solve else solver.solve()  # build what the path builds once
    solver.set_q(start)
    times, hands, pins, iterations, poses_q, points, costs = [], 0, 0, [], [], [], []
    restored = _count_restoring(solver)
    for frame in range(frames):
        targets = _targets(poses, frame, hand_priority)
        t0 = time.perf_counter()
        r = solver.solve(targets) if solve else solver.step(targets)
        times.append(time.perf_counter() - t0)
        e = r.errors()
        hands += max(e["left_hand"][0], e["right_hand"][0]) <= 1e-3
        pins += max(e["pelvis"][0], e["left_foot"][0]) <= 1e-4
        iterations.append(r.iterations)
        poses_q.append(r.q)
        points.append(solver.world_positions())
        costs.append(_posture_cost(solver))
        restored(frame)
    per_linearisation = [t / i for t, i in zip(times, iterations) if i > 0]
    return {"us": 1e6 * float(np.median(times)), "hands": hands, "pins": pins,
            "us_per_linearisation": 1e6 * float(np.median(per_linearisation)) if per_linearisation else 0.0,
            "iterations": float(np.median(iterations)), "restored": restored(None), "q": np.array(poses_q),
            "points": np.array(points),
            "cost": np.array(costs)}


def _count_restoring(solver):
    """``count(frame)``: after a frame, counts it if its last controlled step's full step was given restoring steps
    (the compiled step's ``R_RESTORED``: a posture's move broke a met level); ``count(None)``: the frames counted
    (``"-"`` for a checkout without it)."""
    try:
        from gsik.kernels import accept
    except ImportError:  # a checkout from before the compiled acceptance (--before): nothing to count
        accept = None
    frames = set()

    def count(frame):
        if frame is None:
            return len(frames) if accept is not None else "-"
        controller = getattr(solver, "_controller", None)
        cache = getattr(controller, "_cache", None)
        if hasattr(accept, "R_RESTORED") and cache is not None and cache.out[accept.R_RESTORED] > 0.0:
            frames.add(frame)
        return len(frames)

    return count


def _posture_cost(solver) -> float:
    """``0.5 (q - reference)^T P (q - reference)`` of the solver's posture (0 without one)."""
    p = solver.posture
    if p is None:
        return 0.0
    d = solver.q - p.reference
    return 0.5 * float(d @ (p.precision * d if p.precision.ndim == 1 else p.precision @ d))


def _solve_drag(posture: str | None, hand_priority: int, frames: int) -> dict:
    """The solve drag, and where the settings have ``posture_tolerance`` its quality (:func:`_against`) against the
    drag with it off, and (``refusals``) where the controller has ``settle_refusals`` against the drag with those
    off."""
    import gsik.control

    run = _drag(posture, hand_priority, frames, True)
    if posture is None or "posture_tolerance" not in gsik.solver.setting_names():
        return _plain(run)
    figures = dict(_plain(run), **_against(run, _drag(posture, hand_priority, frames, True, posture_tolerance=0.0)))
    if hasattr(gsik.control.Controller, "settle_refusals"):
        gsik.control.Controller.settle_refusals = False
        try:
            figures["refusals"] = _against(run, _drag(posture, hand_priority, frames, True))
        finally:
            gsik.control.Controller.settle_refusals = True
    return figures


def _against(run: dict, off: dict) -> dict:
    """``run``'s quality against the drag ``off``: ``dq`` the largest joint-angle difference [rad], ``dx`` the
    largest frame position difference [m], ``ratio`` (least, largest) posture cost ratio over the frames whose cost
    in ``off`` is at least 1e-3 (``None``: no such frame)."""
    kept = off["cost"] >= 1e-3
    ratio = run["cost"][kept] / off["cost"][kept]
    return {"dq": float(np.abs(run["q"] - off["q"]).max()),
            "dx": float(np.linalg.norm(run["points"] - off["points"], axis=-1).max()),
            "ratio": (float(ratio.min()), float(ratio.max())) if ratio.size else None}


def _plain(run: dict) -> dict:
    """``run``'s figures without its per-frame arrays (what the JSON between checkouts carries)."""
    return {k: v for k, v in run.items() if k not in ("q", "points", "cost")}


def run(frames: int, rounds: int = 1, warmup: int = WARMUP_FRAMES) -> dict:
    """``{path: {"step": ..., "solve": ...}}``; each with ``rounds_us``, its median µs in each round. A round drags
    every path in turn, so each round's ratios to the plain path are taken close together in time: on a machine
    whose speed shifts between runs (seen here: the same drag 1.6x slower in one run than the next) a shift between
    two paths of one round shows as that round's ratio standing out, not as the only figure. ``us`` is the first
    round's (the one the quality figures come with). First, untimed, every path is dragged ``warmup`` frames
    (stepped and solved): a process's first drag read slower than the later ones (at 30 frames the first round's
    plain step 23 µs, the next rounds' 14), and plain runs first, so without it the first round's ratios to plain
    read low."""
    for posture, prio in PATHS.values() if warmup > 0 else ():
        for solve in (False, True):
            _drag(posture, prio, warmup, solve)
    rows = {name: {"step": _plain(_drag(posture, prio, frames, False)), "solve": _solve_drag(posture, prio, frames)}
            for name, (posture, prio) in PATHS.items()}
    for row in rows.values():
        for kind in ("step", "solve"):
            row[kind]["rounds_us"] = [row[kind]["us"]]
    for _ in range(rounds - 1):
        for name, (posture, prio) in PATHS.items():
            for kind in ("step", "solve"):
                rows[name][kind]["rounds_us"].append(_drag(posture, prio, frames, kind == "solve")["us"])
    return rows


def _print(rows: dict, frames: int, rounds: int, warmup: int) -> None:
    print(f"load {os.getloadavg()[0]:.1f}; {frames} frames, {rounds} round(s) after {warmup} untimed frames a path\n")
    print("| code | path | step µs (x plain) | hands within 1 mm | pins within 0.1 mm | warm solve() ms (x plain) "
          "| linearisations | solve µs per linearisation (x step) | vs posture_tolerance 0: max rad, mm, cost ratio "
          "| vs settle_refusals off | step frames restored |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for code, row in rows.items():
        plain = row["plain"]
        for name, r in row.items():
            s, v = r["step"], r["solve"]
            print(f"| {code} | {name} | {s['us']:.0f} ({_ratios(s, plain['step'])}) | {s['hands']}/{frames} "
                  f"| {s['pins']}/{frames} | {v['us'] / 1e3:.2f} ({_ratios(v, plain['solve'])}) "
                  f"| {v['iterations']:.0f} | {_per_linearisation(v, s)} | {_quality(v)} "
                  f"| {_quality(v.get('refusals', {}))} | {s.get('restored', '-')} |")


def _ratios(r: dict, plain: dict) -> str:
    """``r``'s first round's µs as a multiple of the plain path's, then with more rounds the range of each round's
    multiple (``1.92x; 1.85x-2.01x``: two decimals, to read a bound such as 1.5x)."""
    first = f"{r['us'] / plain['us']:.2f}x"
    ratios = [a / b for a, b in zip(r["rounds_us"], plain["rounds_us"])]
    if len(ratios) < 2:
        return first
    return f"{first}; {min(ratios):.2f}x-{max(ratios):.2f}x"


def _per_linearisation(v: dict, s: dict) -> str:
    """The solve drag's median µs per linearisation (each frame's time over its linearisations) and its ratio to
    the step drag's µs a frame: ``-`` for a checkout whose figures lack it."""
    us = v.get("us_per_linearisation")
    return "-" if us is None else f"{us:.0f} ({us / s['us']:.1f}x)"


def _quality(v: dict) -> str:
    """The solve drag's quality column: ``-`` where there is none to show."""
    if "dq" not in v:
        return "-"
    ratio = "-" if v["ratio"] is None else f"{v['ratio'][0]:.4f}-{v['ratio'][1]:.4f}"
    return f"{v['dq']:.1e}, {1e3 * v['dx']:.2f}, {ratio}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--before", help="a checkout whose gsik to run the same drags with, side by side")
    ap.add_argument("--rounds", type=int, default=1,
                    help="drag every path this many times in turn; the table adds the range of the rounds' ratios")
    ap.add_argument("--warmup", type=int, default=WARMUP_FRAMES,
                    help="untimed frames of every path (stepped and solved) before the first round; 0: none")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.json:
        print(json.dumps(run(args.frames, args.rounds, args.warmup)))
        return
    rows = {}
    if args.before:
        env = dict(os.environ, PYTHONPATH=os.path.abspath(args.before))
        cmd = [sys.executable, os.path.abspath(__file__), "--json", "--frames", str(args.frames), "--rounds",
               str(args.rounds), "--warmup", str(args.warmup)]
        rows["before"] = json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True,
                                                   cwd=os.path.abspath(args.before)).stdout)
    rows["after"] = run(args.frames, args.rounds, args.warmup)
    _print(rows, args.frames, args.rounds, args.warmup)


if __name__ == "__main__":
    main()
