"""The clip's own forward kinematics: local rotations and translations per frame, then world poses."""

from __future__ import annotations

import numpy as np

from gsik.io.bvh.clip import AXIS_INDEX, BvhClip
from gsik.rotations import matrix_from_cos_sin




def _cos_sin_deg(degrees: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """cos and sin of angles in degrees, exact at quarter turns (so 90 deg gives 0, 1)."""
    turns = np.remainder(np.asarray(degrees, dtype=float), 360.0)
    rad = np.deg2rad(turns)
    c, s = np.cos(rad), np.sin(rad)
    quarter = turns / 90.0
    exact = quarter == np.round(quarter)
    if np.any(exact):
        k = np.round(quarter[exact]).astype(int) % 4
        c[exact] = np.array([1.0, 0.0, -1.0, 0.0])[k]
        s[exact] = np.array([0.0, 1.0, 0.0, -1.0])[k]
    return c, s


def _axis_rotation(axis: int, degrees: np.ndarray) -> np.ndarray:
    """(n, 3, 3) right-handed rotations by ``degrees`` (n,) about axis 0 (X), 1 (Y) or 2 (Z)."""
    return matrix_from_cos_sin(axis, *_cos_sin_deg(np.atleast_1d(degrees)))


def bvh_local_rotations(clip: BvhClip) -> np.ndarray:
    """Each joint's rotation relative to its parent, for every frame.

    Rotation channels compose in file order: ``Zrotation Xrotation
    Yrotation`` gives ``Rz @ Rx @ Ry``. Joints without rotation channels
    (End Sites included) get the identity.

    Returns:
        (n_frames, n_joints, 3, 3) rotation matrices.
    """
    n_frames = clip.n_frames
    out = np.broadcast_to(np.eye(3), (n_frames, clip.n_joints, 3, 3)).copy()
    for j, joint in enumerate(clip.joints):
        start = clip.channel_index(j).start
        R = None
        for k, channel in enumerate(joint.channels):
            if channel.endswith("rotation"):
                Rk = _axis_rotation(AXIS_INDEX[channel[0]], clip.motion[:, start + k])
                R = Rk if R is None else R @ Rk
        if R is not None:
            out[:, j] = R
    return out


def bvh_local_translations(clip: BvhClip) -> np.ndarray:
    """Each joint's translation from its parent, for every frame.

    The OFFSET, with each component that has a position channel replaced by
    that channel's value (for the usual root: the X/Y/Zposition values).

    Returns:
        (n_frames, n_joints, 3) translations in file units.
    """
    offsets = np.array([j.offset for j in clip.joints]).reshape(clip.n_joints, 3)
    out = np.broadcast_to(offsets, (clip.n_frames, clip.n_joints, 3)).copy()
    for j, joint in enumerate(clip.joints):
        start = clip.channel_index(j).start
        for k, channel in enumerate(joint.channels):
            if channel.endswith("position"):
                out[:, j, AXIS_INDEX[channel[0]]] = clip.motion[:, start + k]
    return out


def bvh_forward_kinematics(clip: BvhClip) -> tuple[np.ndarray, np.ndarray]:
    """World rotations and positions of every joint (End Sites included).

    ``world_R[j] = world_R[parent] @ local_R[j]`` and
    ``world_p[j] = world_p[parent] + world_R[parent] @ t[j]``, with the
    local parts from :func:`bvh_local_rotations` and
    :func:`bvh_local_translations`; the root's world transform is its local one.

    Returns:
        world_rotations: (n_frames, n_joints, 3, 3).
        world_positions: (n_frames, n_joints, 3) in file units.
    """
    local_R = bvh_local_rotations(clip)
    local_t = bvh_local_translations(clip)
    world_R = np.empty_like(local_R)
    world_p = np.empty_like(local_t)
    for j, joint in enumerate(clip.joints):
        p = joint.parent
        if p < 0:
            world_R[:, j] = local_R[:, j]
            world_p[:, j] = local_t[:, j]
        else:
            world_R[:, j] = world_R[:, p] @ local_R[:, j]
            world_p[:, j] = world_p[:, p] + np.einsum("fij,fj->fi", world_R[:, p], local_t[:, j])
    return world_R, world_p
