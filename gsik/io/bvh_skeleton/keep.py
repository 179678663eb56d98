"""A solved motion written back into the clip it was imported from, keeping every convention of the file."""

from __future__ import annotations

import numpy as np

from gsik.anim.motion import Motion
from gsik.errors import BvhError
from gsik.io.bvh import BvhClip
from gsik.io.bvh.clip import AXIS_INDEX
from gsik.io.bvh_skeleton.conventions import Z_UP_TO_Y_UP, euler_from_matrix
from gsik.io.bvh_skeleton.importer import BvhImport
from gsik.kinematics import world_frames


def clip_with_motion(imported: BvhImport, motion: Motion, wrap_angles: bool = False) -> BvhClip:
    """``imported.clip`` with its motion replaced by ``motion``'s: the file's conventions kept.

    Everything but the motion numbers is the input clip's: joint names
    (namespaces included, whatever the import stripped), End Sites, OFFSETs
    (the root's too), channel orders, units, up axis and frame time. Each
    rotation channel gets its DOF's angle in degrees; position channels of
    joints other than the root keep the clip's values (gsik joints do not
    slide). The root's channels keep the clip's values where ``motion`` pins
    the top joint where the clip has it (the usual track); otherwise they are
    the top joint's world pose in ``motion``, in the file's axes and units.

    Args:
        imported: What :func:`~gsik.io.bvh_skeleton.import_bvh` made of the clip.
        motion: A motion on ``imported.skeleton`` (or a skeleton with the
            same DOF names, such as it with sites added), one frame per clip frame.
        wrap_angles: Write rotation angles in [-180, 180) instead of the
            continuous (unwrapped) angles the import works with.

    Raises:
        BvhError: no clip in ``imported``, a frame count that differs, or a DOF missing.
    """
    clip = _matching_clip(imported, motion)
    values = clip.motion.copy()
    _write_dof_columns(values, imported, motion)
    if not _top_pinned_as_clip(imported, motion):
        values[:, clip.channel_index(0)] = _root_channels(imported, motion)
    if wrap_angles:
        _wrap_rotations(values, clip)
    return BvhClip(clip.joints, clip.frame_time, values)


def _matching_clip(imported: BvhImport, motion: Motion) -> BvhClip:
    """The imported clip, refused when absent or of another frame count than ``motion``."""
    clip = imported.clip
    if clip is None:
        raise BvhError("clip_with_motion needs the BvhImport of import_bvh (it holds the clip)")
    if motion.n_frames != clip.n_frames:
        raise BvhError(f"the motion has {motion.n_frames} frames, the clip {clip.n_frames}")
    return clip


def _write_dof_columns(values: np.ndarray, imported: BvhImport, motion: Motion) -> None:
    """Each DOF's rotation channel of ``values`` (F, channels) set to its angle in ``motion`` [deg], in place."""
    sk = motion.skeleton
    for dof, column in imported.dof_columns:
        if dof not in sk.dof_names:
            raise BvhError(f"the motion's skeleton {sk.name!r} has no DOF {dof!r} of the clip")
        values[:, column] = np.degrees(motion.q[:, sk.dof_index(dof)])


def _wrap_rotations(values: np.ndarray, clip: BvhClip) -> None:
    """Every rotation channel of ``values`` (F, channels) wrapped into [-180, 180) [deg], in place."""
    rotations = [k for k, label in enumerate(c for j in clip.joints for c in j.channels)
                 if label.endswith("rotation")]
    values[:, rotations] = np.remainder(values[:, rotations] + 180.0, 360.0) - 180.0


def _top_pinned_as_clip(imported: BvhImport, motion: Motion) -> bool:
    """True when every frame pins the top joint exactly where the import did."""
    top = imported.motion.roots[0]
    return (all(r == top for r in motion.roots)
            and np.array_equal(motion.world_from_root, imported.motion.world_from_root))


def _root_channels(imported: BvhImport, motion: Motion) -> np.ndarray:
    """(F, k) the root joint's channels carrying the top joint's world pose of ``motion``, file axes and units."""
    clip, sk = imported.clip, motion.skeleton
    top = sk.joint_frame[0]
    M = Z_UP_TO_Y_UP.T if imported.up == "y" else np.eye(3)  # file -> gsik world
    F = motion.n_frames
    R = np.empty((F, 3, 3))
    p = np.empty((F, 3))
    for f in range(F):
        Rf, pf = world_frames(sk, motion.q[f], motion.world_from_root[f], motion.roots[f])
        R[f], p[f] = M.T @ Rf[top] @ M, M.T @ pf[top] / imported.scale
    channels = clip.joints[0].channels
    rotations = "".join(c[0] for c in channels if c.endswith("rotation"))
    angles = {}
    if rotations:
        if len(rotations) != 3:
            raise BvhError(f"the root has rotation channels {rotations}: cannot carry a turned top joint")
        angles = dict(zip(rotations, np.degrees(np.unwrap(euler_from_matrix(R, rotations.lower()), axis=0)).T))
    out = clip.motion[:, clip.channel_index(0)].copy()
    for k, c in enumerate(channels):
        out[:, k] = p[:, AXIS_INDEX[c[0]]] if c.endswith("position") else angles[c[0]]
    return out
