"""``gsik track``: one clip, or a folder of clips in parallel worker processes with one summary table."""

from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import NamedTuple, TextIO

from gsik.cli.common import CommandError, check_out, deg, make_dir, mm, settings_overrides, split_names
from gsik.cli.progress import progress_for
from gsik.errors import GsikError
from gsik.io.bvh import read_bvh, write_bvh
from gsik.io.bvh_skeleton import clip_with_motion, import_bvh, write_motion_bvh


class TrackRow(NamedTuple):
    """One clip's line of the folder summary (lengths [m])."""

    clip: str
    frames: int
    joints: int
    up: str
    worst_joint: str
    worst_p95: float
    height: float
    target_max: float
    seconds: float
    error: str = ""


def cmd_track(args: argparse.Namespace, out: TextIO) -> int:
    if Path(args.clip).is_dir():
        return _track_folder(args, out)
    if args.out:
        check_out(args.out, (".bvh",), "BVH")
    with progress_for(args, "track") as progress:
        run = _track(args, args.clip, args.out, progress)
    _write_report(out, args, run)
    return 0


class _Run(NamedTuple):
    """What one track made: the clip (BvhClip), its import (BvhImport) and the result (TrackResult)."""

    clip: object
    imported: object
    result: object


def _track(args: argparse.Namespace, path: str, out_path: str | None, progress=None) -> _Run:
    """Import ``path``, track it as the options say, write ``out_path`` (when given)."""
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
    if out_path:
        _write_output(args, out_path, imported, result.motion)
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


def _write_output(args: argparse.Namespace, path: str, imported, motion) -> None:
    """The solved motion in the input's conventions, or gsik's export when ``--units`` or ``--up`` change them."""
    file_units = {1.0: "m", 0.01: "cm"}.get(imported.scale)
    keep = (args.units in (None, file_units)) and (args.up in (None, imported.up))
    if keep:
        write_bvh(path, clip_with_motion(imported, motion, wrap_angles=args.wrap_angles),
                  precision=8 if file_units == "m" else 6)
    else:
        write_motion_bvh(path, motion, units=args.units or file_units or "cm", up=args.up or imported.up)


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
    if args.out:
        out.write(f"wrote {args.out}\n")


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


def _track_folder(args: argparse.Namespace, out: TextIO) -> int:
    clips = _folder_clips(args)
    folder = make_dir(args.out) if args.out else None
    rows = _track_clips(args, clips, folder)
    out.write(format_track_table([rows[p] for p in clips]) + "\n")
    failed = any(r.error for r in rows.values())
    if folder is not None:
        out.write(f"wrote {sum(not r.error for r in rows.values())} files to {args.out}\n")
    return 2 if failed else 0


def _folder_clips(args: argparse.Namespace) -> list[Path]:
    """The folder's ``.bvh`` files in name order; refuses an empty folder and an ``--out`` that names a file."""
    clips = sorted(p for p in Path(args.clip).iterdir() if p.suffix.lower() == ".bvh" and p.is_file())
    if not clips:
        raise CommandError(f"folder {args.clip!r} holds no .bvh files")
    if args.out and Path(args.out).suffix.lower() == ".bvh":
        raise CommandError(f"--out {args.out!r}: with a folder of clips, --out names a folder")
    return clips


def _track_clips(args: argparse.Namespace, clips: list[Path], folder: Path | None) -> dict[Path, TrackRow]:
    """Track every clip in a pool of worker processes; each clip's summary row."""
    workers = args.workers or min(len(clips), os.cpu_count() or 1)
    rows: dict[Path, TrackRow] = {}
    with progress_for(args, f"track {len(clips)} clips") as progress, \
            ProcessPoolExecutor(max_workers=workers) as pool:
        jobs = {pool.submit(track_one, args, str(p), _out_path(folder, p)): p for p in clips}
        for n, job in enumerate(as_completed(jobs), start=1):
            rows[jobs[job]] = job.result()
            progress(n, len(clips))
    return rows


def _out_path(folder: Path | None, clip: Path) -> str | None:
    return str(folder / clip.name) if folder else None


def track_one(args: argparse.Namespace, path: str, out_path: str | None) -> TrackRow:
    """Track one clip of a folder (in a worker process); its summary row, or the error that stopped it."""
    start = time.perf_counter()
    try:
        clip, imported, result = _track(args, path, out_path)
    except GsikError as exc:
        return TrackRow(Path(path).name, 0, 0, "-", "-", 0.0, 0.0, 0.0, 0.0, str(exc))
    joints = set(imported.skeleton.joint_names)
    rows = [r for r in result.body_table(95.0) if r.name in joints]
    worst = rows[0] if rows else None
    return TrackRow(Path(path).name, clip.n_frames, imported.skeleton.n_joints, imported.up,
                    worst.name if worst else "-", worst.percentile_error if worst else 0.0, result.body_height,
                    result.summary(0).max_position_error, time.perf_counter() - start)


def format_track_table(rows: list[TrackRow]) -> str:
    """The folder summary: one line per clip."""
    w = max(len(r.clip) for r in rows)
    head = (f"{'clip':<{w}}  {'frames':>6} {'joints':>6} {'up':>2}  {'worst joint (p95)':<22} {'p95 %':>6}  "
            f"{'targets max':>12}  {'seconds':>7}")
    lines = [head, "-" * len(head)]
    for r in rows:
        if r.error:
            lines.append(f"{r.clip:<{w}}  error: {r.error}")
            continue
        pct = 100 * r.worst_p95 / r.height if r.height else 0.0
        lines.append(f"{r.clip:<{w}}  {r.frames:>6} {r.joints:>6} {r.up:>2}  {r.worst_joint:<22} {pct:5.2f}%  "
                     f"{mm(r.target_max):>12}  {r.seconds:7.2f}")
    return "\n".join(lines)
