"""The ``gsik`` command line: inspect skeletons, solve poses, walk, run scenarios, track clips, benchmark.

Run ``gsik --help`` (or ``python -m gsik --help``) and ``gsik COMMAND --help``.

Exit codes: 0 success; 2 bad input (an unknown skeleton, a missing or
malformed file, a bad option; the message goes to stderr as
``gsik: error: ...``); 1 a feature this installation lacks or an unexpected
failure; 130 interrupted. A solve that cannot reach its targets is not an
error: the best reach is reported (and written) with its status.

A progress bar is drawn on stderr for work that takes more than a second,
when stderr is a terminal or with ``--progress``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

import gsik
from gsik.errors import GsikError
from gsik.solver import PAPER_METHOD

PROG = "gsik"


class CommandError(GsikError):
    """A command cannot run as asked (a missing feature, an unwritable folder)."""

    def __init__(self, message: str, exit_code: int = 2):
        super().__init__(message)
        self.exit_code = exit_code


def _require(module: str, *names: str, feature: str):
    """Import ``names`` from gsik's ``module``, or fail with a sentence saying which feature is missing."""
    try:
        mod = importlib.import_module(module)
        found = tuple(getattr(mod, n) for n in names)
    except (ImportError, AttributeError) as exc:
        raise CommandError(f"{feature} is not available in this installation of gsik "
                           f"({module}.{' / '.join(names)}: {exc})", exit_code=1) from None
    return found if len(found) > 1 else found[0]


# -- progress ---------------------------------------------------------------------------------------


class Progress:
    """A one-line progress bar on a text stream, drawn only once the work has taken ``delay`` seconds.

    Call the instance as ``progress(done, total)``; :meth:`close` ends the line.
    Disabled, it does nothing.
    """

    def __init__(self, label: str, enabled: bool, stream: TextIO | None = None, width: int = 30,
                 delay: float = 1.0):
        self.label = label
        self.enabled = enabled
        self.stream = sys.stderr if stream is None else stream
        self.width = width
        self.delay = delay
        self._start = time.monotonic()
        self._drawn = False
        self._last = -1.0

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if now - self._start < self.delay or (now - self._last < 0.1 and done < total):
            return
        self._last = now
        fraction = min(max(done / total, 0.0), 1.0) if total > 0 else 1.0
        filled = int(round(fraction * self.width))
        bar = "#" * filled + "-" * (self.width - filled)
        self.stream.write(f"\r{self.label} [{bar}] {100 * fraction:3.0f}% ({done}/{total})")
        self.stream.flush()
        self._drawn = True

    def close(self) -> None:
        if self._drawn:
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _progress(args: argparse.Namespace, label: str) -> Progress:
    enabled = args.progress if args.progress is not None else sys.stderr.isatty()
    return Progress(label, enabled)


# -- shared helpers -------------------------------------------------------------------------------


def load_any_skeleton(spec: str):
    """A bundled skeleton by name, a skeleton YAML file, a URDF robot (``.urdf``) or a BVH clip's skeleton."""
    suffix = Path(spec).suffix.lower()
    if suffix == ".urdf":
        skeleton_from_urdf = _require("gsik.io.urdf_skeleton", "skeleton_from_urdf", feature="URDF import")
        return skeleton_from_urdf(spec)
    if suffix == ".bvh":
        read_bvh = _require("gsik.io.bvh", "read_bvh", feature="BVH reading")
        import_bvh = _require("gsik.io.bvh_skeleton", "import_bvh", feature="BVH import")
        return import_bvh(read_bvh(spec)).skeleton
    return gsik.load_skeleton(spec)


def _settings_overrides(args: argparse.Namespace) -> dict:
    out = {}
    if getattr(args, "sweeps", None) is not None:
        out["sweeps"] = args.sweeps
    if getattr(args, "paper", False):
        out.update(PAPER_METHOD)
    return out


def _mm(x: float) -> str:
    return f"{x * 1e3:.3f} mm"


