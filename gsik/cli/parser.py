"""The options of every command (``gsik --help``) and :func:`main`, which runs one and maps errors to exit codes."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from typing import TextIO

import gsik
from gsik.cli.batch import add_batch_options
from gsik.cli.commands import cmd_bench, cmd_scenarios, cmd_solve, cmd_walk
from gsik.cli.track import cmd_track
from gsik.cli.common import PROG
from gsik.cli.humanoid import add_command as add_humanoid_command
from gsik.cli.info import cmd_info
from gsik.cli.gltf import add_command as add_gltf_command
from gsik.cli.prior import add_commands as add_prior_commands
from gsik.errors import GsikError, show_value


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
    g.add_argument("--end-sites", action="store_true", help="write a site that is its joint's only child as an "
                   "End Site (no extra bone in Blender; a re-import names it <joint>_end)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, allow_abbrev=False,
        description="Real-time character inverse kinematics by Projected Gauss-Seidel (Kenwright 2012).",
        epilog="Run 'gsik COMMAND --help' for a command's options. Lengths are metres, angles radians, "
               "unless an option says otherwise. " + EXIT_CODES)
    parser.add_argument("--version", action="version", version=f"%(prog)s {gsik.__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def add(name: str, help: str, description: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help, description=description, allow_abbrev=False, epilog=EXIT_CODES)

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

    p = add("track", "track a BVH clip (or a folder of clips) frame by frame; report every joint's error",
            "Import a BVH clip as a skeleton and motion, then solve its targets frame by frame (motion-capture "
            "cleanup's core loop). By default each frame starts from the clip's own pose and prefers it (the "
            "lowest priority), so every joint the targets do not need follows the clip, and the output keeps the "
            "input's "
            "conventions (names, End Sites, channels, root OFFSET, units, up axis, frame time). Prints the "
            "targets' errors, every joint's error against the clip and the time per frame. CLIP may be a folder: "
            "its clips are tracked in parallel worker processes (--out names a folder then) with one summary "
            "table.")
    p.add_argument("clip", metavar="CLIP.bvh|DIR", help="a BVH file, or a folder of them")
    g = p.add_argument_group("targets")
    g.add_argument("--effectors", nargs="+", action="extend", metavar="NAME",
                   help="joints or end sites to track (names or a comma list; default every end site and the "
                        "pelvis), e.g. LeftKnee,mixamorig:LeftHand")
    g.add_argument("--position-only", nargs="?", action="append", const="*", metavar="NAMES",
                   help="track positions only: all targets, or the ones named (a comma list)")
    g.add_argument("--priority", nargs="+", action="extend", metavar="NAME=LEVEL",
                   help="priority levels, 0 the most important (default: end sites 0, other joints 1)")
    g.add_argument("--pole", nargs="+", action="extend", metavar="NAME",
                   help="knees or elbows to hold where the clip has them (position only, below every other "
                        "target): the limb's plane follows the clip")
    g.add_argument("--root", help="the IK root, pinned where the clip has it (default the top joint)")
    g.add_argument("--no-follow-clip", dest="follow_clip", action="store_false",
                   help="no preferred posture: frame 0 from the rest pose, untracked joints go where the solver "
                        "puts them (the solver measure)")
    g.add_argument("--posture-weight", type=_finite, default=1.0, help="weight of the clip's pose (default 1)")
    g = p.add_argument_group("input")
    g.add_argument("--strip-namespace", action="store_true",
                   help="drop 'prefix:' from joint names for the target options (the output keeps them)")
    g.add_argument("--scale", type=_finite, help="metres per file unit (default: detected)")
    g.add_argument("--file-up", choices=("auto", "y", "z"), default="auto",
                   help="the clip's up axis (default: detected over the whole clip, with a note why)")
    p.add_argument("--steps-per-frame", type=_positive_int, help="most solver steps per frame (default 5)")
    add_batch_options(p)
    p.add_argument("--force", action="store_true", help="write a result even when a frame is not a rotation")
    p.add_argument("--out", metavar="SOLVED.bvh|DIR", help="write the solved motion as BVH (a folder for a folder)")
    g = p.add_argument_group("BVH output (default: the input's conventions)")
    g.add_argument("--units", choices=("cm", "m"), help="change the length unit (writes gsik's layout)")
    g.add_argument("--up", choices=("z", "y"), help="change the up axis (writes gsik's layout)")
    g.add_argument("--wrap-angles", action="store_true",
                   help="write angles in [-180, 180) (default: continuous, as tracked)")
    _add_common(p)
    p.set_defaults(run=cmd_track)

    add_prior_commands(add, _add_common)
    add_humanoid_command(add)
    add_gltf_command(add)

    p = add("bench", "the solver benchmarks (paper Table 1, tracking, stability, reach)",
            "Run the solver benchmarks of benchmarks/bench_solver.py and print them as Markdown.")
    p.add_argument("--quick", action="store_true", help="fewer repeats (seconds instead of minutes)")
    _add_common(p, solver=False)
    p.set_defaults(run=cmd_bench)
    return parser


#: The exit codes, for ``gsik --help`` and every command's.
EXIT_CODES = ("exit codes: 0 done; 2 bad input (a file, a field, an option); 3 a result outside its tolerance, not "
              "written (--force writes it); 4 some clips of a folder failed (the others were written); 1 an "
              "unexpected failure; 130 interrupted.")


def _fail(message: str, code: int = 2) -> int:
    """Report an input problem (or a result outside its tolerance) as one line on stderr; exit code ``code``."""
    print(f"{PROG}: error: {' '.join(message.split(chr(10)))}", file=sys.stderr)
    return code


def _inputs(args: argparse.Namespace) -> str:
    """The files a command was given, for a message that has nothing else to name."""
    named = [f"{show_value(getattr(args, k))}" for k in ("pose", "clip", "skeleton", "map")
             if isinstance(getattr(args, k, None), str)]
    return ", ".join(named) if named else "this input"


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
    except GsikError as exc:  # CommandError included; a ToleranceError exits 3
        return _fail(str(exc), exc.exit_code)
    except OSError as exc:
        where = f" {show_value(exc.filename)}" if exc.filename else ""
        return _fail(f"cannot access{where}: {exc.strerror or exc}")
    except MemoryError:
        return _fail(f"not enough memory for {_inputs(args)}")
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
