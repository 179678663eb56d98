"""``gsik track``: one clip, or a folder of clips in parallel worker processes with one summary table."""

from __future__ import annotations

import argparse
import functools
import sys
from pathlib import Path
from typing import NamedTuple, TextIO

from gsik.anim.retarget_check import Tolerances, rotation_check
from gsik.cli.batch import ClipOutcome, batch_exit, folder_clips, format_table, run_batch, summary_line
from gsik.cli.common import CommandError, check_out, deg, mm, settings_overrides, split_names
from gsik.cli.progress import progress_for
from gsik.errors import ToleranceError
from gsik.io.bvh import format_bvh, read_bvh
from gsik.io.bvh_skeleton import clip_with_motion, import_bvh, motion_to_bvh
from gsik.io.files import atomic_write_text
from gsik.io.out_folder import OutputFolder


def cmd_track(args: argparse.Namespace, out: TextIO) -> int:
    if Path(args.clip).is_dir():
        return _track_folder(args, out)
    if args.out:
        check_out(args.out, (".bvh",), "BVH")
    with progress_for(args, "track") as progress:
        run = _track(args, args.clip, progress)
    _write_report(out, args, run)
    if args.out:
        atomic_write_text(args.out, _output_text(args, run.imported, run.result.motion))
        out.write(f"wrote {args.out}\n")
    return 0


class _Run(NamedTuple):
    """What one track made: the clip (BvhClip), its import (BvhImport) and the result (TrackResult)."""

    clip: object
    imported: object
    result: object


def _track(args: argparse.Namespace, path: str, progress=None) -> _Run:
    """Import ``path`` and track it as the options say; :class:`ToleranceError` (unless ``--force``) when a frame
    of the result is not a rotation."""
    from gsik.anim.tracking import track_clip

    clip = read_bvh(path)
    imported = import_bvh(clip, strip_namespace=args.strip_namespace, up=args.file_up, source=path,
                          **({"scale": args.scale} if args.scale else {}))
    targets, position_only, priorities = _targets(args)
    options = dict(settings_overrides(args))
    if args.steps_per_frame:
        options["steps_per_frame"] = args.steps_per_frame
    result = track_clip(imported.skeleton, imported.motion, targets, root=args.root, position_only=position_only,
                        priorities=priorities, follow_clip=args.follow_clip, posture_weight=args.posture_weight,
                        progress=progress, **options)
    rotations = rotation_check(result.motion)
    if not rotations.error <= Tolerances().rotation and not args.force:
        raise ToleranceError(f"{path}: the result is outside its tolerance: frame {rotations.frame} is not a "
                             f"rotation at clip frame {rotations.clip_frame} (deviation {rotations.error:.3g}); "
                             "reason: a degenerate frame (use --force to write it anyway)")
    return _Run(clip, imported, result)


def _targets(args: argparse.Namespace) -> tuple[list[str] | None, bool | list[str], dict[str, int] | None]:
    """``(targets, position_only, priorities)`` from ``--effectors``, ``--position-only``, ``--priority``, ``--pole``.

    A pole (a knee or elbow) is tracked by position only, one level below every other target.
    """
    targets = split_names(args.effectors)
    poles = split_names(args.pole) or []
    priorities = _priority_map(args.priority)
    position_only = _position_only(args.position_only)
    if poles:
        if targets is None:
            raise CommandError("--pole needs --effectors (the targets the poles sit under)")
        targets, position_only = _add_poles(poles, targets, position_only, priorities)
    return targets, position_only, priorities or None


def _position_only(values) -> bool | list[str]:
    """``--position-only``: ``False`` when absent, ``True`` for ``*``, else the names listed."""
    if values is None:
        return False
    if "*" in values:
        return True
    return split_names(values) or []


def _add_poles(poles: list[str], targets: list[str], position_only: bool | list[str],
               priorities: dict[str, int]) -> tuple[list[str], bool | list[str]]:
    """Poles joined to the targets, by position only, one level below every other target (``priorities`` in place)."""
    below = max([*priorities.values(), 0]) + 1
    targets = [*targets, *(p for p in poles if p not in targets)]
    priorities.update({p: below for p in poles if p not in priorities})
    if position_only is not True:
        position_only = [*(position_only or []), *poles]
    return targets, position_only


def _priority_map(values) -> dict[str, int]:
    """``NAME=LEVEL`` pairs (several arguments and/or comma lists) as a dict."""
    out: dict[str, int] = {}
    for item in split_names(values) or []:
        name, sep, level = item.rpartition("=")
        if not sep or not name or not level.strip().isdigit():
            raise CommandError(f"--priority {item!r}: expected NAME=LEVEL with a whole LEVEL >= 0 "
                               "(0 is the most important)")
        out[name] = int(level)
    return out


def _output_text(args: argparse.Namespace, imported, motion) -> str:
    """The solved motion as BVH text in the input's conventions, or gsik's export when ``--units`` or ``--up``
    change them."""
    file_units = {1.0: "m", 0.01: "cm"}.get(imported.scale)
    keep = (args.units in (None, file_units)) and (args.up in (None, imported.up))
    if keep:
        return format_bvh(clip_with_motion(imported, motion, wrap_angles=args.wrap_angles),
                          8 if file_units == "m" else 6)
    units = args.units or file_units or "cm"
    return format_bvh(motion_to_bvh(motion, units=units, up=args.up or imported.up), 8 if units == "m" else 6)


