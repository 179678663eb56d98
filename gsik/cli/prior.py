"""``gsik retarget`` (a clip onto the biped or ``--onto`` a humanoid) and ``gsik learn-prior`` (a pose prior from
clips, for the same skeleton)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TextIO

import numpy as np

from gsik.anim.retarget import Retargeted
from gsik.cli.batch import add_batch_options
from gsik.cli.common import check_out, load_any_skeleton
from gsik.cli.progress import progress_for
from gsik.cli.retarget_batch import learn_prior_many, retarget_clip, retarget_folder, verdict
from gsik.io.bvh_skeleton import write_motion_bvh
from gsik.prior import fit_prior, write_prior
from gsik.prior_mixture import MAX_COMPONENTS, fit_mixture, write_mixture


def add_commands(add, common) -> None:
    """Register both commands; ``add(name, help, description)`` makes a sub-parser, ``common`` adds --progress."""
    p = add("retarget", "retarget a BVH clip onto the biped (or --onto any humanoid); report every joint's error",
            "Recognise the clip's humanoid bones (gsik.humanoid: names of the common rig conventions, the "
            "tree's shape where names fail; --map for the rest) and the target's, scale by leg length, and solve "
            "each frame with the target's joints tracking the clip's bone directions at the target's own "
            "lengths, by priority (feet, hands, head; then knees, elbows, toes, neck; then shoulders, hips, "
            "spine), warm-started; the clip's planted feet are pinned. Prints each mapped joint's error, what "
            "could not be mapped and the foot slide, and checks the result (frames are rotations, mapped joints "
            "p95 within 2%% of the target's height, planted feet do not slide): a result outside is not written "
            "(exit 3) unless --force. CLIP may be a folder: its clips run in parallel (locally, or on a Dask "
            "cluster with --scheduler), --out names a folder, one summary table (exit 4 if some clips failed).")
    _clip_options(p)
    p.add_argument("--limit-margin", type=float, default=30.0, metavar="DEG",
                   help="let the retargeted pose exceed the target's joint limits by this much each side "
                        "(default 30: real motion exceeds the biped's authoring ranges; 0 keeps them)")
    _onto_option(p)
    p.add_argument("--out", metavar="OUT.bvh|DIR", help="write the retargeted motion as BVH (a folder for a folder)")
    p.add_argument("--units", choices=("cm", "m"), default="cm", help="BVH length unit (default cm)")
    p.add_argument("--up", choices=("z", "y"), help="BVH up axis (default: the clip's)")
    common(p, solver=False)
    p.set_defaults(run=cmd_retarget)

    p = add("learn-prior", "learn a skeleton's pose prior (a Gaussian over its angles) from BVH clips or folders",
            "Retarget the clips onto the biped (or --onto any humanoid; as 'gsik retarget') and write the mean "
            "and regularised covariance of their poses as a .npz pose prior (gsik.prior); the shrinkage is chosen by "
            "cross-validation over time segments. Several clips or a folder (every .bvh under it): every "
            "--stride-th frame, each clip's rig recognised on its own, on a process pool or a Dask cluster "
            "(as 'gsik retarget DIR'), and the poses and their mirror images "
            "with the performer normalised away (gsik.prior_variants.learn_prior; the bundled prior's recipe).")
    p.add_argument("clips", nargs="+", metavar="CLIP.bvh|FOLDER", help="a BVH clip of a human rig, several, "
                   "or folders of them (a CMU 'SSS_TT.bvh' clip belongs to subject SSS, any other to itself)")
    p.add_argument("--map", metavar="MAP.yaml", help="biped frame -> clip joint entries the heuristics miss "
                   "(one clip only)")
    _onto_option(p)
    p.add_argument("--file-up", choices=("auto", "y", "z"), default="auto",
                   help="the clip's up axis (default: detected over the whole clip; one clip only)")
    p.add_argument("--stride", type=_frame_count, metavar="N",
                   help="keep every N-th frame of each clip (default 1; several clips: 10)")
    p.add_argument("--cache", metavar="DIR", help="keep each retargeted clip in this folder for the next run")
    p.add_argument("--force", action="store_true", help="use a result even when it is outside its tolerance")
    add_batch_options(p)
    p.add_argument("--out", metavar="PRIOR.npz|DIR", required=True,
                   help="the pose prior file to write (a folder: DIR/prior.npz)")
    p.add_argument("--frames", type=_frame_count, help="use only the clip's first N frames (N >= 1; one clip only)")
    p.add_argument("--source", default="", help="what the clip is and its licence, kept in the file")
    p.add_argument("--components", type=_components, metavar="K|auto",
                   help="learn a mixture of K Gaussians (gsik.prior_mixture; 'auto': K chosen by cross-validation "
                        "over time segments) instead of a single Gaussian")
    common(p, solver=False)
    p.set_defaults(run=cmd_learn_prior)


def _onto_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--onto", metavar="SKELETON", default="biped",
                   help="the humanoid to retarget onto: a bundled skeleton, a skeleton .yaml, a .urdf or a .bvh "
                        "clip's skeleton (default biped)")


def _components(text: str) -> int | str:
    """``--components``: a count >= 1 or ``auto``."""
    if text == "auto":
        return text
    try:
        k = int(text)
    except ValueError:
        k = 0
    if not 1 <= k <= MAX_COMPONENTS:
        raise argparse.ArgumentTypeError(f"must be a count from 1 to {MAX_COMPONENTS} or 'auto', got {text!r}")
    return k


def _frame_count(text: str) -> int:
    """``--frames``: a count >= 1 (a negative count would silently drop frames from the end)."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got {text!r}")
    return n


