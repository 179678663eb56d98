"""gsik beside placo on single chains: one arm (7 DOF) and one leg (6 DOF) of the biped, figures side by side.

    python benchmarks/bench_peers.py [--problems 200] [--frames 300] [--seed 0]

The chains are small URDF files written for this benchmark (``peer_chains.py``: the biped's segment lengths and
joint ranges), read by both peers. Two measures, each with 6-DOF targets and with position-only ones:

- **Chain reach**: ``--problems`` random reachable targets (the effector's pose at angles drawn uniformly within
  the limits), each solved from the rest pose to gsik's default tolerances (0.1 mm, 1e-3 rad). gsik:
  ``Solver.solve()``. placo: its kinematics solver with one frame task (or position task), ``solve(True)``
  iterations until the effector is within those tolerances, at most 200 (gsik's linearisations per attempt).
  Figures: median µs per solve (the target's setting and every check included), median iterations (gsik:
  linearisations of all its attempts), share solved; and the median µs over the problems both solved.
- **Chain tracking**: a target going once round a 0.1 m circle through the effector's rest position (in the
  sagittal plane, the rest orientation kept) over ``--frames`` frames, one step per frame, each peer through the
  per-frame calls a user would make: gsik ``Solver.move_target(name, position[, rotation])`` (the target set once
  before the first frame, moved in place after) and ``Solver.step()``, placo setting the task's target, one
  ``solve(True)`` and ``update_kinematics()``. A gsik without ``move_target`` (an older one, through
  ``PYTHONPATH``) steps with a new ``Target`` a frame: ``Solver.step({name: Target(...)})``.
  Figures: median µs per frame, frames whose effector ends within 1 mm of the target, the largest miss.

placo is an optional peer (``pip install placo``, or the ``peers`` extra); without it the benchmark says why and
prints gsik's figures alone. Timings on a shared machine are noisy: compare the peers within one run.

``--before CHECKOUT`` compares with another checkout of gsik in the same period: ``--rounds`` times, this
checkout's run then the other's (the same script run by ``CHECKOUT/.venv/bin/python`` with ``PYTHONPATH`` the
checkout, so with that checkout's gsik; placo where that interpreter has it), each printing its table.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

import numpy as np

import gsik
from gsik.io.urdf_skeleton import skeleton_from_urdf

from peer_chains import CHAINS, Chain  # noqa: E402  (the benchmark's own chain problems, beside this file)

#: gsik's default tolerances: position [m], orientation [rad].
POSITION_TOLERANCE = gsik.SolverSettings().position_tolerance
ORIENTATION_TOLERANCE = gsik.SolverSettings().orientation_tolerance
#: placo's iterations per reach at most (gsik's default linearisations per attempt).
PLACO_ITERATIONS = gsik.SolverSettings().max_iterations
#: The tracking circle's radius [m] and the miss a tracked frame may have [m].
RADIUS = 0.05
TRACKED = 1e-3


class Problem(NamedTuple):
    """One chain problem: world poses (4, 4) of the effector to reach, and the tracking circle's, per frame."""

    chain: Chain
    urdf: Path
    reach: list[np.ndarray]
    circle: list[np.ndarray]


class Figures(NamedTuple):
    """One peer's figures on one problem with one kind of target."""

    reach_us: list[float]  # per solve [µs]
    reach_iterations: list[int]
    solved: list[bool]
    track_us: list[float]  # per frame [µs]
    track_miss: list[float]  # per frame, position error after the step [m]


def problems(folder: Path, n: int, frames: int, seed: int) -> list[Problem]:
    """Each chain's URDF written into ``folder``, ``n`` reach targets and the circle of ``frames`` targets."""
    out = []
    rng = np.random.default_rng(seed)
    for make in CHAINS.values():
        chain = make()
        path = chain.write(folder)
        sk = skeleton_from_urdf(path, effectors=[chain.effector], root="base")
        reach = [sk.effector_poses(q)[chain.effector] for q in rng.uniform(sk.lower, sk.upper, (n, sk.n_dofs))]
        rest = sk.effector_poses(chain.bent)[chain.effector]
        centre = rest[:3, 3] + [0.0, 0.0, RADIUS]
        circle = []
        for f in range(frames):
            a = 2.0 * math.pi * f / frames
            T = rest.copy()
            T[:3, 3] = centre + RADIUS * np.array([0.0, math.sin(a), -math.cos(a)])
            circle.append(T)
        out.append(Problem(chain, path, reach, circle))
    return out


