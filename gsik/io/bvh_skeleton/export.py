"""gsik -> BVH: poses and motions as BVH clips (conventions in :mod:`gsik.io.bvh_skeleton`)."""

from __future__ import annotations

import os
import re
from typing import NamedTuple

import numpy as np

from gsik.anim.motion import Motion
from gsik.errors import BvhError, choices
from gsik.io.bvh import BvhClip, BvhJoint, format_bvh
from gsik.io.bvh_skeleton.conventions import EULER_ORDER, UNITS_PER_METRE, UP_AXES, Z_UP_TO_Y_UP, euler_from_matrix
from gsik.io.files import atomic_write_text
from gsik.io.names import unique_name
from gsik.kinematics import world_frames
from gsik.rotations import matrix_from_axis_angle
from gsik.skeleton import Skeleton

_BAD_NAME_CHARS = re.compile(r"[\s{}]")
#: How close to a coordinate axis (and to no fixed orientation) a joint must be for exact channels.
_EXACT_TOLERANCE = 1e-12




def _check_units(units: str) -> float:
    if units not in UNITS_PER_METRE:
        raise BvhError(f"unknown units {units!r}; expected one of {choices(UNITS_PER_METRE)}")
    return UNITS_PER_METRE[units]


def _check_up(up: str) -> np.ndarray:
    if up not in UP_AXES:
        raise BvhError(f"unknown up axis {up!r}; expected one of {choices(UP_AXES)}")
    return Z_UP_TO_Y_UP if up == "y" else np.eye(3)


def _bvh_name(name: str) -> str:
    return _BAD_NAME_CHARS.sub("_", name)


def _first_frame(sk: Skeleton, j: int) -> int:
    """The frame holding joint ``j``'s offset and fixed orientation."""
    dofs = sk.joint_dofs[j]
    return int(sk.dof_frame[dofs[0]]) if dofs else int(sk.joint_frame[j])


class _Channels(NamedTuple):
    """How one exported joint fills its channels."""

    channels: tuple[str, ...]
    dofs: tuple[int, ...]  # exact: the DOF of each channel
    signs: tuple[float, ...]  # exact: +1 / -1 per channel
    euler: bool  # decompose the local rotation instead


def _joint_channels(sk: Skeleton, j: int, C: np.ndarray, order: str) -> _Channels:
    dofs = sk.joint_dofs[j]
    if not dofs:
        return _Channels((), (), (), False)
    R0 = sk.frame_rotation[_first_frame(sk, j)]
    channels, signs = [], []
    exact = bool(np.abs(R0 - np.eye(3)).max() <= _EXACT_TOLERANCE)
    for d in dofs:
        a = C @ sk.frame_axis[sk.dof_frame[d]]
        i = int(np.argmax(np.abs(a)))
        if abs(abs(a[i]) - 1.0) > _EXACT_TOLERANCE:
            exact = False
            break
        channels.append("XYZ"[i] + "rotation")
        signs.append(float(np.sign(a[i])))
    if exact and len(set(channels)) == len(channels):
        return _Channels(tuple(channels), tuple(dofs), tuple(signs), False)
    return _Channels(tuple(c.upper() + "rotation" for c in order), (), (), True)


def _padded(plan: _Channels, order: str) -> _Channels:
    """``plan`` with three rotation channels: the missing axes added as locked channels (DOF -1, always 0).

    The missing axes go where ``order`` (like ``"XZY"``) puts them when the joint's own axes keep that
    relative order, else after the joint's own. An identity factor anywhere in the product leaves the
    rotation unchanged, so every frame's pose is the same; Blender's importer needs 0 or 3 rotations.
    """
    if plan.euler or not 0 < len(plan.channels) < 3:
        return plan
    own = [c[0] for c in plan.channels]
    axes = _padded_axes(own, order)
    where = {a: k for k, a in enumerate(own)}
    dofs = tuple(plan.dofs[where[a]] if a in where else -1 for a in axes)
    signs = tuple(plan.signs[where[a]] if a in where else 1.0 for a in axes)
    return _Channels(tuple(a + "rotation" for a in axes), dofs, signs, False)


def _padded_axes(own: list[str], order: str) -> list[str]:
    """All three axes: ``order``'s when the joint's ``own`` axes keep its relative order, else own ones first."""
    in_order = "".join(a for a in order if a in own) == "".join(own)
    return list(order) if in_order else own + [a for a in order if a not in own]