def _write_report(out: TextIO, args: argparse.Namespace, run: _Run) -> None:
    clip, imported, result = run
    sk = imported.skeleton
    out.write(f"clip {args.clip}: {clip.n_frames} frames at {1 / clip.frame_time:g} fps, {sk.n_joints} joints, "
              f"{sk.n_dofs} DOF (scale {imported.scale:g} m per unit, {imported.up} up)\n")
    out.write(f"up axis: {imported.up_reason}\n")
    for w in imported.warnings:
        print(f"gsik: warning: {w}", file=sys.stderr)
    only = " (positions only)" if args.position_only and "*" in args.position_only else ""
    out.write(f"tracked {', '.join(result.effector_names)} with root {result.motion.roots[0]}{only}"
              f"{'; the clip pose preferred' if args.follow_clip else ''}\n")
    _write_target_summary(out, result, clip.n_frames)
    _write_body_table(out, result)


def _write_target_summary(out: TextIO, result, n_frames: int) -> None:
    """Errors and time per frame over frames 1.., then each target's mean and largest error."""
    s = result.summary()
    out.write(f"frames 1-{n_frames - 1} (frame 0 is a full solve):\n")
    out.write(f"  position error:    mean {mm(s.mean_position_error)}, median of frame max "
              f"{mm(s.median_position_error)}, max {mm(s.max_position_error)}\n")
    out.write(f"  orientation error: mean {deg(s.mean_orientation_error)}, max {deg(s.max_orientation_error)}\n")
    out.write(f"  time per frame:    median {s.median_frame_seconds * 1e3:.3f} ms, "
              f"max {s.max_frame_seconds * 1e3:.3f} ms\n")
    w = max((len(n) for n in result.effector_names), default=8)
    out.write(f"  {'effector':<{w}}  {'mean':>12}  {'max':>12}\n")
    for k, name in enumerate(result.effector_names):
        col = result.position_errors[1:, k] if result.position_errors.shape[0] > 1 else result.position_errors[:, k]
        out.write(f"  {name:<{w}}  {mm(float(col.mean())):>12}  {mm(float(col.max())):>12}\n")


def _percent(length: float, height: float) -> str:
    """``length`` [m] as a percentage of ``height`` [m]; ``-`` for a clip of no height (all its joints level)."""
    return f"{100 * length / height:.2f}%" if height > 0.0 else "-"


def _write_body_table(out: TextIO, result) -> None:
    """Every joint and site against the clip: p95 and max, in mm and % of the body's height; the worst joint."""
    rows = result.body_table(95.0)
    if not rows:
        return
    h = result.body_height
    joints = set(result.motion.skeleton.joint_names)
    worst = next((r for r in rows if r.name in joints and not r.tracked), None)
    if worst is not None:
        out.write(f"worst untracked joint: {worst.name}, {mm(worst.max_error)} at frame {worst.worst_frame} "
                  f"(p95 {_percent(worst.percentile_error, h)} of the body height {h:.3f} m)\n")
    w = max(len(r.name) for r in rows)
    out.write("every joint and site against the clip (all frames, * tracked):\n")
    out.write(f"  {'':1} {'name':<{w}}  {'p95':>12} {'p95 %':>7}  {'max':>12}  {'at frame':>8}\n")
    for r in rows:
        out.write(f"  {'*' if r.tracked else ' '} {r.name:<{w}}  {mm(r.percentile_error):>12} "
                  f"{_percent(r.percentile_error, h):>7}  {mm(r.max_error):>12}  {r.worst_frame:>8}\n")


# -- a folder of clips ---------------------------------------------------------------------------------


#: The folder summary's columns (the worst untracked joint's p95 against the clip, % of the body height).
TRACK_COLUMNS = ("frames", "joints", "up", "worst joint (p95)", "p95 %", "targets max")


def _track_folder(args: argparse.Namespace, out: TextIO) -> int:
    clips = folder_clips(args.clip, args.out)
    folder = OutputFolder.create(args.out) if args.out else None
    outcomes, written = run_batch(args, functools.partial(track_one, args, folder is not None), clips, "track",
                                  folder)
    out.write(format_table(TRACK_COLUMNS, outcomes, left=(3,)) + "\n")
    out.write(summary_line(outcomes, written, args.out) + "\n")
    return batch_exit(outcomes)


def track_one(args: argparse.Namespace, write: bool, path: str) -> ClipOutcome:
    """Track one clip of a folder (in a worker): its table cells and, with ``write``, its BVH text."""
    clip, imported, result = _track(args, path)
    joints = set(imported.skeleton.joint_names)
    rows = [r for r in result.body_table(95.0) if r.name in joints]
    worst = rows[0] if rows else None
    pct = 100 * worst.percentile_error / result.body_height if worst and result.body_height else 0.0
    cells = (str(clip.n_frames), str(imported.skeleton.n_joints), imported.up, worst.name if worst else "-",
             f"{pct:.2f}%", mm(result.summary(0).max_position_error))
    name = Path(path).name
    outputs = ((name, _output_text(args, imported, result.motion).encode("utf-8")),) if write else ()
    return ClipOutcome(name, cells, outputs=outputs)
