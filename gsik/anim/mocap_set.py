"""A folder of motion-capture clips retargeted onto a skeleton, frame-strided, grouped by performer.

What the pose prior learns from (:mod:`gsik.prior`, ``gsik learn-prior FOLDER``)
and what its leave-one-performer-out benchmark holds out
(``benchmarks/bench_prior.py``). Every ``*.bvh`` under the folder is read
(sorted by path, so the result does not depend on the file system's order),
every ``stride``-th frame is kept (neighbouring frames at 30-120 fps are near
copies: a stride costs little information and saves most of the retargeting),
and the kept frames are retargeted onto the skeleton (:mod:`gsik.anim.retarget`,
each frame warm-started from the previous kept one).

Performers: a CMU database file name ``SSS_TT.bvh`` (subject, trial) belongs
to subject ``SSS``; any other file is a performer of its own (its stem).
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gsik.anim.retarget import Retargeter
from gsik.errors import GsikFileError, RetargetError
from gsik.io.bvh import BvhClip, read_bvh
from gsik.io.bvh.limits import MAX_BVH_BYTES
from gsik.io.files import atomic_write_bytes, read_bounded
from gsik.io.npz import npz_bytes
from gsik.skeleton import Skeleton

#: A CMU database clip name: subject, underscore, trial number.
CMU_NAME = re.compile(r"^(\d+)_\d+$")


@dataclass(frozen=True, eq=False)
class RetargetedClip:
    """One clip's kept frames on the skeleton.

    Attributes:
        name: The clip's file name.
        performer: Who performed it (:func:`performer_of`).
        q: (n_frames, n_dofs) joint angles [rad] of the kept frames.
        world_from_root: (n_frames, 4, 4) where the IK root (the pelvis) stands [m].
        stride: Every how many of the clip's frames one was kept.
        mapped: The skeleton frames the clip drives (:attr:`gsik.anim.retarget.Retargeted.mapping`'s keys).
        targets: (n_frames, len(mapped), 3) where the clip put them, at the skeleton's proportions [m].
        errors: (n_frames, len(mapped)) their distance from there after the solve [m].
    """

    name: str
    performer: str
    q: np.ndarray
    world_from_root: np.ndarray
    stride: int
    mapped: tuple[str, ...]
    targets: np.ndarray
    errors: np.ndarray


def performer_of(path: str | os.PathLike) -> str:
    """The performer of a clip file: the subject of a CMU ``SSS_TT.bvh`` name, else the file's stem."""
    stem = Path(path).stem
    m = CMU_NAME.match(stem)
    return m.group(1) if m else stem


def clip_paths(paths: Iterable[str | os.PathLike]) -> list[Path]:
    """Every ``.bvh`` file among ``paths`` and under the folders among them, sorted, without repeats.

    Raises:
        GsikFileError: a path that does not exist, or no clip at all.
    """
    found: set[Path] = set()
    for p in map(Path, paths):
        if p.is_dir():
            found.update(q for q in p.rglob("*") if q.suffix.lower() == ".bvh" and q.is_file())
        elif p.is_file():
            found.add(p)
        else:
            raise GsikFileError(f"no such clip or folder: {p}")
    if not found:
        raise GsikFileError(f"no .bvh clip in {', '.join(map(str, paths))}")
    return sorted(found)


def strided(clip: BvhClip, stride: int) -> BvhClip:
    """Every ``stride``-th frame of ``clip`` (the first kept), its frame time scaled to match."""
    if stride < 1:
        raise RetargetError(f"stride must be a whole number >= 1, got {stride!r}")
    return BvhClip(clip.joints, clip.frame_time * stride, clip.motion[::stride])


def retarget_clip(skeleton: Skeleton, path: str | os.PathLike, stride: int = 1) -> RetargetedClip:
    """Read the clip at ``path``, keep every ``stride``-th frame and retarget them onto ``skeleton``."""
    clip = strided(read_bvh(path), stride)
    retargeter = Retargeter(skeleton, clip)
    r = retargeter.retarget(clip)
    return RetargetedClip(Path(path).name, performer_of(path), np.asarray(r.motion.q),
                          np.asarray(r.motion.world_from_root), stride, tuple(r.mapping),
                          retargeter.world_targets(clip)[1], r.errors)


def _cache_file(cache: Path, skeleton: Skeleton, path: Path, stride: int) -> Path:
    """Where a clip's retargeted frames are cached: keyed by the clip's bytes, the skeleton and the stride."""
    key = hashlib.sha256()
    key.update(read_bounded(path, "BVH clip", MAX_BVH_BYTES))  # the bounded reader every clip goes through
    for a in (skeleton.lower, skeleton.upper, skeleton.rest):
        key.update(np.ascontiguousarray(a, dtype=float).tobytes())
    key.update(repr((skeleton.name, skeleton.dof_names, stride)).encode())
    key.update(_code_digest())
    return cache / f"{path.stem}-{key.hexdigest()[:16]}.npz"


@functools.cache
def _code_digest() -> bytes:
    """A digest of gsik's own sources: a cached retargeting is stale once any of them changes."""
    key = hashlib.sha256()
    for f in sorted(Path(__file__).resolve().parents[1].rglob("*.py")):
        key.update(f.read_bytes())
    return key.digest()


def retarget_clips(skeleton: Skeleton, paths: Iterable[str | os.PathLike], stride: int = 1,
                   cache: str | os.PathLike | None = None,
                   progress: Callable[[int, int], None] | None = None) -> list[RetargetedClip]:
    """Retarget every clip of :func:`clip_paths` ``(paths)``, every ``stride``-th frame.

    ``cache``: a folder (created if needed) keeping each clip's result for the
    next call, keyed by the clip's contents, the skeleton's limits and rest
    pose, the stride and gsik's sources.
    ``progress(done, total)`` is called before each clip and once at the end.
    """
    out = []
    paths = clip_paths(paths)
    for k, path in enumerate(paths):
        if progress is not None:
            progress(k, len(paths))
        file = None if cache is None else _cache_file(Path(cache), skeleton, path, stride)
        if file is not None and file.exists():
            with np.load(file, allow_pickle=False) as z:
                out.append(RetargetedClip(path.name, performer_of(path), z["q"], z["world_from_root"], stride,
                                          tuple(str(m) for m in z["mapped"]), z["targets"], z["errors"]))
            continue
        r = retarget_clip(skeleton, path, stride)
        if file is not None:  # atomically, as every file gsik writes: a killed run leaves no torn cache entry
            file.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(file, npz_bytes({"q": r.q, "world_from_root": r.world_from_root,
                                                "mapped": np.array(r.mapped), "targets": r.targets,
                                                "errors": r.errors}))
        out.append(r)
    if progress is not None:
        progress(len(paths), len(paths))
    return out


def by_performer(clips: Iterable[RetargetedClip]) -> dict[str, np.ndarray]:
    """Each performer's poses (n, n_dofs) [rad], the clips in order, performers sorted by name."""
    groups: dict[str, list[np.ndarray]] = {}
    for c in clips:
        groups.setdefault(c.performer, []).append(c.q)
    return {p: np.concatenate(groups[p]) for p in sorted(groups)}
