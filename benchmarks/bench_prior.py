"""Naturalness benchmark: learned pose priors against no posture and the rest posture, from few targets.

The real clip (default ``../shared/mocap/mocap_bvhtools_test.bvh`` beside the
repository) is retargeted onto the biped (:mod:`gsik.anim.retarget`). Its
frames are cut into ``--folds`` contiguous time segments; for each segment the
priors are learned from the rest of the clip less ``--gap`` frames either side
of the segment (so no training pose is a near copy of a test pose), and every
``--stride``-th pose of the held-out segment is a test pose ``q*``. The biped
stands on its right foot where ``q*`` puts it (the IK root), the solver gets
only the targets taken from ``q*`` (full poses) of

* ``five``: pelvis, head, both hands and the left foot;
* ``hands+feet``: both hands and the left foot;

and ``solve()`` starts from the rest pose with no posture, the rest posture
(``set_posture()``, weight 1), the learned Gaussian (:func:`gsik.prior.use_prior`)
and the learned mixture of Gaussians (:func:`gsik.prior_mixture.solve_with_mixture`;
its component count chosen by cross-validation inside the training frames).
Printed per case: mean and 95th percentile of the joints' position error
against ``q*`` (every joint but the hips; "interior": knees, elbows,
shoulders and neck, which no target's pose fixes rigidly), the share of test
poses whose targets are all met within 1 mm, the largest target error, the
median step time (the second ``step()`` from the rest pose towards the
targets; the mixture's includes choosing its component) with its ratio to
the rest posture's, and the median ``solve()`` time; then the interior error
per fold, whose spread says how far one clip's figures carry.

Run: ``python benchmarks/bench_prior.py [--clip PATH] [--folds 5] [--gap 150] [--stride 20] [--cache motion.npz]``
(retargeting the whole clip takes minutes: ``--cache`` keeps it for the next run).
Nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from gsik import Solver, Target, load_skeleton
from gsik.anim.retarget import Retargeter
from gsik.io.bvh import BvhClip, read_bvh
from gsik.kinematics import world_frames
from gsik.prior import PosePrior, fit_prior, segments, use_prior
from gsik.prior_mixture import PoseMixture, fit_mixture, follow_mixture, solve_with_mixture

CLIP = Path(__file__).resolve().parents[1].parent / "shared" / "mocap" / "mocap_bvhtools_test.bvh"
TARGET_SETS = {
    "five": ("pelvis", "head", "left_hand", "right_hand", "left_foot"),
    "hands+feet": ("left_hand", "right_hand", "left_foot"),
}
POSTURES = ("none", "rest", "prior", "mixture")
#: Joints whose position the comparison counts: every joint but the top (hips), which the pelvis is.
JOINTS = ("waist", "neck", "atlas", "left_shoulder", "left_elbow", "right_shoulder", "right_elbow",
          "left_hip", "left_knee", "left_ankle", "right_hip", "right_knee", "right_ankle")
#: Interior joints: mid-limb and spine joints no target's pose fixes rigidly (a hip is rigid with the pelvis,
#: an ankle with its foot, the waist with the pelvis, the atlas with the head).
INTERIOR = ("left_knee", "right_knee", "left_elbow", "right_elbow", "left_shoulder", "right_shoulder", "neck")
STEP_SAMPLES = 40
#: Further attempts of solve() (the default 20 makes a run take hours on the prioritised path); the same for all.
RESTARTS = 2


class Posture:
    """How one posture kind is set, stepped and solved (the solver's posture; the mixture's component)."""

    def __init__(self, kind: str, prior: PosePrior, mixture: PoseMixture):
        self.kind, self.prior, self.mixture, self.component = kind, prior, mixture, None

    def set(self, solver: Solver) -> None:
        if self.kind == "none":
            solver.set_posture(None, 0.0)
        elif self.kind == "rest":
            solver.set_posture(None, 1.0)
        elif self.kind == "prior":
            use_prior(solver, self.prior)
        else:
            self.component = follow_mixture(solver, self.mixture)

    def step(self, solver: Solver, targets=None):
        """One dragging step; the mixture first re-chooses its component for the current pose (timed with it)."""
        if self.kind == "mixture":
            self.component = follow_mixture(solver, self.mixture, current=self.component)
        return solver.step(targets)

    def solve(self, solver: Solver, targets, q0):
        if self.kind == "mixture":
            return solve_with_mixture(solver, self.mixture, targets, q0)
        return solver.solve(targets, q0=q0)


def _world_from(sk, R: np.ndarray, p: np.ndarray, name: str) -> np.ndarray:
    """(4, 4) world transform of frame ``name`` from world rotations ``R`` (f, 3, 3) and positions ``p`` (f, 3)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R[sk.frame_of(name)], p[sk.frame_of(name)]
    return T