def _deg(x: float) -> str:
    return f"{math.degrees(x):.3f} deg"


def _make_dir(path: str) -> Path:
    p = Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CommandError(f"cannot create folder {path!r}: {exc.strerror or exc}") from None
    return p


def _check_out(path: str, suffixes: Sequence[str], what: str) -> None:
    if Path(path).suffix.lower() not in suffixes:
        raise CommandError(f"--out {path!r}: {what} files end in {' or '.join(suffixes)}")
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise CommandError(f"--out {path!r}: folder {str(parent)!r} does not exist")


# -- info -------------------------------------------------------------------------------------------


def skeleton_info(sk) -> dict:
    """The skeleton as plain data (what ``gsik info --json`` prints)."""
    dofs = []
    joint_of_dof = {}
    for j, name in enumerate(sk.joint_names):
        for d in sk.joint_dofs[j]:
            joint_of_dof[d] = name
    for d, name in enumerate(sk.dof_names):
        dofs.append({
            "name": name, "joint": joint_of_dof.get(d),
            "axis": [float(v) for v in sk.frame_axis[sk.dof_frame[d]]],
            "lower": float(sk.lower[d]), "upper": float(sk.upper[d]), "rest": float(sk.rest[d]),
            "lower_deg": math.degrees(sk.lower[d]), "upper_deg": math.degrees(sk.upper[d]),
            "rest_deg": math.degrees(sk.rest[d]),
        })
    joints = [{"name": name,
               "parent": None if sk.joint_parent[j] < 0 else sk.joint_names[sk.joint_parent[j]],
               "dofs": [sk.dof_names[d] for d in sk.joint_dofs[j]]}
              for j, name in enumerate(sk.joint_names)]
    sites = [{"name": name, "parent": sk.frame_names[sk.frame_parent[f]],
              "effector": name in sk.effector_sites}
             for name, f in zip(sk.site_names, sk.site_frame)]
    segments = []
    for s, name in enumerate(sk.segment_names):
        bones = [b for b in range(len(sk.bone_segment)) if sk.bone_segment[b] == s]
        start = _frame_owner(sk, int(sk.bone_frames[bones[0], 0])) if bones else None
        segments.append({"name": name, "from": start,
                         "to": [_frame_owner(sk, int(sk.bone_frames[b, 1])) for b in bones]})
    return {"name": sk.name, "source": sk.source, "root": sk.root, "n_joints": sk.n_joints, "n_dofs": sk.n_dofs,
            "joints": joints, "dofs": dofs, "effectors": list(sk.effector_sites), "sites": sites,
            "segments": segments}


def _frame_owner(sk, frame: int) -> str:
    """The joint or site name of a frame (a joint's rotations are named ``joint.x``)."""
    for j, f in enumerate(sk.joint_frame):
        if int(f) == frame:
            return sk.joint_names[j]
    return sk.frame_names[frame]


def format_info(info: dict) -> str:
    lines = [f"skeleton {info['name']}  ({info['source']})",
             f"{info['n_joints']} joints, {info['n_dofs']} degrees of freedom, {len(info['sites'])} sites, "
             f"{len(info['segments'])} segments",
             f"IK root: {info['root']}",
             f"effectors ({len(info['effectors'])}): {', '.join(info['effectors']) or '-'}",
             "", "joints:"]
    w = max((len(j["name"]) for j in info["joints"]), default=4)
    for j in info["joints"]:
        parent = j["parent"] or "(top)"
        dofs = f"{len(j['dofs'])} DOF" if j["dofs"] else "fixed"
        lines.append(f"  {j['name']:<{w}}  parent {parent:<{w}}  {dofs}")
    lines += ["", "degrees of freedom (limits and rest: degrees, then radians):"]
    w = max((len(d["name"]) for d in info["dofs"]), default=4)
    lines.append(f"  {'dof':<{w}}  {'lower':>8} {'upper':>8} {'rest':>8}   {'lower':>8} {'upper':>8} {'rest':>8}")
    for d in info["dofs"]:
        lines.append(f"  {d['name']:<{w}}  {d['lower_deg']:8.1f} {d['upper_deg']:8.1f} {d['rest_deg']:8.1f}   "
                     f"{d['lower']:8.4f} {d['upper']:8.4f} {d['rest']:8.4f}")
    lines += ["", "sites (* = effector):"]
    for s in info["sites"]:
        lines.append(f"  {'*' if s['effector'] else ' '} {s['name']}  on {s['parent']}")
    lines += ["", "segments:"]
    for s in info["segments"]:
        lines.append(f"  {s['name']}: {s['from']} -> {', '.join(s['to'])}")
    return "\n".join(lines)