def _usual_order(plans: list[_Channels], order: str) -> str:
    """The skeleton's usual rotation order: the most common one of its exact three-channel joints, else ``order``."""
    orders = ["".join(c[0] for c in p.channels) for p in plans if not p.euler and len(p.channels) == 3]
    return max(orders, key=orders.count) if orders else order.upper()


def motion_to_bvh(motion: Motion, units: str = "cm", up: str = "z", *, pad_rotations: bool = True,
                  end_sites: bool = False) -> BvhClip:
    """A :class:`~gsik.anim.motion.Motion` as a BVH clip (see the module's conventions).

    Args:
        motion: The motion; each frame may pin a different IK root.
        units: ``"cm"`` (default) or ``"m"``: the unit of offsets and positions.
        up: ``"z"`` (default, gsik's world) or ``"y"``.
        pad_rotations: Write joints with one or two rotations with three
            rotation channels, the missing ones locked at 0 (default: what
            Blender's importer needs); ``False`` writes only their own.
        end_sites: Write a site that is its joint's only child as an
            ``End Site`` (no extra bone in Blender; the site's name is lost,
            a re-import calls it ``<joint>_end``); by default every site is a
            zero-channel ``JOINT`` named after it.

    Returns:
        The clip, hierarchy rooted at the skeleton's top joint.

    Raises:
        BvhError: bad ``units`` or ``up``, an empty motion, or two names that
            are the same once made valid BVH names.
    """
    if not isinstance(motion, Motion):
        raise BvhError(f"motion_to_bvh needs a gsik.anim.motion.Motion, got {type(motion).__name__}")
    scale = _check_units(units)
    C = _check_up(up)
    order = EULER_ORDER[up]
    if motion.n_frames == 0:
        raise BvhError("cannot export a motion with no frames")
    sk = motion.skeleton
    F = motion.n_frames
    plans = _channel_plans(sk, C, order, pad_rotations)
    top_R, top_p = _top_world(motion)
    site_joint = _site_joints(sk)

    joints: list[BvhJoint] = []
    columns: list[np.ndarray] = []  # (F,) per channel, in file order
    names: dict[str, str] = {}

    def add(name: str, parent: int, offset, channels=(), is_end_site=False) -> int:
        if not is_end_site:
            bvh = _bvh_name(name)
            if bvh in names:
                raise BvhError(f"joints or sites {names[bvh]!r} and {name!r} both become {bvh!r} in BVH")
            names[bvh] = name
            name = bvh
        joints.append(BvhJoint(name=name or "end", parent=parent, offset=offset, channels=channels,
                               is_end_site=is_end_site))
        return len(joints) - 1

    def emit(j: int, parent: int) -> None:
        if parent < 0:
            world = C @ top_R @ C.T
            angles = np.unwrap(euler_from_matrix(world, order), axis=0)
            channels = ("Xposition", "Yposition", "Zposition") + tuple(a.upper() + "rotation" for a in order)
            me = add(sk.joint_names[j], -1, (0.0, 0.0, 0.0), channels)
            columns.extend(scale * (top_p @ C.T).T)
            columns.extend(np.degrees(angles).T)
        else:
            offset = scale * (C @ sk.frame_offset[_first_frame(sk, j)])
            plan = plans[j]
            me = add(sk.joint_names[j], parent, offset, plan.channels)
            if plan.euler:
                R = np.broadcast_to(sk.frame_rotation[_first_frame(sk, j)], (F, 3, 3))
                for d in sk.joint_dofs[j]:
                    R = R @ matrix_from_axis_angle(sk.frame_axis[sk.dof_frame[d]], motion.q[:, d])
                angles = np.unwrap(euler_from_matrix(C @ R @ C.T, order), axis=0)
                columns.extend(np.degrees(angles).T)
            else:
                columns.extend(np.degrees(sign * motion.q[:, d]) if d >= 0 else np.zeros(F)
                               for d, sign in zip(plan.dofs, plan.signs))
        children = [k for k in range(sk.n_joints) if sk.joint_parent[k] == j]
        sites = [s for s in range(len(sk.site_names)) if site_joint[s] == j]
        for k in children:
            emit(k, me)
        leaf_site = end_sites and not children and len(sites) == 1
        for s in sites:
            offset = scale * (C @ sk.frame_offset[sk.site_frame[s]])
            if leaf_site:
                add("", me, offset, is_end_site=True)
                continue
            site = add(sk.site_names[s], me, offset)
            add("", site, (0.0, 0.0, 0.0), is_end_site=True)
        if not children and not sites:
            add("", me, (0.0, 0.0, 0.0), is_end_site=True)

    emit(0, -1)
    _name_end_sites(joints, set(names))
    motion_values = np.stack(columns, axis=1) if columns else np.zeros((F, 0))
    return BvhClip(joints=tuple(joints), frame_time=motion.frame_time, motion=motion_values)