class GsikPeer:
    """gsik on one chain: its URDF as a skeleton (root the base link, the chain's end the one effector)."""

    name = "gsik"

    def __init__(self, problem: Problem):
        chain = problem.chain
        self.effector = chain.effector
        self.rest, self.bent = chain.rest, chain.bent
        self.solver = gsik.Solver(skeleton_from_urdf(problem.urdf, effectors=[chain.effector], root="base"),
                                  q0=chain.rest)

    def reach(self, T: np.ndarray, position_only: bool) -> tuple[int, bool, float]:
        """From the rest pose (set untimed) solve for the pose ``T`` (4, 4): (linearisations, converged, µs)."""
        self.solver.set_q(self.rest)
        start = time.perf_counter_ns()
        target = gsik.Target(T[:3, 3]) if position_only else gsik.Target(T[:3, 3], T[:3, :3])
        r = self.solver.solve({self.effector: target})
        return r.iterations, r.converged, (time.perf_counter_ns() - start) * 1e-3

    def track(self, circle: list[np.ndarray], position_only: bool) -> tuple[list[float], list[float]]:
        """From the bent pose, one step a frame towards each pose of ``circle``: (µs, miss [m]) per frame."""
        self.solver.set_q(self.bent)
        solver, name, us, miss = self.solver, self.effector, [], []
        moves = hasattr(solver, "move_target")
        first = circle[0]
        solver.set_targets({name: gsik.Target(first[:3, 3]) if position_only else gsik.Target.from_transform(first)})
        for T in circle:
            p, R = T[:3, 3], T[:3, :3]
            start = time.perf_counter_ns()
            if not moves:
                r = solver.step({name: gsik.Target(p) if position_only else gsik.Target(p, R)})
            else:
                if position_only:
                    solver.move_target(name, p)
                else:
                    solver.move_target(name, p, R)
                r = solver.step()
            us.append((time.perf_counter_ns() - start) * 1e-3)
            miss.append(float(r.position_errors[0]))
        return us, miss


class PlacoPeer:
    """placo on one chain: its kinematics solver, the floating base masked, one soft task on the chain's end."""

    name = "placo"

    def __init__(self, problem: Problem, placo):
        chain = problem.chain
        self.effector, self.rest, self.bent, self.dofs = chain.effector, chain.rest, chain.bent, chain.dof_names
        self.robot = placo.RobotWrapper(str(problem.urdf), placo.Flags.ignore_collisions)
        self.solvers = {}
        for position_only in (False, True):
            solver = placo.KinematicsSolver(self.robot)
            solver.mask_fbase(True)
            if position_only:
                task = solver.add_position_task(chain.effector, np.zeros(3))
                task.configure(chain.effector, "soft", 1.0)
            else:
                task = solver.add_frame_task(chain.effector, np.eye(4))
                task.configure(chain.effector, "soft", 1.0, 1.0)
            self.solvers[position_only] = (solver, task)

    def _set_q(self, angles: np.ndarray) -> None:
        for name, q in zip(self.dofs, angles):
            self.robot.set_joint(name, float(q))
        self.robot.update_kinematics()

    def _set_target(self, task, T: np.ndarray, position_only: bool) -> None:
        if position_only:
            task.target_world = T[:3, 3]
        else:
            task.T_world_frame = T

    def _within(self, p: list[float], R: list[list[float]] | None) -> bool:
        """True if the effector is within gsik's tolerances of position ``p`` and rotation ``R`` (None: any)."""
        X = self.robot.get_T_world_frame(self.effector).tolist()
        dx, dy, dz = X[0][3] - p[0], X[1][3] - p[1], X[2][3] - p[2]
        if dx * dx + dy * dy + dz * dz > POSITION_TOLERANCE ** 2:
            return False
        if R is None:
            return True
        trace = sum(X[i][j] * R[i][j] for i in range(3) for j in range(3))
        return 0.5 * (trace - 1.0) >= math.cos(ORIENTATION_TOLERANCE)

    def reach(self, T: np.ndarray, position_only: bool) -> tuple[int, bool, float]:
        """From the rest pose (set untimed) iterate towards ``T`` (4, 4): (iterations, converged, µs)."""
        self._set_q(self.rest)
        solver, task = self.solvers[position_only]
        robot = self.robot
        start = time.perf_counter_ns()
        self._set_target(task, T, position_only)
        L = T.tolist()
        p, R = [row[3] for row in L[:3]], None if position_only else [row[:3] for row in L[:3]]
        it = 0
        converged = self._within(p, R)
        while not converged and it < PLACO_ITERATIONS:
            solver.solve(True)
            robot.update_kinematics()
            it += 1
            converged = self._within(p, R)
        return it, converged, (time.perf_counter_ns() - start) * 1e-3

    def track(self, circle: list[np.ndarray], position_only: bool) -> tuple[list[float], list[float]]:
        """From the bent pose, one iteration a frame towards each pose of ``circle``: (µs, miss [m]) per frame."""
        self._set_q(self.bent)
        solver, task = self.solvers[position_only]
        robot, us, miss = self.robot, [], []
        for T in circle:
            start = time.perf_counter_ns()
            self._set_target(task, T, position_only)
            solver.solve(True)
            robot.update_kinematics()
            us.append((time.perf_counter_ns() - start) * 1e-3)
            miss.append(float(np.linalg.norm(robot.get_T_world_frame(self.effector)[:3, 3] - T[:3, 3])))
        return us, miss


