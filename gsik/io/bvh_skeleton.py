"""BVH <-> gsik: export poses and motions as BVH clips, import a clip as a skeleton and its motion.

:mod:`gsik.io.bvh` reads and writes the file format; this module converts
between a :class:`~gsik.io.bvh.BvhClip` and a gsik :class:`~gsik.skeleton.Skeleton`
with its :class:`~gsik.anim.motion.Motion`.

Conventions of the export (:func:`motion_to_bvh`, :func:`pose_to_bvh`,
:func:`write_motion_bvh`):

* **Hierarchy.** The skeleton's own joint tree, rooted at its top joint (the
  biped's ``hips``), whatever IK root each frame used: one consistent
  hierarchy for a walk whose root alternates between the feet.
* **Root.** The ROOT has ``OFFSET 0 0 0`` and six channels: ``Xposition
  Yposition Zposition`` then three rotations, carrying the top joint's world
  position and orientation in each frame, computed by forward kinematics from
  that frame's ``(q, root, world_from_root)``. (A zero root OFFSET means
  readers that add the OFFSET to the position channels and readers that
  replace it agree.) The rotation order is :data:`EULER_ORDER` of the up axis:
  ``Zrotation Xrotation Yrotation`` for z up, ``Yrotation Xrotation
  Zrotation`` for y up (the vertical turn outermost, so a character turning
  round never meets gimbal lock).
* **Joints.** Every other gsik joint is a ``JOINT`` with its definition offset.
  A joint whose rotation axes are coordinate axes (after the up-axis change)
  and that has no fixed ``orientation`` gets exactly its one-DOF rotations as
  channels, in its own order, angles in degrees (the biped's knee is
  ``CHANNELS 1 Xrotation``, its hip ``Xrotation Yrotation Zrotation``). Any
  other joint (a fixed ``orientation``, oblique axes) gets three channels in
  :data:`EULER_ORDER`, decomposed from its local rotation matrix, unwrapped
  over the frames so the angles are continuous. A joint without rotations
  gets ``CHANNELS 0``.
* **Sites.** Every site becomes a zero-channel ``JOINT`` named after the site,
  at the site's offset, holding an ``End Site`` with a zero offset. This keeps
  the sites' names (``left_hand``, ``head`` ...) in the file, so a re-imported
  clip has the same effectors; readers that draw bones show the forearm ending
  at the hand. A site's fixed orientation is not written (BVH has no place for
  it). A joint with neither child joints nor sites gets a zero ``End Site``.
* **Units.** ``units="cm"`` (the default: most animation tools expect
  centimetres) or ``"m"``.
* **Up axis.** ``up="z"`` (the default, gsik's own world) or ``"y"``: the
  world is turned by -90 degrees about x (:data:`Z_UP_TO_Y_UP`), applied to
  offsets, positions and rotations alike, so the rest pose stands along +y and
  the biped, which faces +y in gsik, faces -z. Coordinate-axis rotations stay
  exact: gsik x, y, z become ``Xrotation``, ``Zrotation`` (angle negated) and
  ``Yrotation``.
* Names with whitespace or braces (not allowed in BVH) have them replaced by ``_``.

Conventions of the import (:func:`import_bvh`, :func:`skeleton_from_bvh`):

* **Names** are kept as written (``mixamorig:Hips``); ``strip_namespace=True``
  drops everything up to the last ``:``. DOFs are named ``"<joint>.<axis>"``
  after the file's channel (``"mixamorig:Spine.z"`` for ``Zrotation``).
* **Joints.** The ROOT becomes the skeleton's top joint, a fixed frame: all
  its channels go into the Motion's ``world_from_root`` (per frame, with the
  top joint as the root); its definition offset and orientation are those of
  the first frame. Every other joint with rotation channels gets one one-DOF
  rotation per channel, in the file's channel order, so any order (ZXY, ZYX,
  XYZ ...) reproduces the file's forward kinematics exactly. A joint without
  channels is a fixed joint.
* **Position channels** on a non-root joint replace its offset. gsik has no
  sliding joints, so the first frame's value is used; where the value changes
  over the clip, the import reports it in ``warnings`` (and only frames with
  the first frame's value are reproduced exactly).
* **Sites.** Each ``End Site`` becomes a site named ``"<parent>_end"`` (the
  parser's name). A zero-channel ``JOINT`` without child joints whose End
  Sites all have a zero offset (what the export writes for a site) becomes a
  site named after the ``JOINT``.
* **Effectors.** By default every site, plus a site ``"<root>_site"`` at the
  top joint's origin when no site is there already (the pelvis). An explicit
  list names sites or joints; a joint gets a site ``"<joint>_site"`` at its
  origin. The skeleton's IK root is the top joint unless ``root`` says
  otherwise.
* **Units.** ``scale`` is metres per file unit. By default it is detected from
  the size of the rest pose (the hierarchy's offsets, root offset excluded):
  up to 10 units across is metres, up to 1000 centimetres, more millimetres.
* **Up axis.** ``up="auto"`` (the default) takes y when the rest pose is taller
  along y than along z, else z; a y-up file is turned to gsik's z-up world
  (the inverse of the export's turn), so an export with either ``up``
  re-imports exactly.
* **Limits.** ``limits="wide"``: [-pi, pi] for each angle, widened where the
  clip goes further; ``"from_motion"``: the clip's range of each angle plus
  ``margin`` on both sides. Either way every frame of the clip lies within the
  limits. The rest angle is 0 (the file's rest pose), clamped into the limits.

Conversion errors raise :class:`~gsik.errors.BvhError`.
"""