def _clip_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("clip", metavar="CLIP.bvh|DIR", help="a BVH clip of a human rig, or a folder of them")
    p.add_argument("--force", action="store_true", help="use a result even when it is outside its tolerance")
    add_batch_options(p)
    p.add_argument("--map", metavar="MAP.yaml", help="biped frame -> clip joint entries the heuristics miss")
    p.add_argument("--file-up", choices=("auto", "y", "z"), default="auto",
                   help="the clip's up axis (default: detected over the whole clip)")


def _retarget(args: argparse.Namespace, out: TextIO, frames: int | None = None) -> Retargeted:
    """One clip retargeted and reported; :class:`~gsik.errors.ToleranceError` (after the report) when the result is
    outside its tolerance and ``--force`` is not given."""
    with progress_for(args, "retarget") as bar:
        r = retarget_clip(args, args.clip, frames, bar)
    _report(r, out)
    check = r.check()
    print(f"feet: {len(r.contacts.spans)} contacts pinned; slide (p95 planted speed) {r.slide[0]:.3f} m/s before, "
          f"{r.slide[1]:.3f} m/s after", file=out)
    print(f"check: {verdict(args, args.clip, check)} (worst joint p95 {check.worst_p95 * 1e3:.1f} mm, "
          f"{100 * check.worst_p95 / r.height:.2f}% of the height {r.height:.3f} m)", file=out)
    return r


def _report(r: Retargeted, out: TextIO) -> None:
    print(f"{r.motion.n_frames} frames, up {r.up}, scale {r.scale:.5g} m per file unit (leg length)", file=out)
    name = r.motion.skeleton.name
    print(f"{name + ' frame':16} {'clip joint':20} {'mean':>8} {'p95':>8} {'max':>8}  [mm]", file=out)
    for frame, joint, mean, p95, worst in r.error_table():
        print(f"{frame:16} {joint:20} {mean:8.2f} {p95:8.2f} {worst:8.2f}", file=out)
    print(f"{name} frames not mapped: {', '.join(r.unmapped_frames) or 'none'}", file=out)
    print(f"clip joints not used: {', '.join(r.unmapped_clip) or 'none'}", file=out)


def cmd_retarget(args: argparse.Namespace, out: TextIO) -> int:
    if Path(args.clip).is_dir():
        return retarget_folder(args, out)
    if args.out:
        check_out(args.out, (".bvh",), "BVH")
    r = _retarget(args, out)
    if args.out:
        write_motion_bvh(args.out, r.motion, units=args.units, up=args.up or r.up)
        print(f"wrote {args.out}", file=out)
    return 0


def cmd_learn_prior(args: argparse.Namespace, out: TextIO) -> int:
    if len(args.clips) > 1 or Path(args.clips[0]).is_dir():
        return learn_prior_many(args, out)
    args.clip = args.clips[0]
    check_out(args.out, (".npz",), "pose prior")
    r = _retarget(args, out, args.frames)
    print(_fit_and_write(args, r.motion.q, args.out, True), file=out)
    return 0


def _fit_and_write(args: argparse.Namespace, q: np.ndarray, path, follow_symlinks: bool) -> str:
    """Fit the prior (a Gaussian, or ``--components`` of them) to ``q`` (n, n_dofs) [rad] and write it to ``path``;
    the report line."""
    skeleton = load_any_skeleton(args.onto)
    if args.components is None:
        prior = fit_prior(q, skeleton, source=args.source)
        write_prior(prior, path, follow_symlinks)
        return f"wrote {path}: {prior.n_frames} poses, shrinkage {prior.shrinkage:g}"
    mixture = fit_mixture(q, skeleton, None if args.components == "auto" else args.components, source=args.source)
    write_mixture(mixture, path, follow_symlinks)
    return (f"wrote {path}: {mixture.n_frames} poses, {mixture.n_components} components, "
            f"shrinkage {mixture.shrinkage:g}")
