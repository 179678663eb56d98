"""``gsik retarget DIR`` and ``gsik learn-prior DIR``: every clip of a folder retargeted (and checked) in a batch.

The work of one clip (:func:`retarget_one`, :func:`learn_one`) runs in a
worker (:mod:`gsik.cli.batch`); it returns the BVH text or the angles, and
this process writes them. A clip whose result is outside its tolerance
(:mod:`gsik.anim.retarget_check`) fails with the check's message unless
``--force``.
"""

from __future__ import annotations

import argparse
import functools
import math
from pathlib import Path
from typing import TextIO


from gsik.anim.mocap_set import by_performer, clip_paths, retarget_clips
from gsik.anim.retarget import Retargeted, Retargeter
from gsik.anim.retarget_check import RetargetCheck
from gsik.anim.retarget_map import read_mapping
from gsik.cli.batch import SOME_FAILED, ClipOutcome, batch_exit, folder_clips, format_table, run_batch, summary_line
from gsik.cli.common import CommandError, load_any_skeleton
from gsik.errors import RetargetError, ToleranceError
from gsik.io.bvh import BvhClip, format_bvh, read_bvh
from gsik.io.bvh_skeleton import motion_to_bvh
from gsik.io.out_folder import OutputFolder
from gsik.prior import CV_SEGMENTS, write_prior
from gsik.prior_variants import learn_prior

#: The retarget summary's columns: the worst mapped joint's p95 error, and the planted-foot slide [m/s].
RETARGET_COLUMNS = ("frames", "mapped", "worst joint (p95)", "p95 mm", "p95 %", "slide before", "slide after",
                    "check")
#: The pose prior's file name when ``learn-prior DIR --out`` names a folder.
PRIOR_NAME = "prior.npz"
#: Frames kept from each clip when learning from several (neighbouring frames are near copies).
MANY_STRIDE = 10


def retarget_clip(args: argparse.Namespace, path: str, frames: int | None = None, progress=None) -> Retargeted:
    """Read ``path`` (its first ``frames`` frames), map it (``--map``, ``--file-up``) and retarget it ``--onto`` the
    target (the biped by default; ``--limit-margin``); ``progress(done, total)`` after each frame."""
    clip = read_bvh(path)
    if frames:
        clip = BvhClip(clip.joints, clip.frame_time, clip.motion[:frames])
    if hasattr(args, "components"):
        _check_learnable(args, path, clip.n_frames)
    mapping = read_mapping(args.map) if args.map else None
    try:
        rt = Retargeter(load_any_skeleton(getattr(args, "onto", "biped")), clip, mapping,
                        None if args.file_up == "auto" else args.file_up, name=str(path),
                        limit_margin=math.radians(getattr(args, "limit_margin", 0.0)))
        return rt.retarget(clip, None if progress is None else lambda i: progress(i + 1, clip.n_frames))
    except RetargetError as exc:  # name the clip where the retargeter did not
        message = str(exc)
        raise RetargetError(message if str(path) in message else f"{path}: {message}") from None


def _check_learnable(args: argparse.Namespace, path: str, n_frames: int) -> None:
    """Before ``learn-prior``'s retarget: enough frames to learn from, and to fit ``--components``."""
    if n_frames < 2 * CV_SEGMENTS:
        raise CommandError(f"{path}: {n_frames} frames; learning a prior needs at least {2 * CV_SEGMENTS}")
    if isinstance(args.components, int) and args.components > n_frames // 2:
        raise CommandError(f"--components {args.components}: {n_frames} frames fit at most {n_frames // 2} "
                           f"components ({path})")


def verdict(args: argparse.Namespace, path: str, check: RetargetCheck) -> str:
    """``"ok"`` or ``"outside (forced)"``; :class:`ToleranceError` with the check's message when the result is
    outside its tolerance and ``--force`` is not given."""
    if check.ok:
        return "ok"
    if not args.force:
        raise ToleranceError(check.message(f"{Path(path).name}: the retargeted clip"))
    return "outside (forced)"


def bvh_text(args: argparse.Namespace, r: Retargeted) -> str:
    """The retargeted motion as BVH text (``--units``, ``--up`` or the clip's)."""
    return format_bvh(motion_to_bvh(r.motion, units=args.units, up=args.up or r.up), 8 if args.units == "m" else 6)