def _channel_plans(sk: Skeleton, C: np.ndarray, order: str, pad_rotations: bool) -> list[_Channels]:
    """Each joint's rotation channels, padded to three where ``pad_rotations`` asks."""
    plans = [_joint_channels(sk, j, C, order) for j in range(sk.n_joints)]
    if pad_rotations:
        usual = _usual_order(plans, order)
        plans = [_padded(plan, usual) for plan in plans]
    return plans


def _top_world(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """The top joint's world rotation (F, 3, 3) and position (F, 3) [m], from each frame's own root."""
    sk = motion.skeleton
    F = motion.n_frames
    top_frame = int(sk.joint_frame[0])
    top_R = np.empty((F, 3, 3))
    top_p = np.empty((F, 3))
    for f in range(F):
        R, p = world_frames(sk, motion.q[f], motion.world_from_root[f], motion.roots[f])
        top_R[f] = R[top_frame]
        top_p[f] = p[top_frame]
    return top_R, top_p


def _site_joints(sk: Skeleton) -> dict[int, int]:
    """Site index -> the index of the joint it hangs from."""
    frame_to_joint = {int(fr): j for j, fr in enumerate(sk.joint_frame)}
    return {s: frame_to_joint[int(sk.frame_parent[fr])] for s, fr in enumerate(sk.site_frame)}


def _name_end_sites(joints: list[BvhJoint], taken: set[str]) -> None:
    """End Sites get the parser's names, ``"<parent>_end"``, unique among all names (``joints`` in place)."""
    for i, joint in enumerate(joints):
        if joint.is_end_site:
            name = unique_name(joints[joint.parent].name + "_end", taken)
            taken.add(name)
            joints[i] = BvhJoint(name=name, parent=joint.parent, offset=joint.offset, is_end_site=True)


def pose_to_bvh(
    skeleton: Skeleton,
    q,
    world_from_root=None,
    root: str | None = None,
    units: str = "cm",
    up: str = "z",
    frame_time: float = 1.0 / 30.0,
    **options,
) -> BvhClip:
    """One pose as a one-frame BVH clip (see :func:`motion_to_bvh`).

    Args:
        skeleton: The skeleton.
        q: Joint angles (n_dofs,) [rad].
        world_from_root: World transform (4, 4) of ``root``; by default the
            skeleton stands where its definition places it.
        root: The frame ``world_from_root`` pins (default ``skeleton.root``).
        units, up, options: As for :func:`motion_to_bvh`.
        frame_time: The clip's frame time [s].
    """
    q = skeleton.validate_q(q)
    root = skeleton.root if root is None else root
    if world_from_root is None:
        world_from_root = skeleton.frame_transforms(q)[skeleton.frame_of(root)]
    motion = Motion(skeleton, q[None], (root,), np.asarray(world_from_root, dtype=float)[None], frame_time)
    return motion_to_bvh(motion, units=units, up=up, **options)


def write_motion_bvh(
    path: str | os.PathLike, motion: Motion, units: str = "cm", up: str = "z", precision: int | None = None,
    **options,
) -> None:
    """Export ``motion`` (see :func:`motion_to_bvh`) and write it to ``path`` atomically.

    Args:
        precision: Decimals of the numbers; by default 6 for centimetres and
            8 for metres (10 nm either way; angles to 1e-6 degrees or finer).
        options: :func:`motion_to_bvh`'s keyword options.

    Raises:
        BvhError: as :func:`motion_to_bvh`.
        GsikFileError: the file cannot be written.
    """
    clip = motion_to_bvh(motion, units=units, up=up, **options)
    if precision is None:
        precision = 8 if units == "m" else 6
    atomic_write_text(path, format_bvh(clip, precision))
