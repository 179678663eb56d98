"""Compile (and cache) every numba kernel gsik runs, by calling the public API once.

``python -m gsik._warmup`` is what a regular install runs while the package is built (``setup.py``), so that the
first start after ``pip install`` loads compiled kernels from the package's ``__pycache__`` folders instead of
compiling for tens of seconds. Running it again only loads the cache.
"""

from __future__ import annotations

import sys
import time

import numpy as np


def compile_kernels() -> float:
    """Run each public entry point that reaches a kernel once; returns the seconds it took."""
    import gsik
    from gsik import kinematics, pgs

    start = time.perf_counter()
    biped = gsik.load_skeleton("biped")
    for settings in (gsik.SolverSettings(), gsik.SolverSettings.paper()):
        solver = gsik.Solver(biped, settings=settings)
        targets = {n: gsik.Target.from_transform(T) for n, T in solver.effector_poses().items()}
        solver.step(targets)
        name, T = next(iter(solver.effector_poses().items()))
        solver.move_target(name, T[:3, 3], T[:3, :3])  # gsik.kernels.targets
        solver.solve(targets)
        solver.set_root("left_foot")
    solver = gsik.Solver(biped)  # the prioritised path (kernels.accept, .control, .priority): two levels, a posture
    solver.set_posture()
    poses = solver.effector_poses()
    solver.step({n: gsik.Target.from_transform(T, priority=k % 2) for k, (n, T) in enumerate(poses.items())})
    solver.move_target(name, poses[name][:3, 3] + 0.01)  # a moved target gathered (kernels.gather), then stepped
    solver.step()
    solver.solve()  # a solve's posture settle (kernels.settle)
    solver.set_balance(True)  # balance's levels are packed from Python: the step's kernels one by one
    solver.step()
    kinematics.jacobian(biped, biped.rest)
    A = np.eye(3) * 2.0
    pgs.projected_gauss_seidel(A, np.ones(3), -np.ones(3), np.ones(3))
    pgs.solve_bounded(A, np.ones(3), -np.ones(3), np.ones(3))
    from gsik.skinning import SkinBinding, skin_into, skinned

    one = np.ones((1, 3))
    binding = SkinBinding(one, one, np.zeros((1, 1)), np.ones((1, 1)), np.zeros(1), np.eye(4)[None],
                          np.zeros((0, 3)), one)
    skinned(binding, np.eye(4)[None])
    skin_into(binding, np.eye(4)[None], np.zeros((1, 3), np.float32), np.zeros((1, 3), np.float32))  # the studio's
    return time.perf_counter() - start


def kernel_cache_stats() -> tuple[int, int]:
    """``(hits, misses)`` of numba's on-disk cache over every kernel gsik has loaded in this process."""
    hits = misses = 0
    for name, module in list(sys.modules.items()):
        if name != "gsik" and not name.startswith("gsik."):
            continue
        for obj in vars(module).values():
            stats = getattr(obj, "stats", None)
            if stats is not None and hasattr(stats, "cache_hits") and getattr(obj, "py_func", None) is not None:
                hits += sum(stats.cache_hits.values())
                misses += sum(stats.cache_misses.values())
    return hits, misses


def main() -> int:
    seconds = compile_kernels()
    if "--quiet" not in sys.argv:
        print(f"gsik: kernels compiled and cached in {seconds:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
