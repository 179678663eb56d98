"""Mutation fuzzing of gsik's readers: shared by the tests (a few hundred cases each) and benchmarks/fuzz_long.py.

Every reader gets valid seed files, mutated by a fixed-seed random generator with the edits hostile files use
(anchors, tags, brackets, huge and non-finite numbers, NUL, byte-order marks, deleted and repeated lines, XML
entities ...). The contract checked: a mutated file is either read, or refused with a :class:`gsik.GsikError`
whose message is bounded and names the source; any other exception is a crash.
"""

from __future__ import annotations

import functools
import random
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import gsik
from gsik.io.bvh import parse_bvh
from gsik.io.bvh_skeleton import import_bvh
from gsik.io.pose import pose_from_yaml, pose_to_yaml
from gsik.io.urdf import parse_urdf
from gsik.io.urdf_skeleton import skeleton_from_urdf

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
HOSTILE = DATA / "hostile"

#: Longest message a refusal may have [characters]: a few bounded values, names and a path.
MAX_MESSAGE = 2000

_COMMON = ["\x00", "\ufeff", "\t", "\r\n", "\r", "\n", "\\", "'", '"', "\u2028", "\udc80", "\U0001F9B4", "é",
           "9" * 30, "-" + "9" * 400, "1.0e+400", "-1.0e+400", "1e400", "nan", ".nan", "inf", "-.inf", "-0", "0x" + "f" * 20,
           "1e308", "-1e308", "5e-324", "x" * 300]
TOKENS = {
    "yaml": _COMMON + ["&a ", "*a", "&a [*a]", "!!python/object/apply:os.system ['true']", "!!binary aGk=", "!tag ",
                       "!!set {a}", "!!str ", "!!int ", "!!float ", "[", "]", "{", "}", ": ", ":", ",", "- ", "? ",
                       "<<: ", "|", ">", "%YAML 1.1\n---\n", "---\n", "...\n", "#", "@", "`", "~", "null", "true", "=",
                       "2001-13-45", "1:30:00", "[" * 200, "{a: " * 100],
    "bvh": _COMMON + ["{", "}", "ROOT ", "JOINT ", "End Site", "OFFSET ", "CHANNELS 3 ", "CHANNELS 99999999999 ",
                      "Xrotation", "Yposition", "MOTION\n", "Frames: ", "Frames: 99999999999", "Frame Time: ",
                      "Frame Time: 0", "Frame Time: -1", "HIERARCHY\n", "[root]", "{" * 200],
    "urdf": _COMMON + ["<", ">", "/>", "</joint>", "<joint name='j' type='revolute'>", "<link name='l'/>",
                       '<!DOCTYPE r [<!ENTITY a "aaaa">]>', "&a;", "&amp;", "&#0;", "&#xD800;", "<![CDATA[",
                       "<xi:include href='/etc/passwd'/>", 'encoding="no-such-codec"', 'xyz="1e308 1e308 0"',
                       'type="floating"', 'type="continuous"', 'lower="1" upper="-1"', "<mimic joint='j'/>",
                       'rpy="1e400 0 0"'],
}


def pose_of(skeleton: gsik.Skeleton):
    """The rest pose of ``skeleton`` with a target at every effector, as a pose file holds it."""
    from gsik.io.pose import Pose
    from gsik.rotations import quaternion_from_matrix
    solver = gsik.Solver(skeleton)
    W = solver.world_from_root
    targets = {n: _target_pose(T) for n, T in solver.effector_poses().items()}
    return Pose(skeleton.name, solver.root, tuple(W[:3, 3]), tuple(quaternion_from_matrix(W[:3, :3])),
                dict(zip(skeleton.dof_names, solver.q.tolist())), targets)


def _target_pose(world_from_effector):
    """The pose module's target type, whatever it is called on this branch."""
    import gsik.io.pose as pose_module
    make = getattr(pose_module, "TargetPose", None) or gsik.Target
    return make.from_transform(world_from_effector)


def _pose_with_motion(skeleton: gsik.Skeleton) -> str:
    """A pose file that also keeps keys, poles and a two-frame clip (the studio's timeline and pole targets)."""
    import numpy as np

    from gsik.anim.motion import Motion
    from gsik.io.pose import Clip, KeySequence, Pole

    pose = pose_of(skeleton)
    W = np.tile(gsik.Solver(skeleton).world_from_root, (2, 1, 1))
    clip = Clip("walk.bvh", Motion(skeleton, np.tile(skeleton.rest, (2, 1)), (skeleton.root,) * 2, W, 1 / 30))
    return pose_to_yaml(pose, keys=KeySequence(((0, pose), (12, pose)), 24.0, 20),
                        poles={"left_knee": Pole((0.1, 0.3, 0.5)), "right_elbow": Pole((-0.2, 0.1, 1.0), False)},
                        clip=clip)


@functools.cache
def seeds() -> dict[str, list[str]]:
    """Valid seed texts for each format."""
    return {
        "pose": [pose_to_yaml(pose_of(gsik.load_skeleton("biped"))), _pose_with_motion(gsik.load_skeleton("biped"))],
        "skeleton": [(ROOT / "skeletons" / "biped.yaml").read_text(encoding="utf-8")],
        "bvh": [p.read_text(encoding="utf-8") for p in sorted(DATA.glob("*.bvh"))],
        "urdf": [p.read_text(encoding="utf-8") for p in sorted(DATA.glob("*.urdf"))],
    }


