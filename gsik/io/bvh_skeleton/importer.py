"""BVH -> gsik: a clip as a skeleton and its motion (conventions in :mod:`gsik.io.bvh_skeleton`)."""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Literal, NamedTuple

import numpy as np

from gsik import validate
from gsik.anim.motion import Motion
from gsik.errors import BvhError, choices
from gsik.io.bvh import BvhClip, bvh_forward_kinematics, bvh_local_rotations, bvh_local_translations
from gsik.io.bvh_skeleton.conventions import AXIS_INDEX, LIMIT_MODES, UP_AXES, Z_UP_TO_Y_UP, BvhImportWarning
from gsik.io.names import unique_name
from gsik.skeleton import JointSpec, RotationSpec, SegmentSpec, SiteSpec, Skeleton, build_skeleton




class BvhImport(NamedTuple):
    """What :func:`import_bvh` made of a clip.

    Attributes:
        skeleton: The skeleton (root: the top joint unless chosen otherwise).
        motion: The clip's motion on it, the top joint pinned per frame.
        effectors: The effector sites, in the order asked for.
        scale: Metres per file unit used.
        up: The file's up axis used (``"y"`` or ``"z"``).
        warnings: What could not be reproduced exactly, one sentence each.
        clip: The clip imported.
        dof_columns: ``(dof name, motion column)`` of every rotation channel:
            where :func:`~gsik.io.bvh_skeleton.clip_with_motion` writes a
            solved motion back.
        up_reason: Why ``up`` was chosen (detected, or as given).
    """

    skeleton: Skeleton
    motion: Motion
    effectors: tuple[str, ...]
    scale: float
    up: str
    warnings: tuple[str, ...]
    clip: BvhClip | None = None
    dof_columns: tuple[tuple[str, int], ...] = ()
    up_reason: str = ""


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
    """The clip's up axis, ``"y"`` or ``"z"``, judged over the whole clip (see :func:`detect_up_reason`)."""
    return detect_up_reason(clip)[0]


