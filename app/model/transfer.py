"""Import and export between the document and other files: BVH clips, skeletons (YAML or URDF), BVH export.

Plain Python, through gsik's public readers and writers only (so fixes of the
BVH conventions in :mod:`gsik.io.bvh_skeleton` flow in). Every reader raises
a :class:`gsik.GsikError` on a bad file before anything in a document changes.
"""

from __future__ import annotations

import os

import numpy as np

import gsik
from gsik.anim.motion import Motion
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import BvhImport, import_bvh, write_motion_bvh
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik_studio.model.document import Document

#: Largest angle [rad] a padding DOF of an exported clip may have (the writer prints 1e-6 degrees).
PADDING_TOLERANCE = 1e-6

#: File name endings read as URDF (anything else is skeleton YAML).
URDF_SUFFIXES = (".urdf", ".xml")


def read_clip(path: str | os.PathLike) -> BvhImport:
    """A BVH file as a skeleton and its motion (named after the file).

    Raises:
        GsikFileError, BvhError: the file cannot be read or is not valid BVH.
    """
    name = os.path.splitext(os.path.basename(os.fspath(path)))[0] or "bvh"
    return import_bvh(read_bvh(path), name=name)


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


def read_skeleton(path: str | os.PathLike) -> gsik.Skeleton:
    """A skeleton from a YAML file or a URDF file (by its ending, :data:`URDF_SUFFIXES`).

    Raises:
        GsikError: the file cannot be read or is not a valid skeleton.
    """
    if os.fspath(path).lower().endswith(URDF_SUFFIXES):
        return skeleton_from_urdf(path)
    return gsik.load_skeleton(path)


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


def export_bvh(doc: Document, path: str | os.PathLike, units: str = "cm", up: str = "z") -> str:
    """Write :func:`export_source` as BVH (gsik's Blender-compatible writer); returns what was written.

    Raises:
        GsikFileError, BvhError: nothing was written.
    """
    what, motion = export_source(doc)
    write_motion_bvh(path, motion, units=units, up=up)
    return what


def describe(skeleton: gsik.Skeleton) -> str:
    """A short description of a skeleton for messages ("humanoid: 12 DOFs, effectors a, b")."""
    return f"{skeleton.name}: {skeleton.n_dofs} DOFs, effectors {', '.join(skeleton.effector_sites)}"