def _case(sk, Q_test, W_test, posture: Posture, names) -> dict:
    """Solve every test pose for one target set and posture; errors [mm], step and solve times [s]."""
    joints = [sk.frame_of(j) for j in JOINTS]
    interior = [JOINTS.index(j) for j in INTERIOR]
    joint_err, target_err, step_times, solve_times = [], [], [], []
    for i, (q, W) in enumerate(zip(Q_test, W_test)):
        R, p = world_frames(sk, q, W, "pelvis")
        solver = Solver(sk, world_from_root=_world_from(sk, R, p, "right_foot"), restarts=RESTARTS)
        posture.set(solver)
        targets = {n: Target.from_transform(_world_from(sk, R, p, n)) for n in names}
        if i < STEP_SAMPLES:  # a dragging step: the second one (the first builds the prioritised controller)
            posture.step(solver, targets)
            t = time.perf_counter()
            posture.step(solver)
            step_times.append(time.perf_counter() - t)
            posture.set(solver)
        t = time.perf_counter()
        r = posture.solve(solver, targets, sk.rest)
        solve_times.append(time.perf_counter() - t)
        got = solver.world_positions()
        joint_err.append(np.linalg.norm(got[joints] - p[joints], axis=1))
        target_err.append(max(r.errors()[n][0] for n in names))
    e = np.array(joint_err) * 1000.0
    return dict(all=e, interior=e[:, interior], target=np.array(target_err) * 1000.0, step=np.array(step_times),
                solve=np.array(solve_times))


def _met(m: dict) -> str:
    """How many test poses had all their targets met within 1 mm, of how many."""
    return f"{np.sum(m['target'] < 1.0)} / {len(m['target'])}"


def training_frames(n: int, held: np.ndarray, gap: int) -> np.ndarray:
    """Frames ``range(n)`` outside the held-out segment ``held`` and ``gap`` frames either side of it."""
    keep = np.ones(n, dtype=bool)
    keep[max(held[0] - gap, 0):held[-1] + gap + 1] = False
    return np.flatnonzero(keep)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--clip", type=Path, default=CLIP)
    ap.add_argument("--folds", type=int, default=5)
    ap.add_argument("--gap", type=int, default=150, help="frames either side of a held-out segment left out of "
                    "its training (default 150: 5 s at 30 fps)")
    ap.add_argument("--stride", type=int, default=20, help="every n-th held-out frame is a test pose")
    ap.add_argument("--frames", type=int, default=0, help="use only the clip's first n frames (0: all)")
    ap.add_argument("--targets", choices=tuple(TARGET_SETS), nargs="+", default=tuple(TARGET_SETS))
    ap.add_argument("--cache", type=Path, help="keep the retargeted motion in this .npz (read it if it exists)")
    args = ap.parse_args()
    sk = load_skeleton("biped")
    clip = read_bvh(args.clip)
    if args.frames:
        clip = BvhClip(clip.joints, clip.frame_time, clip.motion[:args.frames])
    Q, W = _retargeted(sk, clip, args.cache)
    folds = segments(len(Q), args.folds)
    n_test = sum(len(h[::args.stride]) for h in folds)
    print(f"## Pose prior: {args.clip.name}, {clip.n_frames} frames, {args.folds} time folds (training leaves "
          f"{args.gap} frames out either side), every {args.stride}th held-out frame: {n_test} test poses; "
          f"load {os.getloadavg()[0]:.2f}\n")
    warm = Solver(sk)
    warm.set_posture(None, 1.0)
    warm.solve({"left_hand": Target([0.2, 0.3, 1.0])})  # compile before timing
    results = {(s, k): [] for s in args.targets for k in POSTURES}
    for f, held in enumerate(folds):
        train = Q[training_frames(len(Q), held, args.gap)]
        prior = fit_prior(train, sk)
        mixture = fit_mixture(train, sk, shrinkage=prior.shrinkage)
        print(f"fold {f}: frames {held[0]}-{held[-1]} held out, {len(train)} training frames, shrinkage "
              f"{prior.shrinkage:g}, mixture of {mixture.n_components}; held-out log-likelihood Gaussian "
              f"{_gaussian_ll(prior, Q[held]):.1f}, mixture {mixture.log_likelihood(Q[held]):.1f}", flush=True)
        test = held[::args.stride]
        for s in args.targets:
            for k in POSTURES:
                results[s, k].append(_case(sk, Q[test], W[test], Posture(k, prior, mixture), TARGET_SETS[s]))
    print(f"\nload {os.getloadavg()[0]:.2f} at the end\n")
    _print(results, args.targets)
    _print_folds(results, args.targets)
    _print_paired(results, args.targets)