@functools.cache
def readers() -> dict[str, tuple[str, Callable[[str], object]]]:
    """Each reader: (token family, function reading one text the way a user's file is read)."""
    biped = gsik.load_skeleton("biped")

    def bvh(text: str):
        clip = parse_bvh(text, "fuzz.bvh")
        return import_bvh(clip)

    def urdf(text: str):
        return skeleton_from_urdf(parse_urdf(text, "fuzz.urdf"))

    return {
        "pose": ("yaml", lambda text: pose_from_yaml(text, biped, "fuzz.yaml")),
        "skeleton": ("yaml", lambda text: gsik.skeleton_from_yaml(text, "fuzz.yaml")),
        "bvh": ("bvh", bvh),
        "urdf": ("urdf", urdf),
    }


def mutate(text: str, tokens: list[str], rng: random.Random) -> str:
    """``text`` with 1-3 random hostile edits (mostly one, so most of the file stays valid)."""
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        op = rng.randrange(7)
        i = rng.randrange(len(text) + 1)
        if op == 0:  # insert a hostile token
            text = text[:i] + rng.choice(tokens) + text[i:]
        elif op == 1:  # replace a run with a token
            text = text[:i] + rng.choice(tokens) + text[i + rng.randint(1, 12):]
        elif op == 2:  # delete a run
            text = text[:i] + text[i + rng.randint(1, 40):]
        elif op == 3:  # one random character
            text = text[:i] + chr(rng.choice([rng.randrange(32, 127), rng.randrange(0, 0x110000)])) + text[i + 1:]
        elif op == 4:  # truncate
            text = text[:i]
        else:  # repeat or swap lines
            lines = text.split("\n")
            a, b = rng.randrange(len(lines)), rng.randrange(len(lines))
            if op == 5:
                lines.insert(a, lines[b])
            else:
                lines[a], lines[b] = lines[b], lines[a]
            text = "\n".join(lines)
    return text


@dataclass
class Outcome:
    """Counts of one fuzz run; ``crashes`` holds (input, exception) for anything but a clean refusal."""

    read: int = 0
    refused: int = 0
    crashes: list = field(default_factory=list)
    slowest: float = 0.0

    @property
    def total(self) -> int:
        return self.read + self.refused + len(self.crashes)


def check_refusal(exc: BaseException, source: str) -> str | None:
    """Why ``exc`` breaks the error contract, or ``None`` when it is a clean refusal."""
    if not isinstance(exc, gsik.GsikError):
        return f"{type(exc).__name__} is not a GsikError"
    message = str(exc)
    if len(message) > MAX_MESSAGE:
        return f"message of {len(message)} characters"
    if source not in message:
        return f"message does not name {source!r}"
    return None


def fuzz(kind: str, n: int, seed: int = 0) -> Outcome:
    """Read ``n`` mutated files of ``kind`` (``pose``, ``skeleton``, ``bvh``, ``urdf``); count what happened."""
    family, read = readers()[kind]
    texts = seeds()[kind]
    source = {"yaml": "fuzz.yaml", "bvh": "fuzz.bvh", "urdf": "fuzz.urdf"}[family]
    rng = random.Random(seed)
    out = Outcome()
    for _ in range(n):
        text = mutate(rng.choice(texts), TOKENS[family], rng)
        start = time.perf_counter()
        try:
            read(text)
            out.read += 1
        except Exception as exc:  # noqa: BLE001 - what the contract is about
            problem = check_refusal(exc, source)
            if problem is None:
                out.refused += 1
            else:
                out.crashes.append((text, problem, exc))
        out.slowest = max(out.slowest, time.perf_counter() - start)
    return out


# -- bombs: memory and time of reading each hostile file, measured in a fresh process ------------------------

#: (fixture, reader) pairs: every bomb through each reader it could be handed to.
BOMBS = [("alias_bomb_pose.yaml", "pose"), ("alias_bomb_skeleton.yaml", "skeleton"), ("self_alias.yaml", "pose"),
         ("self_alias.yaml", "skeleton"), ("deep_nesting.yaml", "pose"), ("deep_nesting.yaml", "skeleton"),
         ("huge_int_pose.yaml", "pose"), ("xml_bomb.urdf", "urdf")]


def _file_readers() -> dict[str, Callable]:
    from gsik.io.pose import read_pose
    from gsik.io.urdf import read_urdf
    biped = gsik.load_skeleton("biped")
    return {"pose": lambda p: read_pose(p, biped), "skeleton": gsik.load_skeleton,
            "urdf": lambda p: skeleton_from_urdf(read_urdf(p))}


