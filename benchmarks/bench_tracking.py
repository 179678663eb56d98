"""Clip tracking benchmark: export a smooth biped clip to BVH, import it back, track it.

The clip: 10 s at 30 fps of slow random sinusoids within the biped's limits
(at most ~0.03 rad per frame), the hips travelling forward and swaying, the
IK root alternating between the feet every 15 frames as in a walk. It is
written as BVH text (centimetres, y up by default), parsed, imported as a
skeleton, and its own effectors (head, pelvis, hands, feet; 6-DOF targets)
are tracked with the IK root (``--root``, default the hips) pinned where the
clip has it, for a few solver budgets, as the plain solver measure
(``follow_clip=False``: warm-started from the previous frame, no posture).
Figures exclude frame 0 (a full solve from the rest pose).

``--clip PATH`` measures a real clip instead, as ``gsik track`` runs it: every
joint's 95th-percentile distance to the clip in % of the body height, before
(today's main before issue 9: up axis from the rest pose, angles as written,
frame 0 from the rest pose, no posture) and after (the defaults), in one run.

Run: ``python benchmarks/bench_tracking.py [--frames 300] [--units cm] [--up y]``, or
``python benchmarks/bench_tracking.py --clip CLIP.bvh [--effectors A,B]``.
Nothing here is asserted by the tests: timings on a shared machine are noisy.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from gsik.io.bvh import format_bvh, parse_bvh
from gsik.io.bvh_skeleton import import_bvh, motion_to_bvh
from gsik.kinematics import world_frames
from gsik.anim.motion import Motion
from gsik.rotations import matrix_from_rotvec, transform
from gsik.skeleton import Skeleton
from gsik.io.skeleton_yaml import load_skeleton
from gsik.anim.tracking import track_clip

EFFECTORS = ("head", "pelvis", "left_hand", "right_hand", "left_foot", "right_foot")
#: (sweeps per step, most steps per frame) to compare; the first is track_clip's default.
BUDGETS = ((20, 5), (10, 3), (10, 1), (20, 10), (60, 10))


def walk_like_motion(sk: Skeleton, n_frames: int, seed: int) -> Motion:
    """Slow random sinusoids, hips travelling along +y, the root alternating between the feet."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames) / 30.0
    half = 0.5 * (sk.upper - sk.lower)
    q = sk.rest + 0.25 * half * np.sin(2 * np.pi * rng.uniform(0.1, 0.4, sk.n_dofs) * t[:, None]
                                       + rng.uniform(0, 2 * np.pi, sk.n_dofs))
    q = np.clip(q, sk.lower, sk.upper)
    roots = tuple(("right_foot", "left_foot")[(f // 15) % 2] for f in range(n_frames))
    W = np.empty((n_frames, 4, 4))
    for f in range(n_frames):
        hips = transform(matrix_from_rotvec([0.0, 0.0, 0.2 * np.sin(t[f])]),
                         [0.05 * np.sin(2 * t[f]), 0.8 * t[f], 0.95 + 0.02 * np.cos(4 * t[f])])
        R, p = world_frames(sk, q[f], hips, "hips")
        i = sk.frame_of(roots[f])
        W[f] = transform(R[i], p[i])
    return Motion(sk, q, roots, W, 1.0 / 30.0)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--units", choices=("cm", "m"), default="cm")
    parser.add_argument("--up", choices=("y", "z"), default="y")
    parser.add_argument("--root", default="hips", help="the IK root while tracking (hips, right_foot, ...)")
    parser.add_argument("--clip", help="a real BVH clip: per-joint errors before and after issue 9")
    parser.add_argument("--effectors", help="with --clip: targets (a comma list; default the end sites and pelvis)")
    args = parser.parse_args(argv)
    if args.clip:
        clip_report(args.clip, args.effectors.split(",") if args.effectors else None)
        return

    biped = load_skeleton("biped")
    start = time.perf_counter()
    # The biped's own 30 DOFs, as before Blender-compatible padding: the table compares the solver on one problem
    # (a padded export re-imports hinges as 3-DOF joints, 39 DOFs: another problem).
    motion = walk_like_motion(biped, args.frames, args.seed)
    text = format_bvh(motion_to_bvh(motion, units=args.units, up=args.up, pad_rotations=False))
    imported = import_bvh(parse_bvh(text))
    print(f"clip: {args.frames} frames, {len(text) / 1024:.0f} KiB of BVH ({args.units}, {args.up} up), "
          f"exported and re-imported in {time.perf_counter() - start:.2f} s; "
          f"{imported.skeleton.n_dofs} DOF, detected scale {imported.scale} m/unit, up {imported.up}")
    track_clip(imported.skeleton, imported.motion, effectors=EFFECTORS, root=args.root, steps_per_frame=1,
               follow_clip=False)  # JIT

    header = (f"{'sweeps':>6} {'steps':>5} | {'mean pos':>9} {'max pos':>9} {'median':>9} | "
              f"{'mean ori':>9} {'max ori':>9} | {'median t':>9} {'max t':>9} {'steps/fr':>8}")
    tracked = [e for e in EFFECTORS if e != args.root]
    print(f"\ntracking {', '.join(tracked)} with {args.root} pinned where the clip has it, frames 1..{args.frames - 1}")
    print(header)
    print("-" * len(header))
    for sweeps, steps in BUDGETS:
        result = track_clip(imported.skeleton, imported.motion, effectors=EFFECTORS, root=args.root, sweeps=sweeps,
                            steps_per_frame=steps, follow_clip=False)
        s = result.summary()
        print(f"{sweeps:>6} {steps:>5} | {s.mean_position_error * 1e3:>6.3f} mm {s.max_position_error * 1e3:>6.3f} mm "
              f"{s.median_position_error * 1e3:>6.3f} mm | {np.degrees(s.mean_orientation_error):>6.3f} deg "
              f"{np.degrees(s.max_orientation_error):>6.3f} deg | {s.median_frame_seconds * 1e3:>6.3f} ms "
              f"{s.max_frame_seconds * 1e3:>6.3f} ms {np.mean(result.steps[1:]):>8.2f}")
    print("\n'median' is the median over frames of each frame's largest position error; times are the solver's "
          "calls per frame (set root, set targets, steps).")


def clip_report(path: str, effectors) -> None:
    """Per-joint p95 errors [% of body height] of a real clip's track: before and after issue 9, one run."""
    from gsik.io.bvh import read_bvh
    from gsik.io.bvh_skeleton.importer import _rest_extent

    clip = read_bvh(path)
    ext = _rest_extent(clip)
    runs = {}
    for label, up, unwrap, follow in (("before", "y" if ext[1] > ext[2] else "z", False, False),
                                      ("after", "auto", True, True)):
        imported = import_bvh(clip, up=up, unwrap=unwrap)
        start = time.perf_counter()
        result = track_clip(imported.skeleton, imported.motion, effectors, follow_clip=follow)
        runs[label] = (imported, result, time.perf_counter() - start)
    height = runs["after"][1].body_height  # the true height: the "before" import may stand the clip on its side
    print(f"clip {path}: {clip.n_frames} frames, {len(runs['after'][0].skeleton.joint_names)} joints, "
          f"body height {height:.3f} m; up axis before {runs['before'][0].up} (rest pose), "
          f"after {runs['after'][0].up_reason}")
    print(f"targets: {', '.join(runs['after'][1].effector_names)}")
    for label, (_, result, seconds) in runs.items():
        s = result.summary()
        print(f"{label:>6}: {seconds:.1f} s ({s.median_frame_seconds * 1e3:.2f} ms per frame median); targets max "
              f"{s.max_position_error * 1e3:.3f} mm, p95 of frame max "
              f"{np.percentile(result.position_errors[1:].max(axis=1), 95) * 1e3:.3f} mm")
    before = {r.name: r for r in runs["before"][1].body_table()}
    print(f"\n| joint | before p95 % | after p95 % | after max mm (frame) |\n|---|---:|---:|---:|")
    for r in runs["after"][1].body_table():
        b = before[r.name]
        print(f"| {r.name}{' *' if r.tracked else ''} | {100 * b.percentile_error / height:.2f} | "
              f"{100 * r.percentile_error / height:.3f} | {r.max_error * 1e3:.3f} ({r.worst_frame}) |")
    print("\n(* tracked; p95 over all frames of each joint's distance to the clip, in % of the body height)")


if __name__ == "__main__":
    main()
