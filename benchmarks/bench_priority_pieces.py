"""Where the studio's prioritised step spends its time: the compiled pieces, timed in compiled loops (CPU time).

The drag of ``bench_drag.py`` (the biped, pelvis and left foot pinned, both hands at priority 1 round a circle) with
the studio's natural posture (``prior``: the bundled prior's full 30 x 30 precision factor, ``tracking_steps=3``) or
the drag's start pose (``pins``: a diagonal factor). Printed, one run:

1. In how many of ``--frames`` frames of ``Solver.step()`` the last :func:`gsik.kernels.accept.control_step` made
   restoring steps (``R_RESTORED``).
2. At every 20th frame's committed pose, the pieces of one step, each timed ``--repeat`` times inside one compiled
   loop (no dispatch), medians over the frames [µs], in the controller's buffers: the strict-priority kernel (pivoted
   QR every level) on its first 1, 2 and all 3 packed levels (the last's cost is the difference; the pins' and hands'
   levels alone are what a restoring step solves), the step's kernel on all of them as the step calls it
   (:func:`~gsik.kernels.range_space.prioritized_step_range_in`: every level by the normal equations where that is
   exact, with how many passes took them, the first a posture not yet seen; and the QR path it falls back to,
   :func:`~gsik.kernels.posture_level.prioritized_step_posture_in`, a full or diagonal posture by its normal
   equations; a diagonal one timed by the pivoted QR too, as the step solved it before),
   :func:`~gsik.kernels.control.linearise`, :func:`~gsik.kernels.control.trial` (forward kinematics and level state),
   and :func:`~gsik.kernels.control.step_trial` (the three, with the dampings and the box, as a step calls them).

Run: ``python benchmarks/bench_priority_pieces.py [--posture prior|pins] [--frames 300]``. Nothing here is asserted
by the tests.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_drag import _solver, _targets  # noqa: E402  (the drag's solver and targets, in one place)

from gsik._jit import njit  # noqa: E402
from gsik.kernels import accept, control, posture_level, priority, range_space  # noqa: E402


@njit
def _priority_loop(repeat, pw, rows, errors, weights, starts, dampings, lo, hi, tols, dq):
    rank_tol, box_tol, box_rel_tol = tols
    for _ in range(repeat):
        priority.prioritized_step_in(pw, rows, errors, weights, starts, dampings, lo, hi, rank_tol, box_tol,
                                     box_rel_tol, dq)


@njit
def _posture_loop(repeat, pw, rows, errors, weights, starts, dampings, lo, hi, tols, normal, bound, dq, below):
    rank_tol, box_tol, box_rel_tol = tols
    for _ in range(repeat):
        posture_level.prioritized_step_posture_in(pw, rows, errors, weights, starts, dampings, lo, hi, rank_tol,
                                                  box_tol, box_rel_tol, normal, bound, dq, below)


@njit
def _range_loop(repeat, rw, pw, rows, errors, weights, starts, dampings, lo, hi, tols, normal, bound, dq, below):
    rank_tol, box_tol, box_rel_tol = tols
    for _ in range(repeat):
        range_space.prioritized_step_range_in(rw, pw, rows, errors, weights, starts, dampings, lo, hi, rank_tol,
                                              box_tol, box_rel_tol, normal, bound, dq, below)


@njit
def _linearise_loop(repeat, task_model, tasks, posture, q, R, p, e, wk):
    for _ in range(repeat):
        control.linearise(task_model, tasks, posture, q, R, p, e, wk)


@njit
def _trial_loop(repeat, fk, tasks, posture, root, W, lower, upper, q, dq, wk):
    for _ in range(repeat):
        control.trial(fk, tasks, posture, root, W, lower, upper, q, dq, 1.0, wk)


@njit
def _step_trial_loop(repeat, task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e, costs, lam,
                     base, near, tols, wk):
    for _ in range(repeat):
        control.step_trial(task_model, fk, tasks, posture, root, W, lower, upper, max_step, q, R, p, e, costs, lam,
                           base, near, tols, wk)


def _cpu_us(loop, repeat: int, *args) -> float:
    """µs of CPU time per pass of ``loop(repeat, *args)`` (compiled and warmed first)."""
    loop(1, *args)
    t0 = time.process_time()
    loop(repeat, *args)
    return (time.process_time() - t0) / repeat * 1e6


def _pieces(solver, repeat: int) -> dict[str, float | tuple[int, int]]:
    """The pieces of a step from the solver's pose [µs]: the levels linearised and boxed there first."""
    c = solver._controller
    wk, s, tasks = c._work, c._settings, c._tasks_in
    q, R, p = solver._q.copy(), solver._ws.R.copy(), solver._ws.p.copy()
    control.linearise(c._task_model, tasks, c._posture_rows, q, R, p, c._cache.e.copy(), wk)
    control.dampings_into(c._cache.costs, c._near, solver._ws.lam[0], s.damping, True, wk.dampings)
    control.box(q, q, c._lower, c._upper, s.max_step, wk.lo, wk.hi)
    packed = (wk.rows.copy(), wk.errors.copy(), wk.weights.copy())
    dq = np.zeros_like(q)
    out = {}
    for levels in range(1, len(wk.dampings) + 1):
        out[f"priority kernel, levels 0-{levels - 1}"] = _cpu_us(
            _priority_loop, repeat, wk.priority, *packed, tasks.starts[:levels + 1], wk.dampings[:levels], wk.lo,
            wk.hi, c._tols, dq)
    rows = c._posture_rows
    rw = range_space.make_range_work(wk.range_work.F.shape[0], q.shape[0])  # its own: the drag's counts stay
    out["the step's kernel, all levels"] = _cpu_us(_range_loop, repeat, rw, wk.priority, *packed, tasks.starts,
                                                    wk.dampings, wk.lo, wk.hi, c._tols, rows.normal, rows.share[0],
                                                    dq, wk.below)
    out["  by the normal equations"] = (int(rw.state[range_space.S_TAKEN]), repeat + 1)  # passes
    out["  the same by the QR path"] = _cpu_us(_posture_loop, repeat, wk.priority, *packed, tasks.starts,
                                               wk.dampings, wk.lo, wk.hi, c._tols, rows.normal, rows.share[0],
                                               dq, wk.below)
    if rows.normal.shape[0] > 0 and not posture_level.is_full(rows.normal):  # a diagonal posture (pins): by the QR
        out["  the same, posture by pivoted QR"] = _cpu_us(
            _posture_loop, repeat, wk.priority, *packed, tasks.starts, wk.dampings, wk.lo, wk.hi, c._tols,
            np.zeros((0, q.shape[0])), 0.0, dq, wk.below)
    out["linearise"] = _cpu_us(_linearise_loop, repeat, c._task_model, tasks, c._posture_rows, q, R, p,
                               c._cache.e.copy(), wk)
    out["trial (FK + level state)"] = _cpu_us(_trial_loop, repeat, c._fk_model, tasks, c._posture_rows, c._root,
                                              solver._W, c._lower, c._upper, q, dq, wk)
    out["step_trial (all of the above)"] = _cpu_us(
        _step_trial_loop, repeat, c._task_model, c._fk_model, tasks, rows, c._root, solver._W, c._lower, c._upper,
        s.max_step, q, R, p, c._cache.e.copy(), c._cache.costs.copy(), solver._ws.lam[0], s.damping, c._near, c._tols,
        wk)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--posture", choices=("prior", "pins"), default="prior")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=500)
    a = ap.parse_args()
    solver, poses = _solver("prior" if a.posture == "prior" else "start", 1)
    restored = 0
    rows: list[dict] = []
    for frame in range(a.frames):
        solver.step(_targets(poses, frame, 1))
        restored += bool(solver._controller._cache.out[accept.R_RESTORED])
        if frame % 20 == 19:
            rows.append(_pieces(solver, a.repeat))
    print(f"{a.posture}: the frame's last compiled step made restoring steps in {restored} of {a.frames} frames; "
          f"medians over {len(rows)} poses, {a.repeat} passes each:")
    for name in rows[0]:
        if isinstance(rows[0][name], tuple):  # passes: the range over the poses
            taken = [r[name][0] for r in rows]
            print(f"  {name:34s} {min(taken)}-{max(taken)} of {rows[0][name][1]} passes")
            continue
        print(f"  {name:34s} {np.median([r[name] for r in rows]):7.1f} µs")


if __name__ == "__main__":
    main()