def measure(peer, problem: Problem, position_only: bool) -> Figures:
    """One peer's figures on ``problem``, after a few untimed solves (first calls, caches)."""
    for T in problem.reach[:3]:
        peer.reach(T, position_only)
    peer.track(problem.circle[:10], position_only)
    runs = [peer.reach(T, position_only) for T in problem.reach]
    us, miss = peer.track(problem.circle, position_only)
    return Figures([r[2] for r in runs], [r[0] for r in runs], [r[1] for r in runs], us, miss)


def load_placo():
    """``(placo module, None)`` or ``(None, why it cannot run)``."""
    try:
        import placo
    except ImportError as exc:  # an optional peer
        return None, f"placo cannot be imported ({exc}); install it with: python -m pip install placo"
    return placo, None


def _row(label: str, f: Figures, both: list[bool]) -> str:
    solved_us = [t for t, ok in zip(f.reach_us, both) if ok]
    within = sum(m <= TRACKED for m in f.track_miss)
    return (f"| {label} | {statistics.median(f.reach_us):.0f} | {statistics.median(solved_us):.0f} | "
            f"{statistics.median(f.reach_iterations):.0f} | {100.0 * sum(f.solved) / len(f.solved):.1f}% | "
            f"{statistics.median(f.track_us):.1f} | {within} / {len(f.track_miss)} | "
            f"{1e3 * max(f.track_miss):.2f} |")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--problems", type=int, default=200, help="reach targets per chain and kind")
    parser.add_argument("--frames", type=int, default=300, help="tracking frames round the circle")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--before", type=Path, help="another checkout of gsik (with its .venv) to alternate with")
    parser.add_argument("--rounds", type=int, default=2, help="alternations with --before")
    args = parser.parse_args(argv)
    if args.before is not None:
        if not (args.before / ".venv" / "bin" / "python").is_file():
            parser.error(f"--before {args.before}: no .venv/bin/python there (the checkout's own interpreter runs "
                         "its gsik)")
        alternate(args)
        return
    placo, why = load_placo()
    print(f"load average at start: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; gsik {gsik.__file__}")
    if placo is None:
        print(f"placo skipped: {why}")
    with tempfile.TemporaryDirectory() as folder:
        probs = problems(Path(folder), args.problems, args.frames, args.seed)
        print("\n| chain, targets, peer | reach µs/solve | µs, both solved | iterations | solved | "
              "track µs/frame | frames within 1 mm | max miss mm |\n|---|---:|---:|---:|---:|---:|---:|---:|")
        for problem in probs:
            peers = [GsikPeer(problem)] + ([PlacoPeer(problem, placo)] if placo else [])
            for position_only in (False, True):
                figures = [measure(peer, problem, position_only) for peer in peers]
                both = [all(ok) for ok in zip(*(f.solved for f in figures))]
                kind = "position" if position_only else "6-DOF"
                for peer, f in zip(peers, figures):
                    label = f"{problem.chain.name} ({len(problem.chain.dof_names)} DOF), {kind}, {peer.name}"
                    print(_row(label, f, both), flush=True)
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}; {args.problems} reach targets per row (seed "
          f"{args.seed}), {args.frames} tracking frames; medians over problems / frames")


def alternate(args) -> None:
    """``args.rounds`` times: this checkout's run, then ``args.before``'s (its own interpreter), one after the other."""
    common = ["--problems", str(args.problems), "--frames", str(args.frames), "--seed", str(args.seed)]
    here = Path(__file__).resolve().parent.parent
    runs = {"this checkout": (sys.executable, here),
            f"before: {args.before}": (str(args.before / ".venv" / "bin" / "python"), args.before.resolve())}
    for r in range(1, args.rounds + 1):
        for label, (python, checkout) in runs.items():
            print(f"\n## {label}, round {r} of {args.rounds}", flush=True)
            # Each run imports its own checkout's gsik first, whatever PYTHONPATH this run was given.
            env = {**os.environ, "PYTHONPATH": str(checkout)}
            subprocess.run([python, str(Path(__file__).resolve())] + common, check=True, env=env)


if __name__ == "__main__":
    main()
