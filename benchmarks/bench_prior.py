"""Naturalness benchmark: a learned pose prior against no posture and the rest posture, from few targets.

The real clip (default ``../shared/mocap/mocap_bvhtools_test.bvh`` beside the
repository) is retargeted onto the biped (:mod:`gsik.anim.retarget`). Its
frames are cut into ``--folds`` contiguous time segments; for each segment a
prior is learned from the others (:func:`gsik.prior.fit_prior`) and every
``--stride``-th pose of the held-out segment is a test pose ``q*``. The biped
stands on its right foot where ``q*`` puts it (the IK root), the solver gets
only the targets taken from ``q*`` (full poses) of

* ``five``: pelvis, head, both hands and the left foot;
* ``hands+feet``: both hands and the left foot;

and ``solve()`` starts from the rest pose with no posture, the rest posture
(``set_posture()``, weight 1) and the learned prior (:func:`gsik.prior.use_prior`).
Printed per case: mean and 95th percentile of the joints' position error
against ``q*`` (every joint but the hips; "interior": knees, elbows,
shoulders and neck, which no target's pose fixes rigidly), the largest target error, and the median step time
(``step()`` from the rest pose towards the targets) with its ratio to the rest
posture's.

Run: ``python benchmarks/bench_prior.py [--clip PATH] [--folds 5] [--stride 20] [--cache motion.npz]``
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
from gsik.io.bvh import read_bvh
from gsik.kinematics import world_frames
from gsik.prior import fit_prior, segments, use_prior

CLIP = Path(__file__).resolve().parents[1].parent / "shared" / "mocap" / "mocap_bvhtools_test.bvh"
TARGET_SETS = {
    "five": ("pelvis", "head", "left_hand", "right_hand", "left_foot"),
    "hands+feet": ("left_hand", "right_hand", "left_foot"),
}
POSTURES = ("none", "rest", "prior")
#: Joints whose position the comparison counts: every joint but the top (hips), which the pelvis is.
JOINTS = ("waist", "neck", "atlas", "left_shoulder", "left_elbow", "right_shoulder", "right_elbow",
          "left_hip", "left_knee", "left_ankle", "right_hip", "right_knee", "right_ankle")
#: Interior joints: mid-limb and spine joints no target's pose fixes rigidly (a hip is rigid with the pelvis,
#: an ankle with its foot, the waist with the pelvis, the atlas with the head).
INTERIOR = ("left_knee", "right_knee", "left_elbow", "right_elbow", "left_shoulder", "right_shoulder", "neck")
STEP_SAMPLES = 40
#: Further attempts of solve() (the default 20 makes a run take hours on the prioritised path); the same for all.
RESTARTS = 2


def _set_posture(solver: Solver, kind: str, prior) -> None:
    if kind == "none":
        solver.set_posture(None, 0.0)
    elif kind == "rest":
        solver.set_posture(None, 1.0)
    else:
        use_prior(solver, prior)


def _case(sk, Q_test, W_test, prior, names, kind) -> dict:
    """Solve every test pose for one target set and posture; errors [mm] and step times [s]."""
    joints = [sk.frame_of(j) for j in JOINTS]
    interior = [JOINTS.index(j) for j in INTERIOR]
    joint_err, target_err, step_times = [], [], []
    for i, (q, W) in enumerate(zip(Q_test, W_test)):
        R, p = world_frames(sk, q, W, "pelvis")
        foot = sk.frame_of("right_foot")
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R[foot], p[foot]
        solver = Solver(sk, world_from_root=T, restarts=RESTARTS)
        _set_posture(solver, kind, prior)
        targets = {}
        for n in names:
            Tn = np.eye(4)
            Tn[:3, :3], Tn[:3, 3] = R[sk.frame_of(n)], p[sk.frame_of(n)]
            targets[n] = Target.from_transform(Tn)
        if i < STEP_SAMPLES:  # a dragging step: the second one (the first builds the prioritised controller)
            solver.step(targets)
            t = time.perf_counter()
            solver.step()
            step_times.append(time.perf_counter() - t)
        r = solver.solve(targets, q0=sk.rest)
        got = solver.world_positions()
        joint_err.append(np.linalg.norm(got[joints] - p[joints], axis=1))
        target_err.append(max(r.errors()[n][0] for n in names))
    e = np.array(joint_err) * 1000.0
    return dict(all=e, interior=e[:, interior], target=np.array(target_err) * 1000.0, step=np.array(step_times))


def _met(m: dict) -> str:
    """Share of test poses whose targets were all met within 1 mm."""
    return f"{100 * np.mean(m['target'] < 1.0):.0f}%"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--clip", type=Path, default=CLIP)
    ap.add_argument("--folds", type=int, default=5)
    ap.add_argument("--stride", type=int, default=20, help="every n-th held-out frame is a test pose")
    ap.add_argument("--frames", type=int, default=0, help="use only the clip's first n frames (0: all)")
    ap.add_argument("--cache", type=Path, help="keep the retargeted motion in this .npz (read it if it exists)")
    args = ap.parse_args()
    sk = load_skeleton("biped")
    clip = read_bvh(args.clip)
    if args.frames:
        from gsik.io.bvh import BvhClip
        clip = BvhClip(clip.joints, clip.frame_time, clip.motion[:args.frames])
    print(f"## Pose prior: {args.clip.name}, {clip.n_frames} frames, {args.folds} time folds, every "
          f"{args.stride}th held-out frame; load {os.getloadavg()[0]:.2f}\n")
    Q, W = _retargeted(sk, clip, args.cache)
    warm = Solver(sk)
    warm.set_posture(None, 1.0)
    warm.solve({"left_hand": Target([0.2, 0.3, 1.0])})  # compile before timing
    results = {(s, k): [] for s in TARGET_SETS for k in POSTURES}
    for held in segments(len(Q), args.folds):
        prior = fit_prior(np.delete(Q, held, axis=0), sk)
        test = held[::args.stride]
        for s, names in TARGET_SETS.items():
            for k in POSTURES:
                results[s, k].append(_case(sk, Q[test], W[test], prior, names, k))
    _print(results)


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


def _print(results) -> None:
    print("| targets | posture | joints mean / p95 [mm] | interior mean / p95 [mm] | targets met (1 mm) "
          "| largest target error [mm] | step time median [ms] | step time / rest posture's |")
    print("|---|---|---|---|---|---|---|---|")
    for s in TARGET_SETS:
        merged = {k: {f: np.concatenate([r[f].ravel() for r in results[s, k]]) for f in results[s, k][0]}
                  for k in POSTURES}
        rest_step = np.median(merged["rest"]["step"])
        for k in POSTURES:
            m = merged[k]
            print(f"| {s} | {k} | {m['all'].mean():.0f} / {np.percentile(m['all'], 95):.0f} "
                  f"| {m['interior'].mean():.0f} / {np.percentile(m['interior'], 95):.0f} "
                  f"| {_met(m)} | {m['target'].max():.3f} | {1000 * np.median(m['step']):.2f} "
                  f"| {np.median(m['step']) / rest_step:.2f} |")
    print()


if __name__ == "__main__":
    main()
