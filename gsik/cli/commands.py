"""The commands but ``info`` and ``track``: solve, walk, scenarios, bench. Each ``cmd_*`` takes the parsed options and
the output stream and returns the exit code."""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import TextIO

import gsik
from gsik.cli.common import PROG, CommandError, check_out, deg, load_any_skeleton, make_dir, mm, settings_overrides
from gsik.cli.progress import progress_for
from gsik.io.bvh_skeleton import write_motion_bvh
from gsik.io.pose import pose_from_document, read_pose_document, write_pose


def _warn(message: str) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


# -- solve ------------------------------------------------------------------------------------------


def cmd_solve(args: argparse.Namespace, out: TextIO) -> int:
    if args.out:
        check_out(args.out, (".yaml", ".yml"), "pose")
    doc = read_pose_document(args.pose)  # read and parsed once; its skeleton: path is relative to the pose file
    spec = args.skeleton or doc.skeleton
    if spec is None:
        raise CommandError(f"{args.pose}: cannot tell its skeleton (no 'skeleton:' field); give --skeleton")
    sk = load_any_skeleton(spec)
    read = pose_from_document(doc, sk)
    for w in read.warnings:
        _warn(w)
    pose = read.pose
    solver = gsik.Solver(sk.with_root(pose.root), q0=pose.q(sk), world_from_root=pose.world_from_root,
                         **settings_overrides(args))
    targets = {name: t for name, t in pose.targets.items() if t.enabled}
    start = time.perf_counter()
    result = solver.solve(targets)
    elapsed = time.perf_counter() - start
    out.write(f"pose {args.pose}: skeleton {sk.name}, root {pose.root}, {len(targets)} of "
              f"{len(pose.targets)} targets enabled\n")
    out.write(f"status: {result.status.label} after {result.iterations} iterations ({result.sweeps} sweeps, "
              f"{result.attempts} attempt{'s' if result.attempts != 1 else ''}) in {elapsed * 1e3:.1f} ms\n")
    _write_errors(out, result, targets)
    if args.out:
        solved = pose.replace(joints=dict(zip(sk.dof_names, (float(v) for v in result.q))))
        write_pose(args.out, solved, read.library, read.keys, read.poles, read.clip, sk)  # every other block kept
        out.write(f"wrote {args.out}\n")
    return 0


def _write_errors(out: TextIO, result, targets: dict) -> None:
    """Each targeted effector's position and (if it has one) orientation error."""
    w = max((len(n) for n in result.effector_names), default=8)
    out.write(f"  {'effector':<{w}}  {'position error':>16}  {'orientation error':>18}\n")
    for name, (pe, oe) in result.errors().items():
        if name in targets:
            ori = "-" if not targets[name].uses_orientation else deg(oe)
            out.write(f"  {name:<{w}}  {mm(pe):>16}  {ori:>18}\n")


# -- walk -------------------------------------------------------------------------------------------


def cmd_walk(args: argparse.Namespace, out: TextIO) -> int:
    from gsik.anim.gait import REACH_WARNING, WALK_STEPS_PER_FRAME, format_measures, measure_walk, walk

    if args.out:
        check_out(args.out, (".bvh",), "BVH")
    params = _walk_parameters(args)
    sk = load_any_skeleton(args.skeleton)
    with progress_for(args, "walk") as progress:
        result = walk(sk, params, steps_per_frame=args.steps_per_frame or WALK_STEPS_PER_FRAME, progress=progress,
                      **settings_overrides(args))
    m = measure_walk(result)
    p = result.plan.params
    out.write(f"walk: {p.n_steps} steps of {p.step_length:g} m, {p.cadence:g} steps/min "
              f"({p.step_duration:.3g} s per step), {p.fps:g} fps, {result.steps_per_frame} solver steps per frame\n")
    out.write(format_measures(m) + "\n")
    if m.max_tracking_error > REACH_WARNING:
        _warn(f"some targets stayed {mm(m.max_tracking_error)} away: the gait is partly out of "
              "reach (try a shorter --step-length, a larger --pelvis-drop or a lower --cadence)")
    if args.out:
        write_motion_bvh(args.out, result.motion, units=args.units, up=args.up, end_sites=args.end_sites)
        out.write(f"wrote {args.out} ({m.n_frames} frames, {args.units}, {args.up} up)\n")
    return 0