from __future__ import annotations

import math
import os
import re
import warnings
from collections.abc import Sequence
from typing import Literal, NamedTuple

import numpy as np

from gsik.io.bvh import BvhClip, BvhJoint, bvh_local_rotations, bvh_local_translations, format_bvh
from gsik.errors import BvhError, choices
from gsik.io.files import atomic_write_text
from gsik.kinematics import world_frames
from gsik.anim.motion import Motion
from gsik.rotations import matrix_from_axis_angle, matrix_from_cos_sin
from gsik.skeleton import JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton

#: File units per metre for each ``units`` choice.
UNITS_PER_METRE = {"cm": 100.0, "m": 1.0}
#: The ``up`` choices of the export.
UP_AXES = ("z", "y")
#: The world turn from gsik's z-up world to a y-up file: -90 degrees about x (z -> y, y -> -z).
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
Z_UP_TO_Y_UP.flags.writeable = False
#: Euler order of the root's and of decomposed joints' rotation channels, per up axis
#: (``"zxy"``: ``Zrotation Xrotation Yrotation``, ``R = Rz @ Rx @ Ry``).
EULER_ORDER = {"z": "zxy", "y": "yxz"}
#: The ``limits`` choices of the import.
LIMIT_MODES = ("wide", "from_motion")

_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}
_BAD_NAME_CHARS = re.compile(r"[\s{}]")
_EXACT_TOLERANCE = 1e-12


class BvhImportWarning(UserWarning):
    """An import that could not reproduce the whole file exactly (see :attr:`BvhImport.warnings`)."""


# ---------------------------------------------------------------------------
# Euler angles
# ---------------------------------------------------------------------------


def _order_axes(order: str) -> tuple[int, int, int]:
    o = order.lower() if isinstance(order, str) else ""
    if len(o) != 3 or set(o) != {"x", "y", "z"}:
        raise BvhError(f"Euler order must be three distinct axes from 'xyz' (like 'zxy'), got {order!r}")
    return _AXIS_INDEX[o[0]], _AXIS_INDEX[o[1]], _AXIS_INDEX[o[2]]


