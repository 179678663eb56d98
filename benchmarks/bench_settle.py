"""Frames to settle after a small edit, with the studio's defaults: today's code (``--before``) beside this tree's.

The studio's new document (:mod:`gsik_studio.model.document`), rebuilt with the library alone so that the same
script runs on an older checkout: the biped at rest on its right foot, a target on every effector where it stands
(the hands position-only), the feet and the pelvis pinned (priority 0), head and hands at priority 1, the natural
posture (the bundled prior, :func:`gsik.prior.use_prior`), solver settings ``sweeps=8, damping=1e-3``. Each edit
starts from that document settled, then calls ``Solver.step()`` until the studio's frame loop would stop: a
converged step, or :data:`QUIET` settled (converged or stalled) steps in a row (``app/model/document.py``), at
most ``--limit`` steps. Printed per edit: steps, the last status, the largest position error [mm] and the median
cost of a step [µs].

Run: ``python benchmarks/bench_settle.py [--before PATH] [--limit 3000]``; ``--before`` runs the same edits with
the ``gsik`` of another checkout (e.g. ``git worktree add /tmp/settle-before 668c52e``) in a subprocess, and prints
both side by side. Nothing here is asserted by the tests (``tests/test_settle.py`` checks the frame counts).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

#: The joints the studio puts pole targets on (app/model/pins.py).
POLES = ("left_knee", "right_knee", "left_elbow", "right_elbow")
#: Settled steps in a row that end the studio's solving (gsik.anim.scenario_run.QUIET_FRAMES).
QUIET = 10


def studio_solver(posture: bool = True):
    """``(solver, targets)`` of a new studio document on the biped, settled."""
    import gsik
    from gsik.prior import bundled_prior, use_prior

    sk = gsik.load_skeleton("biped")
    solver = gsik.Solver(sk, sweeps=8, damping=1e-3)
    pinned = ("left_foot", "right_foot", "pelvis")
    targets = {n: gsik.Target.from_transform(T, position_only=n.endswith("_hand"), priority=0 if n in pinned else 1)
               for n, T in solver.effector_poses().items()}
    if posture:
        use_prior(solver, bundled_prior("biped"))
    solver.set_targets(targets)
    settle(solver, 3000)
    return solver, targets


def settle(solver, limit: int) -> tuple[int, object, list[float]]:
    """``(steps, last result, step times [s])`` of stepping until the studio would stop (or ``limit`` steps)."""
    import gsik

    quiet, times, result = 0, [], None
    for n in range(1, limit + 1):
        t0 = time.perf_counter()
        result = solver.step()
        times.append(time.perf_counter() - t0)
        quiet = QUIET if result.status is gsik.Status.CONVERGED else \
            quiet + 1 if result.status is gsik.Status.STALLED else 0
        if quiet >= QUIET:
            return n, result, times
    return limit, result, times


def _turned(target, degrees: float):
    from gsik.rotations import matrix_from_axis_angle

    return target.replace(orientation=matrix_from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(degrees))
                          @ target.rotation)


def _moved(target, offset):
    return target.replace(position=np.asarray(target.position) + offset)


def edits() -> dict:
    """``{name: list of target changes}``: each maps ``(targets, position of a joint)`` to new targets; the changes
    are applied, each then settled, in turn."""
    cm = 0.01
    return {
        "head z +15": [lambda t, at: {**t, "head": _turned(t["head"], 15.0)}],
        "head z +15 twice": [lambda t, at: {**t, "head": _turned(t["head"], 15.0)}] * 2,
        "left hand 1 cm out": [lambda t, at: {**t, "left_hand": _moved(t["left_hand"], [cm, 0, 0])}],
        "right hand 1 cm up": [lambda t, at: {**t, "right_hand": _moved(t["right_hand"], [0, 0, cm])}],
        "pelvis 1 cm down": [lambda t, at: {**t, "pelvis": _moved(t["pelvis"], [0, 0, -cm])}],
        "pelvis 1 cm forward": [lambda t, at: {**t, "pelvis": _moved(t["pelvis"], [0, cm, 0])}],
        "pelvis 1 cm left": [lambda t, at: {**t, "pelvis": _moved(t["pelvis"], [cm, 0, 0])}],
        "pelvis 1 cm back": [lambda t, at: {**t, "pelvis": _moved(t["pelvis"], [0, -cm, 0])}],
        "pelvis turned 5 about z": [lambda t, at: {**t, "pelvis": _turned(t["pelvis"], 5.0)}],
        "left knee pole 5 cm forward": [lambda t, at: {**t, "left_knee": _pole(at("left_knee"), [0, 0.05, 0])}],
        "right elbow pole 3 cm out": [
            lambda t, at: {**t, "right_hand": _moved(t["right_hand"], [0.0, 0.25, 0.3])},
            lambda t, at: {**t, **{j: _pole(at(j), [0, 0, 0]) for j in POLES}, "right_elbow": _pole(at("right_elbow"),
                                                                                               [-0.03, 0, 0])}],
    }


def _pole(position, offset):
    """A pole target (position only, priority 2, as the studio's) ``offset`` [m] from ``position`` (3,) [m]."""
    import gsik

    return gsik.Target(np.asarray(position) + offset, position_only=True, priority=2)


def run(limit: int, posture: bool = True) -> dict:
    """``{edit: {steps, status, error_mm, step_us}}`` for every edit, each from a fresh settled document."""
    out = {}
    for name, changes in edits().items():
        solver, targets = studio_solver(posture)
        sk = solver.skeleton
        steps, times = [], []
        for change in changes:
            P = solver.world_positions()
            targets = change(targets, lambda joint, P=P: P[sk.frame_of(joint)])
            solver.set_targets(targets)
            n, result, t = settle(solver, limit)
            steps.append(n)
            times += t
        out[name] = dict(steps=steps, status=result.status.name, error_mm=1000 * result.max_position_error,
                         step_us=1e6 * float(np.median(times)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="a checkout whose gsik to run the same edits with, side by side")
    ap.add_argument("--limit", type=int, default=3000, help="most steps per edit")
    ap.add_argument("--no-posture", action="store_true", help="posture off (the rest of the studio's defaults)")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.json:
        print(json.dumps(run(args.limit, not args.no_posture)))
        return
    rows = {"after": run(args.limit, not args.no_posture)}
    if args.before:
        env = dict(os.environ, PYTHONPATH=os.path.abspath(args.before))
        cmd = [sys.executable, os.path.abspath(__file__), "--json", "--limit", str(args.limit)]
        cmd += ["--no-posture"] if args.no_posture else []
        rows = {"before": json.loads(subprocess.run(cmd, env=env, capture_output=True, text=True, check=True,
                                                    cwd=os.path.abspath(args.before)).stdout), **rows}
    posture = "off" if args.no_posture else "natural"
    print(f"load {os.getloadavg()[0]:.1f}; posture {posture}; at most {args.limit} steps")
    print(f"{'edit':30s}" + "".join(f" | {k + ': steps':>18s} {'status':>16s} {'err mm':>7s} {'µs/step':>8s}"
                                    for k in rows))
    for name in edits():
        cells = []
        for row in rows.values():
            r = row[name]
            cells.append(f" | {'+'.join(map(str, r['steps'])):>18s} {r['status']:>16s} {r['error_mm']:7.3f} "
                         f"{r['step_us']:8.0f}")
        print(f"{name:30s}" + "".join(cells))


if __name__ == "__main__":
    main()
