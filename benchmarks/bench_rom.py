"""Ranges of motion against real motion: retargeted frames with a joint on a limit, and deep knee bends.

Every clip under ``--mocap`` (default ``../shared/mocap``) is retargeted onto
the biped (or ``--skeleton FILE``, e.g. the biped's limits before a change),
every ``--stride``-th frame (:mod:`gsik.anim.mocap_set`, cached in ``--cache``
outside the repository). Printed: per clip and in all, the share of kept
frames with any DOF within 1e-4 rad of a limit, also leaving the ankles out;
the DOFs on a limit most often; and the deep knee bends: the kept frames whose
clip bends a knee past 140 deg (measured on the retargeting's targets: the
clip's hip, knee and ankle directions at the biped's proportions), with the
biped's knee and hip distance from the clip's after the solve.

Run: ``python benchmarks/bench_rom.py [--skeleton FILE] [--stride 10] [--cache DIR]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from gsik import load_skeleton
from gsik.anim.mocap_set import RetargetedClip, retarget_clips

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "mocap"
#: A deep knee bend: knee flexion beyond this [deg] in the clip.
DEEP = 140.0
ON_LIMIT = 1e-4


def on_limit(sk, Q: np.ndarray) -> np.ndarray:
    """(n, n_dofs) True where a DOF is within :data:`ON_LIMIT` rad of a limit."""
    return (Q <= sk.lower + ON_LIMIT) | (Q >= sk.upper - ON_LIMIT)


def knee_flexion(c: RetargetedClip, side: str) -> np.ndarray:
    """(n,) the clip's knee flexion [deg] on ``side``, from its hip, knee and ankle targets."""
    col = {f: k for k, f in enumerate(c.mapped)}
    hip, knee, ankle = (c.targets[:, col[f"{side}_{j}"]] for j in ("hip", "knee", "ankle"))
    a, b = knee - hip, ankle - knee
    cos = np.sum(a * b, axis=1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mocap", type=Path, default=MOCAP)
    ap.add_argument("--skeleton", default="biped")
    ap.add_argument("--stride", type=int, default=10)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/gsik-prior-cache"))
    args = ap.parse_args()
    sk = load_skeleton(args.skeleton)
    clips = retarget_clips(sk, [args.mocap], args.stride, args.cache)
    ankles = np.array(["ankle" in n for n in sk.dof_names])
    print(f"## Ranges of motion: {args.skeleton}, every {args.stride}th frame; load {os.getloadavg()[0]:.2f}\n")
    print("| clip | performer | frames | any joint on a limit | ankles left out |")
    print("|---|---|---|---|---|")
    hits = []
    for c in clips:
        on = on_limit(sk, c.q)
        hits.append(on)
        print(f"| {c.name} | {c.performer} | {len(c.q)} | {on.any(axis=1).mean():.1%} "
              f"| {on[:, ~ankles].any(axis=1).mean():.1%} |")
    on = np.concatenate(hits)
    print(f"| all | | {len(on)} | {on.any(axis=1).mean():.1%} | {on[:, ~ankles].any(axis=1).mean():.1%} |\n")
    order = np.argsort(-on.sum(axis=0))[:8]
    print("On a limit most often: " + ", ".join(f"{sk.dof_names[i]} {on[:, i].mean():.1%}" for i in order) + "\n")
    print(f"Deep knee bends (clip knee flexion > {DEEP:.0f} deg): biped knee / hip distance from the clip's [mm]\n")
    print("| clip | frame | side | clip knee flexion [deg] | biped knee flexion [deg] | knee error | hip error |")
    print("|---|---|---|---|---|---|---|")
    for c in clips:
        col = {f: k for k, f in enumerate(c.mapped)}
        for side in ("left", "right"):
            bend = knee_flexion(c, side)
            for i in np.flatnonzero(bend > DEEP):
                print(f"| {c.name} | {i * c.stride} | {side} | {bend[i]:.0f} "
                      f"| {-np.degrees(c.q[i, sk.dof_index(f'{side}_knee.x')]):.0f} "
                      f"| {1000 * c.errors[i, col[f'{side}_knee']]:.1f} | {1000 * c.errors[i, col[f'{side}_hip']]:.1f} |")


if __name__ == "__main__":
    main()