def matrix_from_euler(angles: np.ndarray, order: str) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of Euler angles (..., 3) [rad].

    ``order="zxy"`` gives ``R = Rz(a[0]) @ Rx(a[1]) @ Ry(a[2])``: the BVH
    meaning of ``Zrotation Xrotation Yrotation`` (the first axis outermost).
    """
    axes = _order_axes(order)
    angles = np.asarray(angles, dtype=float)
    if angles.shape[-1:] != (3,):
        raise BvhError(f"Euler angles must have shape (..., 3), got {angles.shape}")
    R = np.broadcast_to(np.eye(3), angles.shape[:-1] + (3, 3)).copy()
    for n, axis in enumerate(axes):
        R = R @ matrix_from_cos_sin(axis, np.cos(angles[..., n]), np.sin(angles[..., n]))
    return R


def euler_from_matrix(R: np.ndarray, order: str) -> np.ndarray:
    """Euler angles (..., 3) [rad] of rotation matrices (..., 3, 3), the inverse of :func:`matrix_from_euler`.

    The middle angle is in [-pi/2, pi/2], the others in [-pi, pi]. At gimbal
    lock (middle angle +-pi/2) the last angle is 0.
    """
    i, j, k = _order_axes(order)
    R = np.asarray(R, dtype=float)
    if R.shape[-2:] != (3, 3):
        raise BvhError(f"rotation matrices must have shape (..., 3, 3), got {R.shape}")
    s = 1.0 if (j - i) % 3 == 1 else -1.0  # +1 for the cyclic orders xyz, yzx, zxy
    cos_b = np.hypot(R[..., i, i], R[..., i, j])
    b = np.arctan2(s * R[..., i, k], cos_b)
    c = np.arctan2(-s * R[..., i, j], R[..., i, i])
    a = np.arctan2(-s * R[..., j, k], R[..., k, k])
    lock = cos_b < 1e-9
    if np.any(lock):
        c = np.where(lock, 0.0, c)
        a = np.where(lock, np.arctan2(s * R[..., k, j], R[..., j, j]), a)
    return np.stack([a, b, c], axis=-1)


# ---------------------------------------------------------------------------
# Export
# ---------------------------------------------------------------------------


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


def motion_to_bvh(motion: Motion, units: str = "cm", up: str = "z") -> BvhClip:
    """A :class:`~gsik.anim.motion.Motion` as a BVH clip (see the module's conventions).

    Args:
        motion: The motion; each frame may pin a different IK root.
        units: ``"cm"`` (default) or ``"m"``: the unit of offsets and positions.
        up: ``"z"`` (default, gsik's world) or ``"y"``.

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

    # The top joint's world transform in each frame, from each frame's own root.
    top_frame = int(sk.joint_frame[0])
    top_R = np.empty((F, 3, 3))
    top_p = np.empty((F, 3))
    for f in range(F):
        R, p = world_frames(sk, motion.q[f], motion.world_from_root[f], motion.roots[f])
        top_R[f] = R[top_frame]
        top_p[f] = p[top_frame]

    site_joint = {}  # site index -> parent joint index
    frame_to_joint = {int(fr): j for j, fr in enumerate(sk.joint_frame)}
    for s, fr in enumerate(sk.site_frame):
        site_joint[s] = frame_to_joint[int(sk.frame_parent[fr])]

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
            plan = _joint_channels(sk, j, C, order)
            me = add(sk.joint_names[j], parent, offset, plan.channels)
            if plan.euler:
                R = np.broadcast_to(sk.frame_rotation[_first_frame(sk, j)], (F, 3, 3))
                for d in sk.joint_dofs[j]:
                    R = R @ matrix_from_axis_angle(sk.frame_axis[sk.dof_frame[d]], motion.q[:, d])
                angles = np.unwrap(euler_from_matrix(C @ R @ C.T, order), axis=0)
                columns.extend(np.degrees(angles).T)
            else:
                columns.extend(np.degrees(sign * motion.q[:, d]) for d, sign in zip(plan.dofs, plan.signs))
        children = [k for k in range(sk.n_joints) if sk.joint_parent[k] == j]
        sites = [s for s in range(len(sk.site_names)) if site_joint[s] == j]
        for k in children:
            emit(k, me)
        for s in sites:
            fr = sk.site_frame[s]
            site = add(sk.site_names[s], me, scale * (C @ sk.frame_offset[fr]))
            add("", site, (0.0, 0.0, 0.0), is_end_site=True)
        if not children and not sites:
            add("", me, (0.0, 0.0, 0.0), is_end_site=True)

    emit(0, -1)
    # End Sites get the parser's names, "<parent>_end", unique among all names.
    taken = set(names)
    for i, joint in enumerate(joints):
        if joint.is_end_site:
            name = _unique(joints[joint.parent].name + "_end", taken)
            taken.add(name)
            joints[i] = BvhJoint(name=name, parent=joint.parent, offset=joint.offset, is_end_site=True)
    motion_values = np.stack(columns, axis=1) if columns else np.zeros((F, 0))
    return BvhClip(joints=tuple(joints), frame_time=motion.frame_time, motion=motion_values)


def pose_to_bvh(
    skeleton: Skeleton,
    q,
    world_from_root=None,
    root: str | None = None,
    units: str = "cm",
    up: str = "z",
    frame_time: float = 1.0 / 30.0,
) -> BvhClip:
    """One pose as a one-frame BVH clip (see :func:`motion_to_bvh`).

    Args:
        skeleton: The skeleton.
        q: Joint angles (n_dofs,) [rad].
        world_from_root: World transform (4, 4) of ``root``; by default the
            skeleton stands where its definition places it.
        root: The frame ``world_from_root`` pins (default ``skeleton.root``).
        units, up: As for :func:`motion_to_bvh`.
        frame_time: The clip's frame time [s].
    """
    q = skeleton.validate_q(q)
    root = skeleton.root if root is None else root
    if world_from_root is None:
        world_from_root = skeleton.frame_transforms(q)[skeleton.frame_of(root)]
    motion = Motion(skeleton, q[None], (root,), np.asarray(world_from_root, dtype=float)[None], frame_time)
    return motion_to_bvh(motion, units=units, up=up)


def write_motion_bvh(
    path: str | os.PathLike, motion: Motion, units: str = "cm", up: str = "z", precision: int | None = None
) -> None:
    """Export ``motion`` (see :func:`motion_to_bvh`) and write it to ``path`` atomically.

    Args:
        precision: Decimals of the numbers; by default 6 for centimetres and
            8 for metres (10 nm either way; angles to 1e-6 degrees or finer).

    Raises:
        BvhError: as :func:`motion_to_bvh`.
        GsikFileError: the file cannot be written.
    """
    clip = motion_to_bvh(motion, units=units, up=up)
    if precision is None:
        precision = 8 if units == "m" else 6
    atomic_write_text(path, format_bvh(clip, precision))


# ---------------------------------------------------------------------------
# Import
# ---------------------------------------------------------------------------


class BvhImport(NamedTuple):
    """What :func:`import_bvh` made of a clip.

    Attributes:
        skeleton: The skeleton (root: the top joint unless chosen otherwise).
        motion: The clip's motion on it, the top joint pinned per frame.
        effectors: The effector sites, in the order asked for.
        scale: Metres per file unit used.
        up: The file's up axis used (``"y"`` or ``"z"``).
        warnings: What could not be reproduced exactly, one sentence each.
    """

    skeleton: Skeleton
    motion: Motion
    effectors: tuple[str, ...]
    scale: float
    up: str
    warnings: tuple[str, ...]


def _rest_extent(clip: BvhClip) -> np.ndarray:
    """(3,) size of the rest pose along x, y, z in file units (root offset excluded)."""
    pos = np.zeros((clip.n_joints, 3))
    for j, joint in enumerate(clip.joints):
        if joint.parent >= 0:
            pos[j] = pos[joint.parent] + joint.offset
    return pos.max(axis=0) - pos.min(axis=0)


def detect_scale(clip: BvhClip) -> float:
    """Metres per file unit guessed from the rest pose's size: <= 10 units m, <= 1000 cm, else mm."""
    size = float(_rest_extent(clip).max())
    if size <= 10.0:
        return 1.0
    if size <= 1000.0:
        return 0.01
    return 0.001


def detect_up(clip: BvhClip) -> str:
    """``"y"`` if the rest pose is taller along y than along z, else ``"z"``."""
    ext = _rest_extent(clip)
    return "y" if ext[1] > ext[2] else "z"


def _unique(name: str, taken: set[str]) -> str:
    out, k = name, 2
    while out in taken:
        out, k = f"{name}{k}", k + 1
    return out


def _local_names(clip: BvhClip, strip_namespace: bool) -> list[str]:
    names = list(clip.names)
    if not strip_namespace:
        return names
    stripped = [n.rsplit(":", 1)[-1] or n for n in names]
    seen: dict[str, str] = {}
    for full, short in zip(names, stripped):
        if short in seen:
            raise BvhError(f"joints {seen[short]!r} and {full!r} are both {short!r} without their namespace; "
                           "import with strip_namespace=False")
        seen[short] = full
    return stripped


def import_bvh(
    clip: BvhClip,
    effectors: Sequence[str] | None = None,
    *,
    root: str | None = None,
    limits: Literal["wide", "from_motion"] = "wide",
    margin: float = math.radians(15.0),
    scale: float | None = None,
    up: Literal["auto", "y", "z"] = "auto",
    strip_namespace: bool = False,
    name: str = "bvh",
) -> BvhImport:
    """A BVH clip as a gsik skeleton and motion (see the module's conventions).

    Args:
        clip: The parsed clip (:func:`gsik.io.bvh.read_bvh`).
        effectors: Site or joint names to use as effectors (after namespace
            stripping); ``None`` for every site plus the pelvis.
        root: The skeleton's IK root (a joint or site); default the top joint.
        limits: ``"wide"`` or ``"from_motion"``.
        margin: Extra range [rad] on both sides for ``"from_motion"``.
        scale: Metres per file unit; ``None`` to detect it (:func:`detect_scale`).
        up: The file's up axis: ``"y"``, ``"z"`` or ``"auto"`` (:func:`detect_up`).
        strip_namespace: Drop ``"prefix:"`` from joint names.
        name: The skeleton's name.

    Raises:
        BvhError: a bad argument, an unknown effector or root (listing the
            valid names), or names that clash once their namespace is stripped.
    """
    if not isinstance(clip, BvhClip):
        raise BvhError(f"import_bvh needs a gsik.io.bvh.BvhClip, got {type(clip).__name__}")
    if limits not in LIMIT_MODES:
        raise BvhError(f"unknown limits {limits!r}; expected one of {choices(LIMIT_MODES)}")
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0):
        raise BvhError(f"margin must be a finite angle >= 0 [rad], got {margin!r}")
    if scale is None:
        scale = detect_scale(clip)
    elif isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (math.isfinite(scale) and scale > 0):
        raise BvhError(f"scale must be a positive number of metres per file unit, got {scale!r}")
    scale = float(scale)
    if up == "auto":
        up = detect_up(clip)
    elif up not in UP_AXES:
        raise BvhError(f"unknown up axis {up!r}; expected 'auto' or one of {choices(UP_AXES)}")
    M = Z_UP_TO_Y_UP.T if up == "y" else np.eye(3)  # file -> gsik world

    names = _local_names(clip, strip_namespace)
    F = clip.n_frames
    local_R = bvh_local_rotations(clip)
    local_t = bvh_local_translations(clip)
    messages: list[str] = []

    # The root: a fixed top joint, its channels pinned per frame.
    W = np.tile(np.eye(4), (F, 1, 1))
    W[:, :3, :3] = M @ local_R[:, 0] @ M.T
    W[:, :3, 3] = scale * local_t[:, 0] @ M.T
    top_offset = W[0, :3, 3] if F else scale * (M @ clip.joints[0].offset)
    top_orientation = W[0, :3, :3] if F else np.eye(3)
    specs: list[JointSpec] = [JointSpec(names[0], None, tuple(top_offset), (), top_orientation)]
    sites: list[SiteSpec] = []
    dof_columns: list[tuple[str, int]] = []  # (dof name, motion column)

    children = [[] for _ in clip.joints]
    for j, joint in enumerate(clip.joints):
        if joint.parent >= 0:
            children[joint.parent].append(j)

    def is_site_joint(j: int) -> bool:
        joint = clip.joints[j]
        return (not joint.is_end_site and j > 0 and not joint.channels
                and all(clip.joints[c].is_end_site and not np.any(clip.joints[c].offset) for c in children[j]))

    skipped: set[int] = set()
    for j, joint in enumerate(clip.joints):
        if j == 0 or j in skipped:
            continue
        parent = names[joint.parent]
        if joint.is_end_site or is_site_joint(j):
            offset = scale * (M @ joint.offset)
            sites.append(SiteSpec(names[j], parent, tuple(offset)))
            skipped.update(children[j])
            continue
        start = clip.channel_index(j).start
        positions = [k for k, c in enumerate(joint.channels) if c.endswith("position")]
        if positions and F:
            values = clip.motion[:, [start + k for k in positions]]
            if np.any(np.ptp(values, axis=0) > 1e-9 * max(1.0, float(np.abs(values).max()))):
                messages.append(f"joint {joint.name!r}: its position channels change over the clip; gsik joints "
                                f"do not slide, so the first frame's offset is used")
        offset = scale * (M @ (local_t[0, j] if F else joint.offset))
        rotations = []
        for k, channel in enumerate(joint.channels):
            if channel.endswith("rotation"):
                axis = M @ np.eye(3)[_AXIS_INDEX[channel[0].lower()]]
                label = channel[0].lower()
                rotations.append(RotationSpec(tuple(axis), -math.pi, math.pi, 0.0, label))
                dof_columns.append((f"{names[j]}.{label}", start + k))
        specs.append(JointSpec(names[j], parent, tuple(offset), tuple(rotations)))

    # Limits from the motion.
    by_dof = {dof: col for dof, col in dof_columns}
    values = {dof: np.radians(clip.motion[:, col]) for dof, col in by_dof.items()}
    for n, spec in enumerate(specs):
        rots = []
        for r in spec.rotations:
            v = values[f"{spec.name}.{r.label}"]
            if limits == "from_motion" and v.size:
                lo, hi = float(v.min()) - margin, float(v.max()) + margin
            else:
                lo = min(-math.pi, float(v.min(initial=0.0)))
                hi = max(math.pi, float(v.max(initial=0.0)))
            rots.append(RotationSpec(r.axis, lo, hi, min(max(0.0, lo), hi), r.label))
        specs[n] = JointSpec(spec.name, spec.parent, spec.offset, tuple(rots), spec.orientation)

    # Effectors.
    joint_names = [s.name for s in specs]
    site_names = [s.name for s in sites]
    taken = set(joint_names) | set(site_names)
    chosen: list[str] = []
    if effectors is None:
        chosen = list(site_names)
        at_top = [s.name for s in sites if s.parent == names[0] and not np.any(s.offset)]
        if at_top:
            chosen.insert(0, at_top[0])
            chosen = list(dict.fromkeys(chosen))
        else:
            site = _unique(f"{names[0]}_site", taken)
            taken.add(site)
            sites.append(SiteSpec(site, names[0], (0.0, 0.0, 0.0)))
            chosen.insert(0, site)
    else:
        if isinstance(effectors, str):
            effectors = [effectors]
        for e in effectors:
            if e in site_names:
                chosen.append(e)
            elif e in joint_names:
                site = _unique(f"{e}_site", taken)
                taken.add(site)
                sites.append(SiteSpec(site, e, (0.0, 0.0, 0.0)))
                chosen.append(site)
            else:
                raise BvhError(f"no joint or site {e!r} to use as an effector; joints: {choices(joint_names)}; "
                               f"sites: {choices(site_names)}")
        if len(set(chosen)) != len(chosen):
            raise BvhError(f"effectors are listed twice: {list(effectors)}")

    # Segments: one per joint, from the joint to each child joint and site.
    ends: dict[str, list[str]] = {n: [] for n in joint_names}
    for s in specs[1:]:
        ends[s.parent].append(s.name)
    for s in sites:
        ends[s.parent].append(s.name)
    segments = [SegmentSpec(n, n, tuple(e)) for n, e in ends.items() if e]

    root_name = names[0] if root is None else root
    if root_name not in taken:
        raise BvhError(f"no joint or site {root_name!r} to use as the root; joints: {choices(joint_names)}; "
                       f"sites: {choices(s.name for s in sites)}")
    sk = build_skeleton(name, specs, sites, segments, effectors=chosen, root=root_name, source="<bvh>")

    q = np.zeros((F, sk.n_dofs))
    for dof, col in by_dof.items():
        q[:, sk.dof_index(dof)] = np.radians(clip.motion[:, col])
    motion = Motion(sk, q, (names[0],) * F, W, clip.frame_time)
    return BvhImport(sk, motion, tuple(chosen), scale, up, tuple(messages))


def skeleton_from_bvh(
    clip: BvhClip,
    effectors: Sequence[str] | None = None,
    limits: Literal["wide", "from_motion"] = "wide",
    scale: float | None = None,
    **options,
) -> tuple[Skeleton, Motion]:
    """A BVH clip as a gsik skeleton and its motion: :func:`import_bvh` without the extras.

    Whatever cannot be reproduced exactly is reported as a
    :class:`BvhImportWarning` (use :func:`import_bvh` to get it as data).
    ``options`` are :func:`import_bvh`'s keyword arguments.
    """
    result = import_bvh(clip, effectors, limits=limits, scale=scale, **options)
    for message in result.warnings:
        warnings.warn(message, BvhImportWarning, stacklevel=2)
    return result.skeleton, result.motion


__all__ = [
    "EULER_ORDER",
    "LIMIT_MODES",
    "UNITS_PER_METRE",
    "UP_AXES",
    "Z_UP_TO_Y_UP",
    "BvhImport",
    "BvhImportWarning",
    "detect_scale",
    "detect_up",
    "euler_from_matrix",
    "import_bvh",
    "matrix_from_euler",
    "motion_to_bvh",
    "pose_to_bvh",
    "skeleton_from_bvh",
    "write_motion_bvh",
]