def _walk_parameters(args: argparse.Namespace):
    """The :class:`~gsik.anim.gait.WalkParameters` the options give (defaults where not given)."""
    from gsik.anim.gait import WalkParameters

    cadence = args.cadence
    if args.step_duration is not None:
        if not (math.isfinite(args.step_duration) and args.step_duration > 0):
            raise CommandError(f"--step-duration must be > 0 seconds, got {args.step_duration!r}")
        cadence = 60.0 / args.step_duration
    fields = dict(n_steps=args.steps, step_length=args.step_length, step_height=args.step_height, cadence=cadence,
                  fps=args.fps, lead_foot=f"{args.lead}_foot", arm_swing=args.arm_swing,
                  pelvis_drop=args.pelvis_drop, pelvis_sway=args.pelvis_sway)
    return WalkParameters(**{k: v for k, v in fields.items() if v is not None})


# -- scenarios ----------------------------------------------------------------------------------------


def cmd_scenarios(args: argparse.Namespace, out: TextIO) -> int:
    from gsik.anim.scenario_run import format_table, run_scenario

    if args.random < 0:
        raise CommandError(f"--random must be >= 0, got {args.random}")
    scenarios = _chosen_scenarios(args, load_any_skeleton(args.skeleton))
    folder = make_dir(args.out) if args.out else None
    reports = []
    with progress_for(args, "scenarios") as progress:
        for k, s in enumerate(scenarios):
            def step_progress(done, total, k=k):
                progress(k * 1000 + int(1000 * done / max(total, 1)), 1000 * len(scenarios))

            reports.append(run_scenario(s, max_frames=args.max_frames, progress=step_progress,
                                        **settings_overrides(args)))
    out.write(format_table(reports) + "\n")
    if args.verbose:
        for r in reports:
            out.write(f"\n{r.name}: {r.status.label}, {r.ms_per_frame:.3f} ms per frame\n")
            for name, (pe, oe) in r.errors().items():
                out.write(f"  {name:<12} {mm(pe):>14} {deg(oe):>14}\n")
    if folder is not None:
        _write_scenario_files(args, folder, scenarios, reports, out)
    return 0


def _chosen_scenarios(args: argparse.Namespace, sk) -> list:
    """The built-in scenarios asked for (all by default) and ``--random`` seeded random ones."""
    from gsik.anim.scenarios import SCENARIO_NAMES, builtin_scenario, random_scenarios

    names = args.only if args.only else ([] if args.random and args.no_builtin else list(SCENARIO_NAMES))
    scenarios = [builtin_scenario(sk, n) for n in names]
    scenarios += list(random_scenarios(sk, args.random, seed=args.seed, spread=args.spread))
    if not scenarios:
        raise CommandError("no scenarios to run (give --only NAME or --random N)")
    return scenarios


def _write_scenario_files(args: argparse.Namespace, folder, scenarios: list, reports: list, out: TextIO) -> None:
    """``<scenario>.yaml`` (the final pose and its targets) and ``<scenario>.bvh`` (every frame) for each."""
    from gsik.anim.scenarios import scenario_pose

    for s, r in zip(scenarios, reports):
        write_pose(folder / f"{s.name}.yaml", scenario_pose(s, r.motion.q[-1]), skeleton=r.motion.skeleton)
        write_motion_bvh(folder / f"{s.name}.bvh", r.motion, units=args.units, up=args.up, end_sites=args.end_sites)
    out.write(f"wrote {2 * len(scenarios)} files to {args.out} (<scenario>.yaml: the final pose and its "
              f"targets; <scenario>.bvh: every frame of the run)\n")


# -- bench ------------------------------------------------------------------------------------------------


def cmd_bench(args: argparse.Namespace, out: TextIO) -> int:
    from gsik.benchmark import report

    sizes = dict(repeats=500, frames=120, problems=50) if args.quick else dict(repeats=3000, frames=600,
                                                                                  problems=1000)
    with progress_for(args, "reach benchmark") as progress:
        text = report(progress=progress, **sizes)
    out.write(text + "\n")
    return 0