def cmd_info(args: argparse.Namespace, out: TextIO) -> int:
    sk = load_any_skeleton(args.skeleton)
    info = skeleton_info(sk)
    if args.json:
        json.dump(info, out, indent=2)
        out.write("\n")
    else:
        out.write(format_info(info) + "\n")
    return 0


# -- solve ------------------------------------------------------------------------------------------


def _pose_skeleton_name(path: str) -> str | None:
    """The ``skeleton:`` field of a pose file, read loosely (the pose reader checks everything later)."""
    import yaml

    from gsik.io.files import read_text

    try:
        data = yaml.safe_load(read_text(path, "pose file"))
    except yaml.YAMLError:
        return None
    name = data.get("skeleton") if isinstance(data, dict) else None
    return name if isinstance(name, str) else None


def cmd_solve(args: argparse.Namespace, out: TextIO) -> int:
    read_pose, write_pose = _require("gsik.io.pose", "read_pose", "write_pose", feature="the pose file format")
    if args.out:
        _check_out(args.out, (".yaml", ".yml"), "pose")
    spec = args.skeleton or _pose_skeleton_name(args.pose)
    if spec is None:
        raise CommandError(f"{args.pose}: cannot tell its skeleton (no 'skeleton:' field); give --skeleton")
    sk = load_any_skeleton(spec)
    read = read_pose(args.pose, sk)
    for w in read.warnings:
        print(f"{PROG}: warning: {w}", file=sys.stderr)
    pose = read.pose
    solver = gsik.Solver(sk.with_root(pose.root), q0=pose.q(sk), world_from_root=pose.world_from_root,
                         **_settings_overrides(args))
    targets = {name: t for name, t in pose.targets.items() if t.enabled}
    start = time.perf_counter()
    result = solver.solve(targets)
    elapsed = time.perf_counter() - start
    out.write(f"pose {args.pose}: skeleton {sk.name}, root {pose.root}, {len(targets)} of "
              f"{len(pose.targets)} targets enabled\n")
    out.write(f"status: {result.status.label} after {result.iterations} iterations ({result.sweeps} sweeps, "
              f"{result.attempts} attempt{'s' if result.attempts != 1 else ''}) in {elapsed * 1e3:.1f} ms\n")
    w = max((len(n) for n in result.effector_names), default=8)
    out.write(f"  {'effector':<{w}}  {'position error':>16}  {'orientation error':>18}\n")
    for name, (pe, oe) in result.errors().items():
        if name in targets:
            ori = "-" if not targets[name].uses_orientation else _deg(oe)
            out.write(f"  {name:<{w}}  {_mm(pe):>16}  {ori:>18}\n")
    if args.out:
        solved = pose.replace(joints=dict(zip(sk.dof_names, (float(v) for v in result.q))))
        write_pose(args.out, solved)
        out.write(f"wrote {args.out}\n")
    return 0


# -- walk -------------------------------------------------------------------------------------------


