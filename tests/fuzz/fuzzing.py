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


@functools.cache
def seeds() -> dict[str, list[str]]:
    """Valid seed texts for each format."""
    biped = gsik.load_skeleton("biped")
    solver = gsik.Solver(biped)
    from gsik.io.pose import Pose
    from gsik.rotations import quaternion_from_matrix
    W = solver.world_from_root
    targets = {n: _target_pose(T) for n, T in solver.effector_poses().items()}
    pose = Pose(biped.name, solver.root, tuple(W[:3, 3]), tuple(quaternion_from_matrix(W[:3, :3])),
                dict(zip(biped.dof_names, solver.q.tolist())), targets)
    return {
        "pose": [pose_to_yaml(pose)],
        "skeleton": [(ROOT / "skeletons" / "biped.yaml").read_text(encoding="utf-8")],
        "bvh": [p.read_text(encoding="utf-8") for p in sorted(DATA.glob("*.bvh"))],
        "urdf": [p.read_text(encoding="utf-8") for p in sorted(DATA.glob("*.urdf"))],
    }


def _target_pose(world_from_effector):
    """The pose module's target type, whatever it is called on this branch."""
    import gsik.io.pose as pose_module
    make = getattr(pose_module, "TargetPose", None) or gsik.Target
    return make.from_transform(world_from_effector)


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
