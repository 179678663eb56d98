"""Reach and best reach of ``Solver.solve()``, side by side with another checkout of gsik (today's method).

    python benchmarks/bench_reach.py [--quick] [--before PATH]

Figures, on the 30-DOF biped, targets (position and orientation on all five
effectors) taken from random poses within the limits, each solved from the
rest pose; success means within 1 mm and 1 degree on every effector:

- one attempt, 100 linearisations (``restarts=0``), and a plain NumPy damped
  least squares (DLS) baseline with the same budget;
- the defaults (restarts on): success, median, 90th percentile and mean time;
- the first solve of a new unreachable target (a hand 3 m from the pelvis);
- a held unreachable target (a hand 3 m away) solved again and again: time
  per call, attempts, linearisations and sweeps reported.

``--before PATH`` runs the same measurements with PATH's own
``.venv/bin/python`` (a checkout of the code before a change) in the same
run, and prints both. Uses only the public API, so it runs on either.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from gsik import Solver, Target, load_skeleton
from gsik.kinematics import jacobian
from gsik.rotations import rotvec_from_matrix

POSITION_OK = 1e-3  # [m]
ORIENTATION_OK = np.radians(1.0)  # [rad]


def problems(skeleton, count: int, seed: int = 1) -> list[dict[str, Target]]:
    """Targets from ``count`` random poses within the limits (the seed of :func:`gsik.benchmark.reach`)."""
    rng = np.random.default_rng(seed)
    W = Solver(skeleton).world_from_root
    return [{n: Target.from_transform(T) for n, T in skeleton.effector_poses(rng.uniform(skeleton.lower,
                                                                                       skeleton.upper), W).items()}
            for _ in range(count)]


def _ok(result) -> bool:
    return result.max_position_error < POSITION_OK and result.max_orientation_error < ORIENTATION_OK


def _solve_all(solver, skeleton, sets) -> dict:
    ok, times, attempts, iterations = [], [], [], []
    for targets in sets:
        t = time.perf_counter_ns()
        r = solver.solve(targets, q0=skeleton.rest)
        times.append((time.perf_counter_ns() - t) / 1e6)
        ok.append(_ok(r))
        attempts.append(r.attempts)
        iterations.append(r.iterations)
    t_ms = np.array(times)
    return dict(success=float(np.mean(ok)), median_ms=float(np.median(t_ms)), p90_ms=float(np.percentile(t_ms, 90)),
                mean_ms=float(np.mean(t_ms)),
                mean_attempts=float(np.mean(attempts)), median_iterations=float(np.median(iterations)),
                median_ok_ms=float(np.median(t_ms[np.array(ok)])) if any(ok) else float("nan"))


def held_unreachable(skeleton, calls: int = 30) -> dict:
    """A hand 3 m away, the other effectors where they stand, solved ``calls`` times in a row."""
    solver = Solver(skeleton)
    targets = {n: Target.from_transform(T) for n, T in solver.effector_poses().items()}
    targets["left_hand"] = Target([-3.0, 2.0, 2.5])
    solver.solve(targets)  # compile and settle
    times, results = [], []
    for _ in range(calls):
        t = time.perf_counter_ns()
        results.append(solver.solve(targets))
        times.append((time.perf_counter_ns() - t) / 1e6)
    last = results[-1]
    return dict(median_ms=float(np.median(times)), status=last.status.name.lower().replace("_", " "),
                attempts=int(last.attempts), iterations=int(last.iterations), sweeps=int(last.sweeps),
                nan=bool(not all(np.all(np.isfinite(r.q)) for r in results)),
                hand_error_m=float(last.errors()["left_hand"][0]))


def first_unreachable(skeleton, count: int = 20, seed: int = 2) -> dict:
    """The first ``solve()`` of a new unreachable target: the left hand 3 m from the pelvis in a random
    direction, the other effectors where they stand, from the rest pose; ``count`` targets."""
    rng = np.random.default_rng(seed)
    times, attempts, iterations = [], [], []
    for _ in range(count):
        solver = Solver(skeleton)
        targets = {n: Target.from_transform(T) for n, T in solver.effector_poses().items()}
        direction = rng.normal(size=3)
        targets["left_hand"] = Target(targets["pelvis"].position + 3.0 * direction / np.linalg.norm(direction))
        t = time.perf_counter_ns()
        r = solver.solve(targets)
        times.append((time.perf_counter_ns() - t) / 1e6)
        attempts.append(r.attempts)
        iterations.append(r.iterations)
    return dict(median_ms=float(np.median(times)), mean_attempts=float(np.mean(attempts)),
                median_iterations=float(np.median(iterations)))


def measure(count: int) -> dict:
    """Every figure of this benchmark for the gsik this interpreter imports."""
    sk = load_skeleton("biped")
    sets = problems(sk, count)
    Solver(sk, restarts=0).solve(sets[0], q0=sk.rest)  # compile before timing
    one = _solve_all(Solver(sk, max_iterations=100, restarts=0), sk, sets)
    full = _solve_all(Solver(sk), sk, sets)
    return dict(one_attempt=one, restarts=full, held=held_unreachable(sk), first=first_unreachable(sk))


def dls_first_attempt(skeleton, sets, damping: float = 0.03, iterations: int = 100) -> dict:
    """Plain NumPy damped least squares: ``dq = J^T (J J^T + damping^2 I)^-1 e``, clamped to the limits.

    The solver's row weights (orientation rows 0.5 m/rad); damping 0.03 was
    the best of 0.001-0.2 on this problem set.
    """
    W = Solver(skeleton).world_from_root
    names = [n for n in skeleton.effector_sites if n != skeleton.root]
    w = np.sqrt(np.tile([1.0, 1.0, 1.0, 0.5, 0.5, 0.5], len(names)))
    ok, times = [], []
    for targets in sets:
        t = time.perf_counter_ns()
        q = skeleton.rest.copy()
        for _ in range(iterations + 1):
            poses = skeleton.effector_poses(q, W)
            e = np.concatenate([np.concatenate([targets[n].position - poses[n][:3, 3],
                                                rotvec_from_matrix(targets[n].rotation @ poses[n][:3, :3].T)])
                                for n in names])
            pos, ori = e.reshape(-1, 6)[:, :3], e.reshape(-1, 6)[:, 3:]
            good = np.linalg.norm(pos, axis=1).max() < POSITION_OK and np.linalg.norm(ori, axis=1).max() < ORIENTATION_OK
            if good:
                break
            J = jacobian(skeleton, q, names, world_from_root=W) * w[:, None]
            dq = J.T @ np.linalg.solve(J @ J.T + damping ** 2 * np.eye(J.shape[0]), e * w)
            q = np.clip(q + dq, skeleton.lower, skeleton.upper)
        times.append((time.perf_counter_ns() - t) / 1e6)
        ok.append(good)
    return dict(success=float(np.mean(ok)), median_ms=float(np.median(times)))


def _row(label: str, fmt, after: dict, before: dict | None) -> str:
    cells = [fmt(after)] + ([fmt(before)] if before else [])
    return f"| {label} | " + " | ".join(cells) + " |"


def table(after: dict, before: dict | None, dls: dict, count: int) -> str:
    head = "| figure | this checkout |" + (" before |" if before else "")
    lines = [f"### Reach: {count} random poses, 5 effectors x 6-DOF, from the rest pose (1 mm, 1 degree)", "",
             head, "|---|---|" + ("---|" if before else "")]
    b = before or {}
    rows = [
        ("one attempt, 100 linearisations: success", lambda d: f"{100 * d['one_attempt']['success']:.1f}%"),
        ("one attempt: median / p90 / mean time", lambda d: f"{d['one_attempt']['median_ms']:.2f} / "
                                                            f"{d['one_attempt']['p90_ms']:.2f} / "
                                                            f"{d['one_attempt']['mean_ms']:.2f} ms"),
        ("one attempt: median linearisations", lambda d: f"{d['one_attempt']['median_iterations']:.0f}"),
        ("defaults (restarts): success", lambda d: f"{100 * d['restarts']['success']:.1f}%"),
        ("defaults: median / p90 / mean time", lambda d: f"{d['restarts']['median_ms']:.2f} / "
                                                         f"{d['restarts']['p90_ms']:.2f} / {d['restarts']['mean_ms']:.2f} ms"),
        ("defaults: mean attempts", lambda d: f"{d['restarts']['mean_attempts']:.2f}"),
        ("new unreachable target: first solve(), median of 20",
         lambda d: f"{d['first']['median_ms']:.2f} ms ({d['first']['median_ms'] / d['one_attempt']['median_ok_ms']:.1f}x"
                   f" a reachable solve), {d['first']['mean_attempts']:.1f} attempts, "
                   f"{d['first']['median_iterations']:.0f} linearisations"),
        ("held unreachable: time per solve()", lambda d: f"{d['held']['median_ms']:.2f} ms "
                                                         f"({d['held']['median_ms'] / d['one_attempt']['median_ok_ms']:.1f}x"
                                                         " a reachable solve)"),
        ("held unreachable: status, attempts, linearisations, sweeps reported",
         lambda d: f"{d['held']['status']}, {d['held']['attempts']}, {d['held']['iterations']}, {d['held']['sweeps']}"),
        ("held unreachable: NaN / hand error", lambda d: f"{'yes' if d['held']['nan'] else 'no'} / "
                                                         f"{d['held']['hand_error_m']:.4f} m"),
    ]
    lines += [_row(label, fmt, after, b or None) for label, fmt in rows]
    lines += ["", f"NumPy DLS (damping 0.03, clamped to the limits), one attempt, 100 linearisations: "
                  f"{100 * dls['success']:.1f}% success, median {dls['median_ms']:.1f} ms"]
    return "\n".join(lines)


def main(argv: list[str]) -> None:
    count = 200 if "--quick" in argv else 1000
    if "--json" in argv:
        print(json.dumps(measure(count)))
        return
    before = None
    if "--before" in argv:
        path = Path(argv[argv.index("--before") + 1])
        out = subprocess.run([str(path / ".venv/bin/python"), str(Path(__file__).resolve()), "--json"]
                             + (["--quick"] if "--quick" in argv else []),
                             cwd=path, check=True, capture_output=True, text=True).stdout
        before = json.loads(out.strip().splitlines()[-1])
    after = measure(count)
    sk = load_skeleton("biped")
    print(table(after, before, dls_first_attempt(sk, problems(sk, count)), count))


if __name__ == "__main__":
    main(sys.argv[1:])