def cmd_walk(args: argparse.Namespace, out: TextIO) -> int:
    from gsik.anim.gait import REACH_WARNING, WALK_STEPS_PER_FRAME, WalkParameters, format_measures, measure_walk, walk

    if args.out:
        _check_out(args.out, (".bvh",), "BVH")
        write_motion_bvh = _require("gsik.io.bvh_skeleton", "write_motion_bvh", feature="BVH export")
    cadence = args.cadence
    if args.step_duration is not None:
        if not (math.isfinite(args.step_duration) and args.step_duration > 0):
            raise CommandError(f"--step-duration must be > 0 seconds, got {args.step_duration!r}")
        cadence = 60.0 / args.step_duration
    fields = dict(n_steps=args.steps, step_length=args.step_length, step_height=args.step_height, cadence=cadence,
                  fps=args.fps, lead_foot=f"{args.lead}_foot", arm_swing=args.arm_swing,
                  pelvis_drop=args.pelvis_drop, pelvis_sway=args.pelvis_sway)
    params = WalkParameters(**{k: v for k, v in fields.items() if v is not None})
    sk = load_any_skeleton(args.skeleton)
    with _progress(args, "walk") as progress:
        result = walk(sk, params, steps_per_frame=args.steps_per_frame or WALK_STEPS_PER_FRAME, progress=progress,
                      **_settings_overrides(args))
    m = measure_walk(result)
    p = result.plan.params
    out.write(f"walk: {p.n_steps} steps of {p.step_length:g} m, {p.cadence:g} steps/min "
              f"({p.step_duration:.3g} s per step), {p.fps:g} fps, {result.steps_per_frame} solver steps per frame\n")
    out.write(format_measures(m) + "\n")
    if m.max_tracking_error > REACH_WARNING:
        print(f"{PROG}: warning: some targets stayed {_mm(m.max_tracking_error)} away: the gait is partly out of "
              "reach (try a shorter --step-length, a larger --pelvis-drop or a lower --cadence)", file=sys.stderr)
    if args.out:
        write_motion_bvh(args.out, result.motion, units=args.units, up=args.up)
        out.write(f"wrote {args.out} ({m.n_frames} frames, {args.units}, {args.up} up)\n")
    return 0


# -- scenarios ----------------------------------------------------------------------------------------


def cmd_scenarios(args: argparse.Namespace, out: TextIO) -> int:
    from gsik.anim.scenarios import (SCENARIO_NAMES, builtin_scenario, format_table, random_scenarios, run_scenario,
                                scenario_pose)

    if args.random < 0:
        raise CommandError(f"--random must be >= 0, got {args.random}")
    sk = load_any_skeleton(args.skeleton)
    names = args.only if args.only else ([] if args.random and args.no_builtin else list(SCENARIO_NAMES))
    scenarios = [builtin_scenario(sk, n) for n in names]
    scenarios += list(random_scenarios(sk, args.random, seed=args.seed, spread=args.spread))
    if not scenarios:
        raise CommandError("no scenarios to run (give --only NAME or --random N)")
    writers = None
    if args.out:
        write_pose = _require("gsik.io.pose", "write_pose", feature="the pose file format")
        write_motion_bvh = _require("gsik.io.bvh_skeleton", "write_motion_bvh", feature="BVH export")
        folder = _make_dir(args.out)
        writers = (write_pose, write_motion_bvh)
    reports = []
    with _progress(args, "scenarios") as progress:
        for k, s in enumerate(scenarios):
            def step_progress(done, total, k=k):
                progress(k * 1000 + int(1000 * done / max(total, 1)), 1000 * len(scenarios))

            reports.append(run_scenario(s, max_frames=args.max_frames, progress=step_progress,
                                        **_settings_overrides(args)))
    out.write(format_table(reports) + "\n")
    if args.verbose:
        for r in reports:
            out.write(f"\n{r.name}: {r.status.label}, {r.ms_per_frame:.3f} ms per frame\n")
            for name, (pe, oe) in r.errors().items():
                out.write(f"  {name:<12} {_mm(pe):>14} {_deg(oe):>14}\n")
    if writers:
        write_pose, write_motion_bvh = writers
        for s, r in zip(scenarios, reports):
            write_pose(folder / f"{s.name}.yaml", scenario_pose(s, r.motion.q[-1]))
            write_motion_bvh(folder / f"{s.name}.bvh", r.motion, units=args.units, up=args.up)
        out.write(f"wrote {2 * len(scenarios)} files to {args.out} (<scenario>.yaml: the final pose and its "
                  f"targets; <scenario>.bvh: every frame of the run)\n")
    return 0