def _gaussian_ll(prior: PosePrior, X: np.ndarray) -> float:
    """Mean log-likelihood of rows ``X`` under ``prior``, on the mixture's scale (without the 2 pi constant)."""
    return float(np.mean(-0.5 * (np.linalg.slogdet(prior.covariance)[1] + prior.mahalanobis(X) ** 2)))


def _retargeted(sk, clip, cache: Path | None) -> tuple[np.ndarray, np.ndarray]:
    """The clip's poses on the biped (n, n_dofs) [rad] and the pelvis's transforms (n, 4, 4)."""
    if cache is not None and cache.exists():
        with np.load(cache, allow_pickle=False) as z:
            if len(z["q"]) == clip.n_frames:
                print(f"retargeted motion read from {cache}\n")
                return z["q"], z["world_from_root"]
    t = time.perf_counter()
    motion = Retargeter(sk, clip).retarget(clip).motion
    print(f"retargeted in {time.perf_counter() - t:.1f} s\n")
    if cache is not None:
        np.savez(cache, q=motion.q, world_from_root=motion.world_from_root)
    return np.asarray(motion.q), np.asarray(motion.world_from_root)


def _print(results, target_sets) -> None:
    print("| targets | posture | joints mean / p95 [mm] | interior mean / p95 [mm] | targets met (1 mm) "
          "| largest target error [mm] | step time median [ms] | step time / rest posture's | solve median [ms] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for s in target_sets:
        merged = {k: {f: np.concatenate([r[f].ravel() for r in results[s, k]]) for f in results[s, k][0]}
                  for k in POSTURES}
        rest_step = np.median(merged["rest"]["step"])
        for k in POSTURES:
            m = merged[k]
            print(f"| {s} | {k} | {m['all'].mean():.1f} / {np.percentile(m['all'], 95):.0f} "
                  f"| {m['interior'].mean():.1f} / {np.percentile(m['interior'], 95):.1f} "
                  f"| {_met(m)} | {m['target'].max():.3f} | {1000 * np.median(m['step']):.2f} "
                  f"| {np.median(m['step']) / rest_step:.2f} | {1000 * np.median(m['solve']):.0f} |")
    print()


def _print_folds(results, target_sets) -> None:
    """Interior mean error [mm] per held-out fold: the spread says how much one clip's figures can be trusted."""
    n_folds = len(next(iter(results.values())))
    print("Interior mean error [mm] per held-out fold (min-max over folds in the last column):\n")
    print("| targets | posture | " + " | ".join(f"fold {f}" for f in range(n_folds)) + " | spread |")
    print("|---|---|" + "---|" * (n_folds + 1))
    for s in target_sets:
        for k in POSTURES:
            per = [r["interior"].mean() for r in results[s, k]]
            print(f"| {s} | {k} | " + " | ".join(f"{v:.0f}" for v in per) + f" | {min(per):.0f}-{max(per):.0f} |")
    print()


def _print_paired(results, target_sets, resamples: int = 2000) -> None:
    """Mixture minus Gaussian, pose by pose (interior mean [mm]), with a bootstrap 95% interval over the poses."""
    rng = np.random.default_rng(0)
    print("Mixture minus Gaussian, interior mean error per test pose [mm] (negative: the mixture is better):\n")
    print("| targets | mean difference | bootstrap 95% interval | poses better / worse by > 1 mm |")
    print("|---|---|---|---|")
    for s in target_sets:
        d = np.concatenate([m["interior"].mean(axis=1) - g["interior"].mean(axis=1)
                            for m, g in zip(results[s, "mixture"], results[s, "prior"])])
        boot = d[rng.integers(len(d), size=(resamples, len(d)))].mean(axis=1)
        lo, hi = np.percentile(boot, [2.5, 97.5])
        print(f"| {s} | {d.mean():+.2f} | {lo:+.2f} to {hi:+.2f} | {np.sum(d < -1)} / {np.sum(d > 1)} of {len(d)} |")
    print()


if __name__ == "__main__":
    main()