def _cells(r: Retargeted, check: RetargetCheck, verdict: str) -> tuple[str, ...]:
    worst = check.joints[0] if check.joints else None
    return (str(r.motion.n_frames), str(len(r.mapping)), worst.frame if worst else "-",
            f"{worst.p95 * 1e3:.1f}" if worst else "-", f"{100 * worst.p95 / r.height:.2f}%" if worst else "-",
            f"{r.slide[0]:.3f}", f"{r.slide[1]:.3f}", verdict)


def retarget_one(args: argparse.Namespace, write: bool, path: str) -> ClipOutcome:
    """Retarget and check one clip of a folder (in a worker): its cells and, with ``write``, its BVH."""
    r = retarget_clip(args, path)
    check = r.check()
    cells = _cells(r, check, verdict(args, path, check))
    name = Path(path).name
    return ClipOutcome(name, cells, outputs=((name, bvh_text(args, r).encode("utf-8")),) if write else ())


def learn_strided(onto: str, stride: int, cache: str | None, path: str) -> ClipOutcome:
    """Retarget every ``stride``-th frame of one clip onto the skeleton ``onto`` (``--onto``) for the prior (in a
    worker; ``cache``: see :func:`gsik.anim.mocap_set.retarget_clips`): its poses and performer in the table, the
    clip as payload."""
    clip = retarget_clips(load_any_skeleton(onto), [path], stride, cache)[0]
    return ClipOutcome(Path(path).name, (str(len(clip.q)), clip.performer), payload=clip)


def retarget_folder(args: argparse.Namespace, out: TextIO) -> int:
    """``gsik retarget DIR [--out DIR]``: the table; exit 4 when some clips failed."""
    clips = folder_clips(args.clip, args.out)
    folder = OutputFolder.create(args.out) if args.out else None
    outcomes, written = run_batch(args, functools.partial(retarget_one, args, folder is not None), clips,
                                  "retarget", folder)
    out.write(format_table(RETARGET_COLUMNS, outcomes, left=(2,)) + "\n")
    out.write("slide: p95 speed of the feet over the clip's contacts [m/s], of the targets before pinning and of "
              "the result\n")
    out.write(summary_line(outcomes, written, args.out) + "\n")
    return batch_exit(outcomes)


def learn_prior_many(args: argparse.Namespace, out: TextIO) -> int:
    """``gsik learn-prior CLIPS|DIR... --out PRIOR.npz|DIR``: every ``--stride``-th frame of every clip retargeted in
    the batch (a process pool or a Dask cluster), then one prior by the bundled recipe (the poses by performer,
    mirrored, the performer normalised away: :func:`gsik.prior_variants.learn_prior`). Exit 4 when some clips
    failed (the prior is then learned from the others)."""
    for option, given in (("--map", args.map), ("--file-up", args.file_up != "auto"), ("--frames", args.frames),
                          ("--components", args.components)):
        if given:
            raise CommandError(f"learn-prior: {option} applies to one clip only; several clips or a folder "
                               "are each recognised on their own")
    stride = args.stride or MANY_STRIDE
    target = _prior_path(args.out)
    clips = [str(p) for p in clip_paths(args.clips)]
    work = functools.partial(learn_strided, args.onto, stride, args.cache)
    outcomes = run_batch(args, work, clips, "learn-prior").outcomes
    out.write(format_table(("poses", "performer"), outcomes, left=(1,)) + "\n")
    out.write(summary_line(outcomes, 0, None) + "\n")
    good = [o.payload for o in outcomes if not o.failed]
    if not good:
        out.write("no clip retargeted: no prior written\n")
        return SOME_FAILED
    poses = by_performer(good)
    source = args.source or (f"every {stride}th frame of {len(good)} clips of {len(poses)} performers: "
                             + ", ".join(c.name for c in good))
    prior = learn_prior(poses, load_any_skeleton(args.onto), source)
    path, follow = target
    write_prior(prior, path, follow)
    out.write(f"wrote {path}: {prior.n_frames} poses of {len(poses)} performers (and their mirror images), "
              f"every {stride}th frame, shrinkage {prior.shrinkage:g}\n")
    return batch_exit(outcomes)


def _prior_path(out: str) -> tuple[Path, bool]:
    """Where the prior goes and whether links there are followed: ``--out`` itself when it ends in ``.npz``, else
    :data:`PRIOR_NAME` inside the folder ``--out`` (checked, created; no link followed)."""
    if Path(out).suffix.lower() == ".npz":
        return Path(out), True
    return OutputFolder.create(out).path(PRIOR_NAME), False