# -- track ----------------------------------------------------------------------------------------------


def _names(values: Sequence[str] | None) -> list[str] | None:
    if not values:
        return None
    return [n.strip() for v in values for n in v.split(",") if n.strip()]


def cmd_track(args: argparse.Namespace, out: TextIO) -> int:
    read_bvh = _require("gsik.io.bvh", "read_bvh", feature="BVH reading")
    import_bvh, write_motion_bvh = _require("gsik.io.bvh_skeleton", "import_bvh", "write_motion_bvh",
                                            feature="BVH import and export")
    track_clip = _require("gsik.anim.tracking", "track_clip", feature="clip tracking")
    if args.out:
        _check_out(args.out, (".bvh",), "BVH")
    effectors = _names(args.effectors)
    clip = read_bvh(args.clip)
    imported = import_bvh(clip, effectors, strip_namespace=args.strip_namespace,
                          up=args.file_up, **({"scale": args.scale} if args.scale else {}))
    for w in imported.warnings:
        print(f"{PROG}: warning: {w}", file=sys.stderr)
    sk = imported.skeleton
    options = dict(_settings_overrides(args))
    if args.steps_per_frame:
        options["steps_per_frame"] = args.steps_per_frame
    result = track_clip(sk, imported.motion, effectors, root=args.root, position_only=args.position_only, **options)
    s = result.summary()
    out.write(f"clip {args.clip}: {clip.n_frames} frames at {1 / clip.frame_time:g} fps, {sk.n_joints} joints, "
              f"{sk.n_dofs} DOF (scale {imported.scale:g} m per unit, {imported.up} up)\n")
    out.write(f"tracked {', '.join(result.effector_names)} with root {result.motion.roots[0]}"
              f"{' (positions only)' if args.position_only else ''}\n")
    out.write(f"frames 1-{clip.n_frames - 1} (frame 0 is a full solve from the rest pose):\n")
    out.write(f"  position error:    mean {_mm(s.mean_position_error)}, median of frame max "
              f"{_mm(s.median_position_error)}, max {_mm(s.max_position_error)}\n")
    out.write(f"  orientation error: mean {_deg(s.mean_orientation_error)}, max {_deg(s.max_orientation_error)}\n")
    out.write(f"  time per frame:    median {s.median_frame_seconds * 1e3:.3f} ms, "
              f"max {s.max_frame_seconds * 1e3:.3f} ms\n")
    w = max((len(n) for n in result.effector_names), default=8)
    out.write(f"  {'effector':<{w}}  {'mean':>12}  {'max':>12}\n")
    for k, name in enumerate(result.effector_names):
        col = result.position_errors[1:, k] if result.position_errors.shape[0] > 1 else result.position_errors[:, k]
        out.write(f"  {name:<{w}}  {_mm(float(col.mean())):>12}  {_mm(float(col.max())):>12}\n")
    if args.out:
        write_motion_bvh(args.out, result.motion, units=args.units, up=args.up)
        out.write(f"wrote {args.out}\n")
    return 0


# -- bench ------------------------------------------------------------------------------------------------


def cmd_bench(args: argparse.Namespace, out: TextIO) -> int:
    report = _require("gsik.benchmark", "report", feature="the solver benchmarks")
    sizes = dict(repeats=500, frames=120, problems=50) if args.quick else dict(repeats=3000, frames=600,
                                                                                  problems=1000)
    with _progress(args, "reach benchmark") as progress:
        text = report(progress=progress, **sizes)
    out.write(text + "\n")
    return 0