def detect_up_reason(clip: BvhClip) -> tuple[str, str]:
    """``(up axis, why)``: the axis along which the body stands over the whole clip.

    The first frame or the rest pose can mislead (a T-pose lying flat, a clip
    that starts on the floor), so every frame counts: the up axis is the one
    along which the body is tallest in the median frame. Where y and z are
    within 10% of each other, gravity decides: the body's lowest point (the
    feet on the ground) keeps one height along the up axis while it travels
    along the others. A clip without frames is judged by its rest pose.
    """
    if clip.n_frames == 0:
        ext = _rest_extent(clip)
        up = "y" if ext[1] > ext[2] else "z"
        return up, f"{up} up: the rest pose is {ext[1]:.4g} units tall along y, {ext[2]:.4g} along z (no frames)"
    step = max(1, clip.n_frames // 2000)  # a few thousand frames tell as much as all of them
    sample = BvhClip(clip.joints, clip.frame_time, clip.motion[::step])
    p = bvh_forward_kinematics(sample)[1]  # (F, n, 3) file units
    height = np.median(p.max(axis=1) - p.min(axis=1), axis=0)
    ground = np.ptp(p.min(axis=1), axis=0)  # how far the lowest point moves along each axis
    tall = int(np.argmax(height[1:])) + 1
    other = 3 - tall
    if height[tall] < 1.1 * height[other] and ground[other] < ground[tall]:
        tall, other = other, tall
    up, side = "xyz"[tall], "xyz"[other]
    why = (f"{up} up: over {clip.n_frames} frames the body is {height[tall]:.4g} units tall along {up} and "
           f"{height[other]:.4g} along {side} (median frame); its lowest point moves {ground[tall]:.4g} units "
           f"along {up} (the ground) and {ground[other]:.4g} along {side}")
    return up, why


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
    unwrap: bool = True,
    source: str = "<bvh>",
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
        unwrap: Unwrap each rotation channel over the frames (default); ``False``
            takes the file's angles as they are (limits then stop at a wrap).
        source: The clip's file, for the messages of a skeleton that cannot be built.

    Raises:
        BvhError: a bad argument, an unknown effector or root (listing the
            valid names), or names that clash once their namespace is stripped.
    """
    scale, (up, up_reason) = _check_import_args(clip, limits, margin, scale, up)
    b = _Importer(clip, _local_names(clip, strip_namespace), scale, up, bool(unwrap))
    b.add_joints_and_sites()
    b.set_limits(limits, margin)
    chosen = b.default_effectors() if effectors is None else b.named_effectors(effectors)
    root_name = b.names[0] if root is None else root
    if root_name not in b.taken:
        raise BvhError(f"no joint or site {root_name!r} to use as the root; joints: {choices(b.joint_names)}; "
                       f"sites: {choices(s.name for s in b.sites)}")
    sk = build_skeleton(name, b.specs, b.sites, b.segments(), effectors=chosen, root=root_name, source=source)
    return BvhImport(sk, b.motion(sk), tuple(chosen), scale, up, tuple(b.messages), clip,
                     tuple(b.dof_columns.items()), up_reason)


def _check_import_args(clip: BvhClip, limits: str, margin: float, scale: float | None,
                       up: str) -> tuple[float, tuple[str, str]]:
    """``(scale [m per file unit], (up axis, why))``, detected where asked; the other arguments checked."""
    if not isinstance(clip, BvhClip):
        raise BvhError(f"import_bvh needs a gsik.io.bvh.BvhClip, got {type(clip).__name__}")
    if limits not in LIMIT_MODES:
        raise BvhError(f"unknown limits {limits!r}; expected one of {choices(LIMIT_MODES)}")
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0):
        raise BvhError(f"margin must be a finite angle >= 0 [rad], got {margin!r}")
    scale = detect_scale(clip) if scale is None else validate.positive(scale, "scale", BvhError,
                                                                       "metres per file unit")
    if up == "auto":
        return scale, detect_up_reason(clip)
    if up not in UP_AXES:
        raise BvhError(f"unknown up axis {up!r}; expected 'auto' or one of {choices(UP_AXES)}")
    return scale, (up, "as given")


class _Importer:
    """A clip turned into joint and site specs by named steps, then into a skeleton and its motion.

    Attributes:
        names: (n_joints,) the clip's joint names (namespace stripped if asked).
        M: (3, 3) file -> gsik world turn.
        W: (F, 4, 4) the top joint's world transform per frame [m].
        specs, sites: The skeleton's joints and sites so far.
        dof_columns: ``{dof name: motion column}`` of every rotation channel.
        messages: What cannot be reproduced exactly.
    """

    def __init__(self, clip: BvhClip, names: list[str], scale: float, up: str, unwrap: bool) -> None:
        self.clip, self.names, self.scale, self.unwrap = clip, names, float(scale), unwrap
        self.M = Z_UP_TO_Y_UP.T if up == "y" else np.eye(3)  # file -> gsik world
        self.local_t = bvh_local_translations(clip)
        self.children: list[list[int]] = [[] for _ in clip.joints]
        for j, joint in enumerate(clip.joints):
            if joint.parent >= 0:
                self.children[joint.parent].append(j)
        self.messages: list[str] = []
        self.dof_columns: dict[str, int] = {}
        self.sites: list[SiteSpec] = []
        self.W = self._root_placement()
        F = clip.n_frames
        top_offset = self.W[0, :3, 3] if F else self.scale * (self.M @ clip.joints[0].offset)
        top_orientation = self.W[0, :3, :3] if F else np.eye(3)
        self.specs: list[JointSpec] = [JointSpec(names[0], None, tuple(top_offset), (), top_orientation)]

    def _root_placement(self) -> np.ndarray:
        """The root: a fixed top joint, its channels pinned per frame as (F, 4, 4) world transforms."""
        M, clip = self.M, self.clip
        W = np.tile(np.eye(4), (clip.n_frames, 1, 1))
        W[:, :3, :3] = M @ bvh_local_rotations(clip)[:, 0] @ M.T
        W[:, :3, 3] = self.scale * self.local_t[:, 0] @ M.T
        return W

    @property
    def joint_names(self) -> list[str]:
        return [s.name for s in self.specs]

    @property
    def taken(self) -> set[str]:
        return set(self.joint_names) | {s.name for s in self.sites}

    # --- joints and sites ------------------------------------------------------------
    def is_site_joint(self, j: int) -> bool:
        """A zero-channel JOINT whose End Sites all sit at its origin: what the export writes for a site."""
        joint = self.clip.joints[j]
        return (not joint.is_end_site and j > 0 and not joint.channels
                and all(self.clip.joints[c].is_end_site and not np.any(self.clip.joints[c].offset)
                        for c in self.children[j]))

    def add_joints_and_sites(self) -> None:
        """Every joint but the root as a joint spec, every End Site (or site joint) as a site spec."""
        skipped: set[int] = set()
        for j, joint in enumerate(self.clip.joints):
            if j == 0 or j in skipped:
                continue
            if joint.is_end_site or self.is_site_joint(j):
                offset = self.scale * (self.M @ joint.offset)
                self.sites.append(SiteSpec(self.names[j], self.names[joint.parent], tuple(offset)))
                skipped.update(self.children[j])
            else:
                self.specs.append(self.joint_spec(j))

    def joint_spec(self, j: int) -> JointSpec:
        """One rotation per rotation channel, in the file's order; position channels fixed at frame 0."""
        joint, F = self.clip.joints[j], self.clip.n_frames
        start = self.clip.channel_index(j).start
        self.warn_if_sliding(j, start)
        offset = self.scale * (self.M @ (self.local_t[0, j] if F else joint.offset))
        rotations = []
        for k, channel in enumerate(joint.channels):
            if channel.endswith("rotation"):
                label = channel[0].lower()
                axis = self.M @ np.eye(3)[AXIS_INDEX[label]]
                rotations.append(RotationSpec(tuple(axis), -math.pi, math.pi, 0.0, label))
                self.dof_columns[f"{self.names[j]}.{label}"] = start + k
        return JointSpec(self.names[j], self.names[joint.parent], tuple(offset), tuple(rotations))

    def warn_if_sliding(self, j: int, start: int) -> None:
        """A message when joint ``j``'s position channels change over the clip (gsik joints do not slide)."""
        joint = self.clip.joints[j]
        positions = [k for k, c in enumerate(joint.channels) if c.endswith("position")]
        if not (positions and self.clip.n_frames):
            return
        values = self.clip.motion[:, [start + k for k in positions]]
        if np.any(np.ptp(values, axis=0) > 1e-9 * max(1.0, float(np.abs(values).max()))):
            self.messages.append(f"joint {joint.name!r}: its position channels change over the clip; gsik joints "
                                 f"do not slide, so the first frame's offset is used")

    def angles(self, dof: str) -> np.ndarray:
        """(F,) the clip's angle of ``dof`` [rad], unwrapped: continuous, without 360-degree jumps."""
        angles = np.radians(self.clip.motion[:, self.dof_columns[dof]])
        return np.unwrap(angles) if self.unwrap else angles

    # --- limits --------------------------------------------------------------------------
    def set_limits(self, limits: str, margin: float) -> None:
        """Limits from the motion: ``"wide"`` [-pi, pi] widened to the clip, or the clip's range + ``margin``."""
        for n, spec in enumerate(self.specs):
            rots = []
            for r in spec.rotations:
                v = self.angles(f"{spec.name}.{r.label}")
                lo, hi = _limits(v, limits, margin)
                rots.append(RotationSpec(r.axis, lo, hi, min(max(0.0, lo), hi), r.label))
            self.specs[n] = JointSpec(spec.name, spec.parent, spec.offset, tuple(rots), spec.orientation)

    # --- effectors -----------------------------------------------------------------------
    def add_site_at(self, joint: str) -> str:
        """A new site ``"<joint>_site"`` (made unique) at the origin of ``joint``; returns its name."""
        site = unique_name(f"{joint}_site", self.taken)
        self.sites.append(SiteSpec(site, joint, (0.0, 0.0, 0.0)))
        return site

    def default_effectors(self) -> list[str]:
        """Every site, the one at the top joint's origin first (added if there is none: the pelvis)."""
        chosen = [s.name for s in self.sites]
        at_top = [s.name for s in self.sites if s.parent == self.names[0] and not np.any(s.offset)]
        if at_top:
            return list(dict.fromkeys([at_top[0], *chosen]))
        return [self.add_site_at(self.names[0]), *chosen]

    def named_effectors(self, effectors: Sequence[str] | str) -> list[str]:
        """The sites named, or a new site at each joint named."""
        effectors = [effectors] if isinstance(effectors, str) else effectors
        site_names = [s.name for s in self.sites]
        sites, joints = set(site_names), set(self.joint_names)
        chosen = []
        for e in effectors:
            if e in sites:
                chosen.append(e)
            elif e in joints:
                chosen.append(self.add_site_at(e))
            else:
                raise BvhError(f"no joint or site {e!r} to use as an effector; joints: {choices(self.joint_names)}; "
                               f"sites: {choices(site_names)}")
        if len(set(chosen)) != len(chosen):
            raise BvhError(f"effectors are listed twice: {list(effectors)}")
        return chosen

    # --- the result ----------------------------------------------------------------------
    def segments(self) -> list[SegmentSpec]:
        """One segment per joint, from the joint to each child joint and site."""
        ends: dict[str, list[str]] = {n: [] for n in self.joint_names}
        for s in [*self.specs[1:], *self.sites]:
            ends[s.parent].append(s.name)
        return [SegmentSpec(n, n, tuple(e)) for n, e in ends.items() if e]

    def motion(self, sk: Skeleton) -> Motion:
        """The clip's angles on ``sk``, the top joint pinned per frame."""
        q = np.zeros((self.clip.n_frames, sk.n_dofs))
        for dof in self.dof_columns:
            q[:, sk.dof_index(dof)] = self.angles(dof)
        return Motion(sk, q, (self.names[0],) * self.clip.n_frames, self.W, self.clip.frame_time)


def _limits(v: np.ndarray, limits: str, margin: float) -> tuple[float, float]:
    """``(lower, upper)`` [rad] of one DOF whose clip values are ``v`` (F,) [rad]."""
    if limits == "from_motion" and v.size:
        return float(v.min()) - margin, float(v.max()) + margin
    lo, hi = float(v.min(initial=0.0)), float(v.max(initial=0.0))
    if lo < -math.pi or hi > math.pi:  # past half a turn (an unwrapped spin): half a turn of room beyond the clip
        return lo - math.pi, hi + math.pi
    return -math.pi, math.pi


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
