"""Shared material of the BVH skeleton tests: fixtures' names, smooth motions, round trips and small clips."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

import gsik
from gsik.anim.motion import Motion
from gsik.io.bvh import BvhClip, BvhJoint, bvh_forward_kinematics, format_bvh, parse_bvh
from gsik.io.bvh_skeleton import (
    Z_UP_TO_Y_UP,
    import_bvh,
    motion_to_bvh,
)
from gsik.rotations import matrix_from_rotvec

DATA = Path(__file__).resolve().parents[1] / "data"
FIXTURES = sorted(p.name for p in DATA.glob("*.bvh"))
ORDERS = ["".join(p) for p in itertools.permutations("xyz")]
PRECISION = {"cm": 6, "m": 8}


# ---------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------


def smooth_motion(sk: gsik.Skeleton, n_frames: int, seed: int, roots=None) -> Motion:
    """Sinusoidal angles within the limits, the hips travelling along x; ``roots`` (a per-frame list) re-pins them."""
    rng = np.random.default_rng(seed)
    t = np.arange(n_frames) / 30.0
    half = 0.5 * (sk.upper - sk.lower)
    phase = rng.uniform(0.0, 2.0 * np.pi, sk.n_dofs)
    freq = rng.uniform(0.1, 0.4, sk.n_dofs)
    q = np.clip(sk.rest + 0.4 * half * np.sin(2.0 * np.pi * freq * t[:, None] + phase), sk.lower, sk.upper)
    top = sk.joint_names[0]
    W = np.tile(np.eye(4), (n_frames, 1, 1))
    W[:, :3, :3] = [matrix_from_rotvec([0.0, 0.0, 0.8 * s]) for s in np.sin(t)]
    W[:, :3, 3] = np.c_[0.6 * t, 0.1 * np.sin(t), 0.95 + 0.02 * np.cos(3 * t)]
    if roots is None:
        return Motion(sk, q, (top,) * n_frames, W, 1.0 / 30.0)
    # Re-pin each frame at its own root, where the top-pinned pose puts it.
    W_root = np.empty_like(W)
    for f in range(n_frames):
        R, p = gsik.kinematics.world_frames(sk, q[f], W[f], top)
        i = sk.frame_of(roots[f])
        W_root[f] = np.eye(4)
        W_root[f, :3, :3] = R[i]
        W_root[f, :3, 3] = p[i]
    return Motion(sk, q, tuple(roots), W_root, 1.0 / 30.0)


def round_trip(motion: Motion, file_units: str, file_up: str, pad_rotations: bool = True, **import_options):
    clip = motion_to_bvh(motion, units=file_units, up=file_up, pad_rotations=pad_rotations)
    text = format_bvh(clip, PRECISION[file_units])
    return import_bvh(parse_bvh(text), **import_options)


def max_position_difference(original: Motion, imported: Motion, names) -> float:
    a = original.positions()
    b = imported.positions()
    fa = [original.skeleton.frame_of(n) for n in names]
    fb = [imported.skeleton.frame_of(n) for n in names]
    return float(np.abs(a[:, fa] - b[:, fb]).max())


def clip_world_positions(clip: BvhClip, scale: float, up: str) -> np.ndarray:
    """The clip's own FK positions in gsik's world [m]."""
    M = Z_UP_TO_Y_UP.T if up == "y" else np.eye(3)
    return scale * bvh_forward_kinematics(clip)[1] @ M.T


def one_joint_clip(order: str, angles_deg: np.ndarray) -> BvhClip:
    """ROOT + one 3-channel JOINT with rotation channels in ``order`` + End Site."""
    channels = tuple(a.upper() + "rotation" for a in order)
    joints = (
        BvhJoint("Hips", -1, (0.0, 0.0, 0.0), ("Xposition", "Yposition", "Zposition") + channels),
        BvhJoint("Arm", 0, (0.3, 0.1, 0.0), channels),
        BvhJoint("Forearm", 1, (0.0, 0.0, 0.4), channels),
        BvhJoint("Forearm_end", 2, (0.25, 0.05, -0.1), is_end_site=True),
    )
    n = angles_deg.shape[0]
    roots = np.c_[np.linspace(0, 1, n), np.zeros(n), np.full(n, 0.9)]
    return BvhClip(joints, 0.04, np.c_[roots, angles_deg])
