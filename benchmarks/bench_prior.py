"""Naturalness benchmark, leave one performer out: pose priors against no posture and the rest posture.

Every clip under ``--mocap`` (default ``../shared/mocap`` beside the
repository: the bvhtools clip and the CMU subjects 001, 002 and 003, four
performers; :func:`gsik.anim.mocap_set.performer_of`) is retargeted onto the
biped, every ``--stride``-th frame (:mod:`gsik.anim.mocap_set`; ``--cache``
keeps the result outside the repository for the next run). For each performer
in turn, every prior is learned from the OTHER performers' poses only, and up
to ``--test-poses`` of the held-out performer's poses, evenly spaced over their
clips, are the test poses ``q*``. The biped stands on its right foot where
``q*`` puts it (the IK root), the solver gets only the targets taken from
``q*`` (full poses) of

* ``hands+feet``: both hands and the left foot (the figure the default is chosen by);
* ``five``: pelvis, head, both hands and the left foot;

and ``solve()`` starts from the rest pose (2 further attempts) with each posture:

* ``none``; ``rest`` (``set_posture()``, weight 1);
* ``gaussian``: the plain global Gaussian of the training poses (:func:`gsik.prior.fit_prior`);
* ``mirror``: the Gaussian of the training poses and their mirror images (:func:`gsik.prior_variants.mirror_poses`);
* ``performer``: the performer normalised away (:func:`gsik.prior_variants.fit_prior_by_performer`);
* ``mirror+performer``: both;
* ``knn``: target-conditioned, the local Gaussian of the 64 training poses (and mirrors) whose targeted
  frames, relative to the root foot, are nearest the targets (:class:`gsik.prior_knn.ConditionedPrior`).

Printed per held-out performer and posture: the interior joints' position
error against ``q*`` (knees, elbows, shoulders, neck: what no target's pose
fixes rigidly), mean and 95th percentile [mm]; the test poses whose targets
are all met within 1 mm; the median step time (the second ``step()`` from the
rest pose towards the targets, a conditioned prior's conditioning included)
over the rest posture's. Then, per posture, the rest posture's interior mean
over the posture's, per performer, and their geometric mean: the default rule
(a prior is the default only when it is no worse than the rest posture for
every performer and at least 2x better on their geometric mean).

Run: ``python benchmarks/bench_prior.py [--mocap DIR] [--stride 10] [--test-poses 60] [--cache DIR]``.
Nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from gsik import Solver, Target, load_skeleton
from gsik.anim.mocap_set import RetargetedClip, retarget_clips
from gsik.kinematics import world_frames
from gsik.prior import fit_prior, use_prior
from gsik.prior_knn import ConditionedPrior
from gsik.prior_variants import fit_prior_by_performer, mirror_poses

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "mocap"
TARGET_SETS = {
    "hands+feet": ("left_hand", "right_hand", "left_foot"),
    "five": ("pelvis", "head", "left_hand", "right_hand", "left_foot"),
}
POSTURES = ("none", "rest", "gaussian", "mirror", "performer", "mirror+performer", "knn")
PRIORS = POSTURES[2:]
#: Interior joints: mid-limb and spine joints no target's pose fixes rigidly.
INTERIOR = ("left_knee", "right_knee", "left_elbow", "right_elbow", "left_shoulder", "right_shoulder", "neck")
STEP_SAMPLES = 25
#: Further attempts of solve(), the same for every posture.
RESTARTS = 2


def learn(train: dict[str, np.ndarray], sk) -> dict[str, object]:
    """Every prior of :data:`PRIORS` from the training performers' poses ``train`` (performer -> (n, n_dofs))."""
    everyone = np.concatenate(list(train.values()))
    mirrored = {p: np.concatenate([Q, mirror_poses(Q, sk)]) for p, Q in train.items()}
    both = np.concatenate(list(mirrored.values()))
    mirror = fit_prior(both, sk)
    return {"gaussian": fit_prior(everyone, sk), "mirror": mirror,
            "performer": fit_prior_by_performer(train, sk),
            "mirror+performer": fit_prior_by_performer(mirrored, sk),
            "knn": ConditionedPrior(mirror, both)}


def set_posture(solver: Solver, kind: str, prior, targets) -> None:
    """Make posture ``kind`` (``prior`` its learned prior, if any) the solver's, for ``targets``."""
    if kind == "none":
        solver.set_posture(None, 0.0)
    elif kind == "rest":
        solver.set_posture(None, 1.0)
    elif kind == "knn":
        prior.apply(solver, targets)
    else:
        use_prior(solver, prior)


