"""``gsik retarget`` (a clip onto the biped) and ``gsik learn-prior`` (a pose prior from a clip)."""

from __future__ import annotations

import argparse
import math
from typing import TextIO

from gsik.anim.retarget import Retargeted, Retargeter
from gsik.anim.retarget_map import read_mapping
from gsik.cli.common import check_out, load_any_skeleton
from gsik.cli.progress import progress_for
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import write_motion_bvh
from gsik.prior import fit_prior, write_prior
from gsik.prior_mixture import fit_mixture, write_mixture


def add_commands(add, common) -> None:
    """Register both commands; ``add(name, help, description)`` makes a sub-parser, ``common`` adds --progress."""
    p = add("retarget", "retarget a BVH clip onto the biped (or --onto any humanoid); report every joint's error",
            "Recognise the clip's humanoid bones (gsik.humanoid: names of the common rig conventions, the "
            "tree's shape where names fail; --map for the rest) and the target's, scale by leg length, and solve "
            "each frame with the target's joints tracking the clip's bone directions at the target's own "
            "lengths, by priority (feet, hands, head; then knees, elbows, toes, neck; then shoulders, hips, "
            "spine), warm-started. Prints each mapped joint's error and what could not be mapped.")
    _clip_options(p)
    p.add_argument("--limit-margin", type=float, default=30.0, metavar="DEG",
                   help="let the retargeted pose exceed the target's joint limits by this much each side "
                        "(default 30: real motion exceeds the biped's authoring ranges; 0 keeps them)")
    p.add_argument("--onto", metavar="SKELETON", default="biped",
                   help="the humanoid to retarget onto: a bundled skeleton, a skeleton .yaml, a .urdf or a .bvh "
                        "clip's skeleton (default biped)")
    p.add_argument("--out", metavar="BIPED.bvh", help="write the biped's motion as BVH")
    p.add_argument("--units", choices=("cm", "m"), default="cm", help="BVH length unit (default cm)")
    p.add_argument("--up", choices=("z", "y"), help="BVH up axis (default: the clip's)")
    common(p, solver=False)
    p.set_defaults(run=cmd_retarget)

    p = add("learn-prior", "learn the biped's pose prior (a Gaussian over its angles) from a BVH clip",
            "Retarget the clip onto the biped (as 'gsik retarget') and write the mean and regularised "
            "covariance of its poses as a .npz pose prior (gsik.prior); the shrinkage is chosen by "
            "cross-validation over time segments of the clip.")
    _clip_options(p)
    p.add_argument("--out", metavar="PRIOR.npz", required=True, help="the pose prior file to write")
    p.add_argument("--frames", type=int, help="use only the clip's first N frames")
    p.add_argument("--source", default="", help="what the clip is and its licence, kept in the file")
    p.add_argument("--components", type=_components, metavar="K|auto",
                   help="learn a mixture of K Gaussians (gsik.prior_mixture; 'auto': K chosen by cross-validation "
                        "over time segments) instead of a single Gaussian")
    common(p, solver=False)
    p.set_defaults(run=cmd_learn_prior)


def _components(text: str) -> int | str:
    """``--components``: a count >= 1 or ``auto``."""
    if text == "auto":
        return text
    try:
        k = int(text)
    except ValueError:
        k = 0
    if k < 1:
        raise argparse.ArgumentTypeError(f"must be a count >= 1 or 'auto', got {text!r}")
    return k


def _clip_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("clip", metavar="CLIP.bvh", help="a BVH clip of a human rig")
    p.add_argument("--map", metavar="MAP.yaml", help="biped frame -> clip joint entries the heuristics miss")
    p.add_argument("--file-up", choices=("auto", "y", "z"), default="auto",
                   help="the clip's up axis (default: detected over the whole clip)")


def _retarget(args: argparse.Namespace, frames: int | None = None) -> Retargeted:
    clip = read_bvh(args.clip)
    if frames:
        clip = type(clip)(clip.joints, clip.frame_time, clip.motion[:frames])
    mapping = read_mapping(args.map) if args.map else None
    rt = Retargeter(load_any_skeleton(getattr(args, "onto", "biped")), clip, mapping, None if args.file_up == "auto" else args.file_up,
                    name=args.clip, limit_margin=math.radians(getattr(args, "limit_margin", 0.0)))
    with progress_for(args, "retarget") as bar:
        return rt.retarget(clip, lambda i: bar(i + 1, clip.n_frames))


def _report(r: Retargeted, out: TextIO) -> None:
    print(f"{r.motion.n_frames} frames, up {r.up}, scale {r.scale:.5g} m per file unit (leg length)", file=out)
    name = r.motion.skeleton.name
    print(f"{name + ' frame':16} {'clip joint':20} {'mean':>8} {'p95':>8} {'max':>8}  [mm]", file=out)
    for frame, joint, mean, p95, worst in r.error_table():
        print(f"{frame:16} {joint:20} {mean:8.2f} {p95:8.2f} {worst:8.2f}", file=out)
    print(f"{name} frames not mapped: {', '.join(r.unmapped_frames) or 'none'}", file=out)
    print(f"clip joints not used: {', '.join(r.unmapped_clip) or 'none'}", file=out)


def cmd_retarget(args: argparse.Namespace, out: TextIO) -> int:
    if args.out:
        check_out(args.out, (".bvh",), "BVH")
    r = _retarget(args)
    _report(r, out)
    if args.out:
        write_motion_bvh(args.out, r.motion, units=args.units, up=args.up or r.up)
        print(f"wrote {args.out}", file=out)
    return 0


def cmd_learn_prior(args: argparse.Namespace, out: TextIO) -> int:
    check_out(args.out, (".npz",), "pose prior")
    r = _retarget(args, args.frames)
    _report(r, out)
    if args.components is None:
        prior = fit_prior(r.motion.q, r.motion.skeleton, source=args.source)
        write_prior(prior, args.out)
        print(f"wrote {args.out}: {prior.n_frames} poses, shrinkage {prior.shrinkage:g}", file=out)
        return 0
    mixture = fit_mixture(r.motion.q, r.motion.skeleton, None if args.components == "auto" else args.components,
                          source=args.source)
    write_mixture(mixture, args.out)
    print(f"wrote {args.out}: {mixture.n_frames} poses, {mixture.n_components} components, "
          f"shrinkage {mixture.shrinkage:g}", file=out)
    return 0
