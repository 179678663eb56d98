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

import numpy as np

from gsik.anim.retarget import Retargeted, Retargeter
from gsik.anim.retarget_check import RetargetCheck
from gsik.anim.retarget_map import read_mapping
from gsik.cli.batch import SOME_FAILED, ClipOutcome, batch_exit, folder_clips, format_table, run_batch, summary_line
from gsik.cli.common import CommandError, load_any_skeleton
from gsik.errors import RetargetError, ToleranceError
from gsik.io.bvh import BvhClip, format_bvh, read_bvh
from gsik.io.bvh_skeleton import motion_to_bvh
from gsik.io.out_folder import OutputFolder
from gsik.prior import CV_SEGMENTS

#: The retarget summary's columns: the worst mapped joint's p95 error, and the planted-foot slide [m/s].
RETARGET_COLUMNS = ("frames", "mapped", "worst joint (p95)", "p95 mm", "p95 %", "slide before", "slide after",
                    "check")
#: The pose prior's file name when ``learn-prior DIR --out`` names a folder.
PRIOR_NAME = "prior.npz"


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


def learn_one(args: argparse.Namespace, path: str) -> ClipOutcome:
    """Retarget and check one clip for the prior (in a worker): its cells and its angles (n_frames, n_dofs) [rad]."""
    r = retarget_clip(args, path, args.frames)
    check = r.check()
    return ClipOutcome(Path(path).name, _cells(r, check, verdict(args, path, check)), payload=np.asarray(r.motion.q))


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


def learn_prior_folder(args: argparse.Namespace, out: TextIO, fit_and_write) -> int:
    """``gsik learn-prior DIR --out DIR|PRIOR.npz``: every clip retargeted, then one prior from all their frames.

    ``fit_and_write(q, path, follow_symlinks)`` fits the prior to ``q`` (n, n_dofs) [rad], writes it and returns
    its report line.
    """
    clips = folder_clips(args.clip, None)
    target = _prior_path(args.out)
    outcomes = run_batch(args, functools.partial(learn_one, args), clips, "learn-prior").outcomes
    out.write(format_table(RETARGET_COLUMNS, outcomes, left=(2,)) + "\n")
    good = [o.payload for o in outcomes if not o.failed]
    out.write(summary_line(outcomes, 0, None) + "\n")
    if not good:
        out.write("no clip retargeted within its tolerance: no prior written\n")
        return SOME_FAILED
    path, follow = target
    out.write(fit_and_write(np.concatenate(good), path, follow) + "\n")
    return batch_exit(outcomes)


def _prior_path(out: str) -> tuple[Path, bool]:
    """Where the prior goes and whether links there are followed: ``--out`` itself when it ends in ``.npz``, else
    :data:`PRIOR_NAME` inside the folder ``--out`` (checked, created; no link followed)."""
    if Path(out).suffix.lower() == ".npz":
        return Path(out), True
    return OutputFolder.create(out).path(PRIOR_NAME), False
