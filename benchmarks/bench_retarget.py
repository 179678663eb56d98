"""Retarget every BVH clip of the given files or folders onto the biped with no mapping file; print a table.

Per clip: frames, mapped biped frames (of those the biped can aim), whether every core joint (pelvis, spine,
neck, head, shoulders, elbows, hands, hips, knees, ankles) is mapped, and the mapped joints' distance from their
targets over all frames and joints: mean, p95 and max [mm], and the joint with the largest p95 of its own. The clips are read from ../shared/mocap (never
copied into the repository)::

    nice -n 5 .venv/bin/python benchmarks/bench_retarget.py ../shared/mocap [--stride N]

``--stride N`` retargets every N-th frame only (for a quick look; the README's table uses every frame).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import gsik
from gsik.anim.retarget import Retargeter
from gsik.io.bvh import BvhClip, read_bvh

#: The biped frames every clip must drive.
CORE = ("pelvis", "waist", "neck", "atlas", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
        "left_hand", "right_hand", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle")


def clips(paths: list[str]) -> list[Path]:
    """The .bvh files named, and those in the folders named (recursively), sorted."""
    out: list[Path] = []
    for p in map(Path, paths):
        out += sorted(p.rglob("*.bvh")) if p.is_dir() else [p]
    return out


def row(path: Path, stride: int, margin: float) -> str:
    """One table row for the clip at ``path``."""
    full = read_bvh(path)
    clip = BvhClip(full.joints, full.frame_time * stride, full.motion[::stride])
    t0 = time.perf_counter()
    rt = Retargeter(gsik.load_skeleton("biped"), clip, name=str(path), limit_margin=np.radians(margin))
    r = rt.retarget(clip)
    e = r.errors * 1000.0
    core = "yes" if all(f in r.mapping for f in CORE) else "no: " + ", ".join(f for f in CORE if f not in r.mapping)
    n_aim = len(r.mapping) + len(r.unmapped_frames)
    worst = max(r.error_table(), key=lambda t: t[3])
    return (f"| {path.name} | {clip.n_frames} | {len(r.mapping)}/{n_aim} | {core} | {e.mean():.1f} | "
            f"{np.percentile(e, 95):.1f} | {e.max():.1f} | {worst[0]} {worst[3]:.1f} | "
            f"{time.perf_counter() - t0:.0f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="+", help="BVH files or folders")
    ap.add_argument("--stride", type=int, default=1, help="retarget every N-th frame (default 1: all)")
    ap.add_argument("--limit-margin", type=float, default=30.0, help="degrees beyond the biped's limits (as "
                    "gsik retarget's default, 30)")
    args = ap.parse_args()
    print("| clip | frames | mapped | core joints | mean [mm] | p95 [mm] | max [mm] | worst joint's p95 [mm] | "
          "time [s] |")
    print("|---|---:|---:|---|---:|---:|---:|---|---:|")
    for path in clips(args.paths):
        print(row(path, args.stride, args.limit_margin), flush=True)


if __name__ == "__main__":
    main()