# -- the parser -----------------------------------------------------------------------------------------------


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return v


def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return v


def _add_common(p: argparse.ArgumentParser, solver: bool = True, progress: bool = True) -> None:
    if solver:
        g = p.add_argument_group("solver")
        g.add_argument("--sweeps", type=_positive_int, help="Gauss-Seidel sweeps per solver step")
        g.add_argument("--paper", action="store_true",
                       help="the paper's plain method: fixed damping, PGS sweeps only, no safeguards")
    if progress:
        p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                       help="draw a progress bar on stderr (default: when stderr is a terminal)")


def _add_bvh_out(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("BVH output")
    g.add_argument("--units", choices=("cm", "m"), default="cm", help="BVH length unit (default cm)")
    g.add_argument("--up", choices=("z", "y"), default="z", help="BVH up axis (default z, as gsik; y for most "
                   "animation packages)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, allow_abbrev=False,
        description="Real-time character inverse kinematics by Projected Gauss-Seidel (Kenwright 2012).",
        epilog="Run 'gsik COMMAND --help' for a command's options. Lengths are metres, angles radians, "
               "unless an option says otherwise.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {gsik.__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def add(name: str, help: str, description: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help, description=description, allow_abbrev=False)

    p = add("info", "joints, degrees of freedom with limits, effectors, sites and segments of a skeleton",
            "Describe a skeleton: joints, degrees of freedom with limits (degrees and radians), effectors, "
            "IK root, sites and segments.")
    p.add_argument("skeleton", metavar="SKELETON",
                   help=f"a bundled skeleton ({', '.join(gsik.bundled_skeletons())}), a skeleton .yaml file, "
                        "a .urdf robot or a .bvh clip")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    p.set_defaults(run=cmd_info)

    p = add("solve", "solve a pose file's targets and print the errors",
            "Solve the enabled targets of a pose YAML file from its joint angles (full solve with restarts) "
            "and print the status and each effector's error; --out writes the solved pose.")
    p.add_argument("pose", metavar="POSE.yaml", help="a pose file (see the README: pose files)")
    p.add_argument("--out", metavar="SOLVED.yaml", help="write the solved pose (same targets, new angles)")
    p.add_argument("--skeleton", help="the skeleton (default: the one the pose file names)")
    _add_common(p, progress=False)
    p.set_defaults(run=cmd_solve)

    p = add("walk", "generate the paper's walk (the root swaps feet each step) and export it as BVH",
            "Walk by root swapping (paper IX.A): the standing foot is the IK root, the swinging foot and the "
            "upper body follow trajectories, every frame is solved warm-started. Prints the continuity at the "
            "root swaps, the stance-foot slide and the footprint accuracy.")
    p.add_argument("--skeleton", default="biped", help="skeleton (default biped)")
    g = p.add_argument_group("gait")
    g.add_argument("--steps", type=_positive_int, default=4, help="number of steps (default 4)")
    g.add_argument("--step-length", type=_finite, help="distance between footprints [m] (default 0.4)")
    g.add_argument("--step-height", type=_finite, help="swing foot clearance [m] (default 0.08)")
    speed = g.add_mutually_exclusive_group()
    speed.add_argument("--cadence", type=_finite, help="steps per minute (default 100)")
    speed.add_argument("--step-duration", type=_finite, help="seconds per step (instead of --cadence)")
    g.add_argument("--fps", type=_finite, help="frames per second (default 60)")
    g.add_argument("--lead", choices=("left", "right"), default="left", help="the foot that steps first")
    g.add_argument("--arm-swing", type=_finite, help="arm swing at full stride [rad] (default 0.35)")
    g.add_argument("--pelvis-drop", type=_finite, help="how much lower the pelvis walks [m] (default 0.04)")
    g.add_argument("--pelvis-sway", type=_finite, help="pelvis shift over the stance foot [m] (default 0.03)")
    g.add_argument("--steps-per-frame", type=_positive_int, help="solver steps per frame (default 2)")
    p.add_argument("--out", metavar="WALK.bvh", help="write the walk as BVH")
    _add_bvh_out(p)
    _add_common(p)
    p.set_defaults(run=cmd_walk)

    p = add("scenarios", "run the pose scenarios and the robustness (impossible) one; print the table",
            "Run pose scenarios like the studio does (one warm-started step per frame from the rest pose) and "
            "print per scenario: frames and sweeps to settle, frames to within 1 mm, final errors, the largest "
            "joint change after settling (0 = no oscillation) and NaN. --out DIR writes <scenario>.yaml (the "
            "final pose with its targets) and <scenario>.bvh (every frame) for each.")
    p.add_argument("--skeleton", default="biped", help="skeleton (default biped)")
    p.add_argument("--only", nargs="+", action="extend", metavar="NAME", help="run only these built-in scenarios")
    p.add_argument("--random", type=int, default=0, metavar="N", help="also run N seeded random poses")
    p.add_argument("--no-builtin", action="store_true", help="with --random: skip the built-in scenarios")
    p.add_argument("--seed", type=int, default=0, help="seed of the first random pose (default 0)")
    p.add_argument("--spread", type=_finite, default=0.5, help="random pose spread, 0 (rest) to 1 (default 0.5)")
    p.add_argument("--max-frames", type=_positive_int, default=600,
                   help="frames allowed to settle after the targets stop moving (default 600)")
    p.add_argument("--verbose", "-v", action="store_true", help="also print each effector's final errors")
    p.add_argument("--out", metavar="DIR", help="write each scenario's pose YAML and BVH into DIR")
    _add_bvh_out(p)
    _add_common(p)
    p.set_defaults(run=cmd_scenarios)

    p = add("track", "track a BVH clip's effectors frame by frame; report errors and time per frame",
            "Import a BVH clip as a skeleton and motion, then solve its own effector poses frame by frame, "
            "warm-started (motion-capture cleanup's core loop). Prints position and orientation errors and "
            "the solver time per frame; --out writes the solved motion.")
    p.add_argument("clip", metavar="CLIP.bvh", help="a BVH file")
    p.add_argument("--effectors", nargs="+", action="extend", metavar="NAME",
                   help="joints or end sites to track (names or a comma list; default every end site and the "
                        "pelvis)")
    p.add_argument("--root", help="the IK root, pinned where the clip has it (default the top joint)")
    p.add_argument("--position-only", action="store_true", help="track positions only")
    p.add_argument("--strip-namespace", action="store_true", help="drop 'prefix:' from joint names")
    p.add_argument("--scale", type=_finite, help="metres per file unit (default: detected)")
    p.add_argument("--file-up", choices=("auto", "y", "z"), default="auto", help="the clip's up axis")
    p.add_argument("--steps-per-frame", type=_positive_int, help="most solver steps per frame (default 5)")
    p.add_argument("--out", metavar="SOLVED.bvh", help="write the solved motion as BVH")
    _add_bvh_out(p)
    _add_common(p, progress=False)
    p.set_defaults(run=cmd_track)

    p = add("bench", "the solver benchmarks (paper Table 1, tracking, stability, reach)",
            "Run the solver benchmarks of benchmarks/bench_solver.py and print them as Markdown.")
    p.add_argument("--quick", action="store_true", help="fewer repeats (seconds instead of minutes)")
    _add_common(p, solver=False)
    p.set_defaults(run=cmd_bench)
    return parser


def main(argv: Sequence[str] | None = None, out: TextIO | None = None) -> int:
    """Run the command line; returns the exit code (``gsik`` and ``python -m gsik`` exit with it)."""
    out = sys.stdout if out is None else out
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a usage error (argparse printed it)
        return int(exc.code or 0)
    try:
        return args.run(args, out)
    except CommandError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except GsikError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        where = f" {exc.filename!r}" if exc.filename else ""
        print(f"{PROG}: error: cannot access{where}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
