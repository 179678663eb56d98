"""Import and export between the document and other files: BVH clips, skeletons (YAML or URDF), BVH export.

Plain Python, through gsik's public readers and writers only (so fixes of the
BVH conventions in :mod:`gsik.io.bvh_skeleton` flow in). Every reader raises
a :class:`gsik.GsikError` on a bad file before anything in a document changes.
"""

from __future__ import annotations

import os
from typing import NamedTuple

import numpy as np

import gsik
from gsik.anim.motion import Motion
from gsik.io.bvh import read_bvh
from gsik.cli.common import load_any_skeleton
from gsik.io.bvh_skeleton import BvhImport, import_bvh, write_motion_bvh
from gsik.io.pose import read_pose_document
from gsik.io.pose.read import names_a_skeleton_file
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.targets import MAX_COORDINATE
from gsik_studio.model.document import Document

#: Largest angle [rad] a padding DOF of an exported clip may have: the writer prints 1e-6 degrees, and a y-up export
#: read back turns its rows through the axis change (3e-5 rad measured on an atlas' padding z of a walk).
PADDING_TOLERANCE = 1e-4

#: File name endings read as URDF (anything else is skeleton YAML).
URDF_SUFFIXES = (".urdf", ".xml")


def read_clip(path: str | os.PathLike) -> BvhImport:
    """A BVH file as a skeleton and its motion (named after the file).

    Raises:
        GsikFileError, BvhError: the file cannot be read or is not valid BVH.
    """
    name = os.path.splitext(os.path.basename(os.fspath(path)))[0] or "bvh"
    imported = import_bvh(read_bvh(path), name=name, source=os.fspath(path))
    check_playable(imported.motion, os.fspath(path))
    return imported


def check_playable(motion: Motion, source: str) -> None:
    """Refuse, before any document changes, a clip the studio could not show: no frames, a skeleton without
    degrees of freedom, or a root placed beyond :data:`gsik.targets.MAX_COORDINATE`."""
    if motion.n_frames < 1:
        raise gsik.BvhError("the clip has no frames (Frames: 0): nothing to play", path=source)
    check_poseable(motion.skeleton, source)
    far = np.abs(motion.world_from_root[:, :3, 3]).max(axis=1) > MAX_COORDINATE
    if far.any():
        raise gsik.BvhError(f"frame {int(np.argmax(far)) + 1} places the root beyond {MAX_COORDINATE:g} m",
                            path=source)


def check_poseable(skeleton: gsik.Skeleton, source: str) -> None:
    """Refuse a skeleton without degrees of freedom: nothing in it could be posed."""
    if skeleton.n_dofs == 0:
        raise gsik.SkeletonError(f"{source}: skeleton {skeleton.name!r} has no degrees of freedom (no joint "
                                 "rotates): nothing to pose")


def motion_on(skeleton: gsik.Skeleton, motion: Motion) -> Motion | None:
    """``motion`` as a motion of ``skeleton`` when it is a clip exported from it, else None.

    DOFs match by name. The clip may have more: gsik's BVH export pads hinges and 2-DOF joints with rotation
    channels that stay 0 (Blender reads only 0 or 3 per joint), and those come back as extra DOFs; any that moves
    means the clip is of another skeleton.
    """
    sk = motion.skeleton
    column = {name: i for i, name in enumerate(sk.dof_names)}
    if any(n not in column for n in skeleton.dof_names) or any(r not in skeleton.frame_names for r in set(motion.roots)):
        return None
    kept = [column[n] for n in skeleton.dof_names]
    extra = np.setdiff1d(np.arange(sk.n_dofs), kept)
    if extra.size and np.abs(motion.q[:, extra]).max() > PADDING_TOLERANCE:
        return None
    return Motion(skeleton, motion.q[:, kept], motion.roots, motion.world_from_root, motion.frame_time)


def placed_on_grid(motion: Motion) -> Motion:
    """``motion`` moved, not turned, so that its first frame stands on the grid: the skeleton's first frame (a BVH
    clip's root joint, the hips) over the origin, and the first frame's lowest point on the ground (z = 0).

    Every frame moves by the same offset [m], so the motion itself (steps, jumps, turns) is kept.
    """
    P = motion.frames(0)[1]  # (n_skeleton_frames, 3) [m]
    W = np.array(motion.world_from_root)
    W[:, :3, 3] -= [P[0, 0], P[0, 1], P[:, 2].min()]
    return Motion(motion.skeleton, motion.q, motion.roots, W, motion.frame_time)


def read_skeleton(path: str | os.PathLike) -> gsik.Skeleton:
    """A skeleton from a YAML file or a URDF file (by its ending, :data:`URDF_SUFFIXES`).

    Raises:
        GsikError: the file cannot be read or is not a valid skeleton.
    """
    if os.fspath(path).lower().endswith(URDF_SUFFIXES):
        skeleton = skeleton_from_urdf(path)
    else:
        skeleton = gsik.load_skeleton(path)
    check_poseable(skeleton, os.fspath(path))
    return skeleton