def _world_from(sk, R: np.ndarray, p: np.ndarray, name: str) -> np.ndarray:
    """(4, 4) world transform of frame ``name`` from world rotations ``R`` (f, 3, 3) and positions ``p`` (f, 3)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R[sk.frame_of(name)], p[sk.frame_of(name)]
    return T


def run_case(sk, Q_test, W_test, kind: str, prior, names) -> dict:
    """Solve every test pose for one target set and posture: interior errors [mm], target errors [mm], times [s]."""
    interior = [sk.frame_of(j) for j in INTERIOR]
    err, target_err, step_times = [], [], []
    for i, (q, W) in enumerate(zip(Q_test, W_test)):
        R, p = world_frames(sk, q, W, "pelvis")
        solver = Solver(sk, world_from_root=_world_from(sk, R, p, "right_foot"), restarts=RESTARTS)
        targets = {n: Target.from_transform(_world_from(sk, R, p, n)) for n in names}
        set_posture(solver, kind, prior, targets)
        if i < STEP_SAMPLES:  # a dragging step: the second one (the first builds the prioritised controller)
            solver.step(targets)
            t = time.perf_counter()
            if kind == "knn":
                set_posture(solver, kind, prior, targets)
            solver.step(targets)
            step_times.append(time.perf_counter() - t)
        r = solver.solve(targets, q0=sk.rest)
        err.append(np.linalg.norm(solver.world_positions()[interior] - p[interior], axis=1))
        target_err.append(max(r.errors()[n][0] for n in names))
    return dict(interior=np.array(err) * 1000.0, target=np.array(target_err) * 1000.0, step=np.array(step_times))


def test_poses(clips: list[RetargetedClip], performer: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``n`` of ``performer``'s poses (n, n_dofs) and pelvis transforms (n, 4, 4), evenly spaced."""
    Q = np.concatenate([c.q for c in clips if c.performer == performer])
    W = np.concatenate([c.world_from_root for c in clips if c.performer == performer])
    keep = np.unique(np.linspace(0, len(Q) - 1, min(n, len(Q))).astype(int))
    return Q[keep], W[keep]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mocap", type=Path, default=MOCAP)
    ap.add_argument("--stride", type=int, default=10, help="retarget every n-th frame of each clip (default 10)")
    ap.add_argument("--test-poses", type=int, default=60, help="test poses per held-out performer at most")
    ap.add_argument("--targets", choices=tuple(TARGET_SETS), nargs="+", default=tuple(TARGET_SETS))
    ap.add_argument("--cache", type=Path, default=Path("/tmp/gsik-prior-cache"),
                    help="folder keeping the retargeted clips (outside the repository)")
    args = ap.parse_args()
    sk = load_skeleton("biped")
    t = time.perf_counter()
    clips = retarget_clips(sk, [args.mocap], args.stride, args.cache)
    performers = sorted({c.performer for c in clips})
    poses = {p: np.concatenate([c.q for c in clips if c.performer == p]) for p in performers}
    print(f"## Pose priors, leave one performer out: {len(clips)} clips under {args.mocap}, every "
          f"{args.stride}th frame retargeted ({time.perf_counter() - t:.0f} s), performers "
          + ", ".join(f"{p} ({len(poses[p])} poses)" for p in performers)
          + f"; up to {args.test_poses} test poses each; load {os.getloadavg()[0]:.2f}\n", flush=True)
    warm = Solver(sk)
    warm.set_posture(None, 1.0)
    warm.solve({"left_hand": Target([0.2, 0.3, 1.0])})  # compile before timing
    results = {}
    for held in performers:
        priors = learn({p: Q for p, Q in poses.items() if p != held}, sk)
        Q_test, W_test = test_poses(clips, held, args.test_poses)
        for s in args.targets:
            for kind in POSTURES:
                results[held, s, kind] = run_case(sk, Q_test, W_test, kind, priors.get(kind), TARGET_SETS[s])
        print(f"held out {held}: {len(Q_test)} test poses done; load {os.getloadavg()[0]:.2f}", flush=True)
    print(f"\nload {os.getloadavg()[0]:.2f} at the end\n")
    for s in args.targets:
        print_performers(results, performers, s)
        print_rule(results, performers, s)


def print_performers(results, performers, s) -> None:
    """Per held-out performer and posture: interior mean / p95, targets met, step time over the rest posture's."""
    print(f"### {s}: interior mean / p95 [mm], targets met (1 mm), step time / rest posture's\n")
    print("| posture | " + " | ".join(f"held out {p}" for p in performers) + " |")
    print("|---|" + "---|" * len(performers))
    for kind in POSTURES:
        cells = []
        for p in performers:
            m, rest = results[p, s, kind], results[p, s, "rest"]
            cells.append(f"{m['interior'].mean():.1f} / {np.percentile(m['interior'], 95):.0f}, "
                         f"{np.sum(m['target'] < 1.0)}/{len(m['target'])}, "
                         f"{np.median(m['step']) / np.median(rest['step']):.2f}x")
        print(f"| {kind} | " + " | ".join(cells) + " |")
    print()


def print_rule(results, performers, s) -> None:
    """Rest posture's interior mean over each prior's, per performer; geometric mean; the default rule."""
    print(f"### {s}: rest posture's interior mean error / the posture's (above 1: better than rest)\n")
    print("| posture | " + " | ".join(performers) + " | geometric mean | no worse for all, >= 2x on average |")
    print("|---|" + "---|" * (len(performers) + 2))
    for kind in ("none",) + PRIORS:
        r = np.array([results[p, s, "rest"]["interior"].mean() / results[p, s, kind]["interior"].mean()
                      for p in performers])
        g = float(np.exp(np.mean(np.log(r))))
        ok = "yes" if np.all(r >= 1.0) and g >= 2.0 else "no"
        print(f"| {kind} | " + " | ".join(f"{v:.2f}" for v in r) + f" | {g:.2f} | {ok} |")
    print()


if __name__ == "__main__":
    main()