def measure_bombs() -> dict:
    """Read every bomb twice (timed, then under tracemalloc); returns figures per bomb and the process's peak.

    Meant to run in a fresh process (``python -c "import fuzzing; fuzzing.print_bomb_figures()"``), so the peak
    resident size is the bombs' own and not a test session's.
    """
    import resource
    import tracemalloc
    read = _file_readers()
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    figures = []
    for name, kind in BOMBS:
        path = str(HOSTILE / name)
        start = time.process_time()
        outcome = _outcome(read[kind], path)
        cpu = time.process_time() - start
        tracemalloc.start()
        _outcome(read[kind], path)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        figures.append({"file": name, "reader": kind, "outcome": outcome, "cpu_s": cpu, "traced_peak_mb": peak / 2**20})
    rss_after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # kB on Linux
    return {"bombs": figures, "rss_growth_mb": (rss_after - rss_before) / 1024, "rss_peak_mb": rss_after / 1024}


def _outcome(read: Callable, path: str) -> str:
    try:
        read(path)
        return "read"
    except gsik.GsikError as exc:
        return f"{type(exc).__name__}: {str(exc)[:120]}"


def print_bomb_figures() -> None:
    import json
    print(json.dumps(measure_bombs()))


def big_bvh_text(n_frames: int, n_joints: int = 10) -> str:
    """A BVH clip of ``n_frames`` frames: a 6-channel root and ``n_joints`` 3-channel joints, 4 decimals a value."""
    import numpy as np
    lines = ["HIERARCHY", "ROOT hips", "{", "  OFFSET 0 0 0",
             "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"]
    for i in range(n_joints):
        lines += [f"  JOINT j{i}", "  {", "    OFFSET 0 1 0", "    CHANNELS 3 Zrotation Xrotation Yrotation",
                  "    End Site", "    {", "      OFFSET 0 1 0", "    }", "  }"]
    lines += ["}", "MOTION", f"Frames: {n_frames}", "Frame Time: 0.0333333"]
    row = " ".join(f"{v:.4f}" for v in np.random.default_rng(0).uniform(-180, 180, 6 + 3 * n_joints))
    return "\n".join(lines) + "\n" + (row + "\n") * n_frames


def print_bvh_figures(n_frames: int) -> None:
    """Parse a large BVH text and print its size, time and the process's memory growth (run in a fresh process)."""
    import json
    import resource
    from gsik.io.bvh import parse_bvh
    text = big_bvh_text(n_frames)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    clip = parse_bvh(text, "big.bvh")
    seconds = time.perf_counter() - start
    growth = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024
    print(json.dumps({"frames": clip.n_frames, "channels": clip.motion.shape[1], "file_mb": len(text) / 2**20,
                      "seconds": seconds, "growth_mb": growth}))


def fuzz_solver(n: int, seed: int = 0) -> dict[str, int]:
    """``n`` solver calls on random extreme input (targets at and beyond the limits, extreme weights, huge root
    placements); counts refusals at the edge and calls that left a non-finite or out-of-limits pose."""
    import numpy as np
    rng = random.Random(seed)
    biped = gsik.load_skeleton("biped")
    solver = gsik.Solver(biped)
    allowed = [0.0, 1e-300, 5e-324, 0.5, -1.0, 1e3, 1e6, -1e6]
    beyond = [1e6 + 1, 1e154, 1e300, float("nan"), float("inf")]

    def extreme() -> float:
        return rng.choice(beyond if rng.random() < 0.03 else allowed)

    counts = {"calls": 0, "refused at the edge": 0, "steps refused (Status.REFUSED)": 0, "poisoned": 0}
    for _ in range(n):
        name = rng.choice(solver.effector_names)
        try:
            if rng.random() < 0.1:
                W = np.eye(4)
                W[:3, 3] = [extreme() for _ in range(3)]
                if rng.random() < 0.5:
                    W[:3, :3] *= extreme()
                solver.set_world_from_root(W)
            target = gsik.Target([extreme() for _ in range(3)], weight=extreme())
            result = solver.solve({name: target}) if rng.random() < 0.2 else solver.step({name: target})
        except gsik.GsikError:
            counts["refused at the edge"] += 1
            continue
        counts["calls"] += 1
        counts["steps refused (Status.REFUSED)"] += result.status is gsik.Status.REFUSED
        q = solver.q
        finite_errors = np.isfinite(result.position_errors).all() and np.isfinite(result.orientation_errors).all()
        poisoned = (not np.isfinite(q).all() or np.any(q < biped.lower - 1e-9) or np.any(q > biped.upper + 1e-9)
                    or (result.status is gsik.Status.CONVERGED and not finite_errors))
        counts["poisoned"] += bool(poisoned)
        if rng.random() < 0.05:
            solver.set_world_from_root(np.eye(4))
    return counts


def kill_during_saves(path, old: str, new: str, rng: random.Random) -> int:
    """Fork a process that saves ``new`` and ``old`` to ``path`` in turn; SIGKILL it after a random few
    milliseconds. Returns the dead writer's process id."""
    import os
    import signal
    from gsik.io.files import atomic_write_text
    pid = os.fork()
    if pid == 0:  # the writer: never returns into the caller
        try:
            while True:
                atomic_write_text(path, new)
                atomic_write_text(path, old)
        finally:
            os._exit(0)
    time.sleep(rng.uniform(0.001, 0.03))
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    return pid