def pose_skeleton(path: str | os.PathLike, current: gsik.Skeleton) -> gsik.Skeleton:
    """The skeleton a pose file opens on: the one its ``skeleton:`` field names.

    ``current`` when the field is its name (or missing: then the file is read against it); a bundled skeleton by
    name; a skeleton file (YAML, URDF, BVH) by its path, relative to the pose file.

    Raises:
        GsikError: the file cannot be read, or names a skeleton that is neither ``current``, bundled nor a file.
    """
    spec = read_pose_document(path).skeleton
    if spec is None or spec == current.name:
        return current
    if spec in gsik.bundled_skeletons() or names_a_skeleton_file(spec):
        return load_any_skeleton(spec)
    raise gsik.PoseError(f"{os.fspath(path)}: the pose is for skeleton {spec!r}, which is not bundled "
                         f"({', '.join(gsik.bundled_skeletons())}) nor the skeleton shown ({current.name!r}): "
                         f"import that skeleton first, then open the pose")


def open_pose(path: str | os.PathLike, doc: Document) -> tuple[Document, tuple[str, ...]]:
    """Open a pose file on its own skeleton: into ``doc`` when it is of ``doc``'s skeleton, else into a new
    document built completely first; returns (the document holding it, the reader's warnings).

    Raises:
        GsikError: nothing changed (``doc`` is left exactly as it was).
    """
    skeleton = pose_skeleton(path, doc.skeleton)
    if skeleton is doc.skeleton:
        return doc, doc.open(path)
    new = document_for(skeleton)
    return new, new.open(path)


def document_for(skeleton: gsik.Skeleton) -> Document:
    """A new document on ``skeleton``: its effector sites as targets, its own default root, standing at rest."""
    return Document(skeleton)


def export_source(doc: Document) -> tuple[str, Motion]:
    """What Export BVH writes: ("clip", the timeline's clip), else ("keys", the baked keys), else ("pose", one frame)."""
    tl = doc.timeline
    if tl.clip is not None:
        return "clip", tl.clip
    if tl.keys:
        return "keys", tl.motion
    W = doc.solver.world_from_root
    return "pose", Motion(doc.skeleton, doc.q[None, :], (doc.root,), W[None], 1 / 30)


class BvhExportOptions(NamedTuple):
    """How Export BVH writes: the file's up axis ("y" or "z") and length unit ("cm" or "m").

    The default, y-up centimetres, is what Blender's BVH importer expects by default: the figure comes in standing.
    """

    up: str = "y"
    units: str = "cm"


def export_bvh(doc: Document, path: str | os.PathLike, options: BvhExportOptions = BvhExportOptions()) -> str:
    """Write :func:`export_source` as BVH (gsik's Blender-compatible writer); returns what was written.

    Raises:
        GsikFileError, BvhError: nothing was written.
    """
    what, motion = export_source(doc)
    write_motion_bvh(path, motion, units=options.units, up=options.up)
    return what


class BvhExport:
    """One Export BVH stepped in chunks, so that a window never blocks for long: a key sequence is baked
    ``budget_frames`` at a time, and the file is written (atomically, :func:`export_bvh`) only by the step that
    finishes. A cancelled export writes nothing (the frames baked so far stay in the timeline's bake).

    Attributes:
        bake: The keys' bake to finish first (None for a clip or a pose: one step writes).
        what: What was written ("clip", "keys" or "pose"), once :attr:`finished`.
    """

    def __init__(self, doc: Document, path: str | os.PathLike, options: BvhExportOptions = BvhExportOptions()):
        self.doc, self.path, self.options = doc, path, options
        tl = doc.timeline
        self.bake = tl.bake if tl.clip is None else None
        self.what: str | None = None
        self.finished = self.cancelled = False

    @property
    def n_frames(self) -> int:
        """Frames to bake in all (0 when there is nothing to bake)."""
        return self.bake.n_frames if self.bake is not None else 0

    @property
    def baked(self) -> int:
        """Frames baked so far."""
        return self.bake.solved if self.bake is not None else 0

    @property
    def ready(self) -> bool:
        """True when the next :meth:`step` writes the file (nothing left to bake)."""
        return self.bake is None or self.bake.done

    def step(self, budget_frames: int) -> bool:
        """Bake up to ``budget_frames`` frames, or write the file when none are left; True once written.

        Raises:
            GsikError: cancelled already, or the file could not be written (nothing was).
        """
        if self.cancelled:
            raise gsik.GsikError(f"the export to {os.fspath(self.path)} was cancelled")
        if not self.finished and not self.ready:
            self.bake.step(budget_frames)
        elif not self.finished:
            self.what = export_bvh(self.doc, self.path, self.options)
            self.finished = True
        return self.finished

    def cancel(self) -> None:
        """Give up: nothing is written."""
        self.cancelled = True


def describe(skeleton: gsik.Skeleton) -> str:
    """A short description of a skeleton for messages ("humanoid: 12 DOFs, effectors a, b")."""
    return f"{skeleton.name}: {skeleton.n_dofs} DOFs, effectors {', '.join(skeleton.effector_sites)}"

