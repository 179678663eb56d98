"""The skeleton: a tree of one-DOF rotations, as frozen structure-of-arrays.

A skeleton is described by *specs* (joints with their one-DOF rotations,
sites, segments) and compiled into :class:`Skeleton`, whose arrays the
kernels read directly.

The compiled tree is made of *frames*, in topological order (parent before
child). A joint with ``k`` rotations becomes ``k`` frames joined by
zero-length links (the paper's "n one-DOF joints"); a joint with none becomes
one fixed frame; every site is one fixed frame. The local transform of
frame ``i`` is::

    parent_from_frame = Trans(offset[i]) @ Rot(rotation[i]) @ RotAxis(axis[i], q[dof[i]])

with ``RotAxis = I`` for fixed frames (``dof[i] == -1``).

Joint angles ``q`` always use this one representation, whatever the IK
root is: the root only decides which frame is pinned to the world (see
:mod:`gsik.kinematics`). A joint that lies between the root and the
skeleton's own top turns the other way round as seen from the root, which is
the same as negating its angle and swapping its limits; the kernels apply
that sign, so ``q``, ``lower`` and ``upper`` never change on a root switch.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from gsik.errors import SkeletonError, choices
from gsik.rotations import is_rotation_matrix
from gsik.validate import frozen, vector

AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclass(frozen=True)
class RotationSpec:
    """One one-DOF rotation of a joint.

    Attributes:
        axis: Unit axis (3,) in the joint's frame.
        lower: Lower limit [rad].
        upper: Upper limit [rad].
        rest: Angle in the standing (rest) pose [rad].
        label: Short name used in the DOF name (``"x"`` gives ``"left_hip.x"``).
    """

    axis: tuple[float, float, float]
    lower: float
    upper: float
    rest: float = 0.0
    label: str = ""


@dataclass(frozen=True)
class JointSpec:
    """A primary joint: a point on its parent with zero or more rotations.

    Attributes:
        name: Unique joint name.
        parent: Parent joint name, ``None`` for the top of the tree.
        offset: Position (3,) [m] of the joint in its parent's frame at rest.
        rotations: The one-DOF rotations, applied in order (first is outermost).
        orientation: Fixed rotation (3, 3) of the joint frame before its
            rotations (URDF origins need it); identity when ``None``.
    """

    name: str
    parent: str | None
    offset: tuple[float, float, float]
    rotations: tuple[RotationSpec, ...] = ()
    orientation: tuple | None = None


@dataclass(frozen=True)
class SiteSpec:
    """A named frame fixed to a joint: an effector, the root or a bone tip.

    Attributes:
        name: Unique name (shared namespace with joints).
        parent: The joint it is fixed to.
        offset: Position (3,) [m] in the parent joint's frame.
        orientation: Fixed rotation (3, 3) in the parent joint's frame, or ``None``.
    """

    name: str
    parent: str
    offset: tuple[float, float, float]
    orientation: tuple | None = None


@dataclass(frozen=True)
class SegmentSpec:
    """A rigid segment, drawn as bones from one joint or site to one or more others."""

    name: str
    start: str
    ends: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A compiled skeleton. Build it with :func:`build_skeleton`.

    All arrays are read-only. ``n_frames`` frames, ``n_dofs`` one-DOF joints.

    Attributes:
        name: Skeleton name.
        root: Name of the default IK root (a site or a joint).
        frame_names: (n_frames,) frame names: ``"joint.x"`` for a rotation,
            ``"joint"`` for a fixed joint, the site name for a site.
        frame_parent: (n_frames,) parent frame index, -1 for the top.
        frame_offset: (n_frames, 3) [m] translation from the parent frame.
        frame_rotation: (n_frames, 3, 3) fixed rotation from the parent frame.
        frame_axis: (n_frames, 3) unit rotation axis, zero for fixed frames.
        frame_dof: (n_frames,) DOF index of the frame, -1 if fixed.
        dof_names: (n_dofs,) names ``"joint.label"``.
        dof_frame: (n_dofs,) frame index of each DOF.
        lower, upper: (n_dofs,) joint limits [rad].
        rest: (n_dofs,) standing pose [rad].
        joint_names: (n_joints,) primary joint names.
        joint_frame: (n_joints,) the frame at the joint's end (after its rotations).
        joint_parent: (n_joints,) parent joint index, -1 for the top.
        joint_dofs: (n_joints,) tuple of each joint's DOF indices.
        site_names: names of the sites (effectors, root candidates, bone tips).
        site_frame: (n_sites,) frame index of each site.
        effector_sites: names of the sites usable as end-effectors.
        segment_names: (n_segments,) names of the rigid segments.
        bone_frames: (n_bones, 2) frame indices of each drawn bone's ends.
        bone_segment: (n_bones,) segment index of each bone.
    """

    name: str
    root: str
    frame_names: tuple[str, ...]
    frame_parent: np.ndarray
    frame_offset: np.ndarray
    frame_rotation: np.ndarray
    frame_axis: np.ndarray
    frame_dof: np.ndarray
    dof_names: tuple[str, ...]
    dof_frame: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    rest: np.ndarray
    joint_names: tuple[str, ...]
    joint_frame: np.ndarray
    joint_parent: np.ndarray
    joint_dofs: tuple[tuple[int, ...], ...]
    site_names: tuple[str, ...]
    site_frame: np.ndarray
    effector_sites: tuple[str, ...]
    segment_names: tuple[str, ...]
    bone_frames: np.ndarray
    bone_segment: np.ndarray
    source: str = field(default="<memory>", compare=False)

    # -- sizes ---------------------------------------------------------------
    @property
    def n_frames(self) -> int:
        return len(self.frame_names)

    @property
    def n_dofs(self) -> int:
        return len(self.dof_names)

    @property
    def n_joints(self) -> int:
        return len(self.joint_names)

    @property
    def effector_names(self) -> tuple[str, ...]:
        """The end-effectors for the current root: every effector site but the root."""
        return tuple(n for n in self.effector_sites if n != self.root)

    # -- lookups -------------------------------------------------------------
    @cached_property
    def _frame_index(self) -> dict[str, int]:
        index = {n: i for i, n in enumerate(self.frame_names)}
        # A joint is addressed by its end frame, whatever its rotations.
        index.update({n: int(f) for n, f in zip(self.joint_names, self.joint_frame)})
        return index

    def frame_of(self, name: str) -> int:
        """Frame index of a joint, a site, or a single DOF (``"left_knee.x"``)."""
        try:
            return self._frame_index[name]
        except KeyError:
            raise SkeletonError(
                f"skeleton {self.name!r} has no joint or site {name!r}; "
                f"joints: {choices(self.joint_names)}; sites: {choices(self.site_names)}"
            ) from None

    def dof_index(self, name: str) -> int:
        """Index of a DOF by its name ``"joint.label"``."""
        try:
            return self.dof_names.index(name)
        except ValueError:
            raise SkeletonError(
                f"skeleton {self.name!r} has no degree of freedom {name!r}; valid: {choices(self.dof_names)}"
            ) from None

    @cached_property
    def ancestry(self) -> np.ndarray:
        """(n_frames, n_frames) bool: ``ancestry[a, f]`` if frame ``a`` is ``f`` or above it."""
        anc = np.zeros((self.n_frames, self.n_frames), dtype=bool)
        for f in range(self.n_frames):
            a = f
            while a >= 0:
                anc[a, f] = True
                a = int(self.frame_parent[a])
        anc.flags.writeable = False
        return anc

    def with_root(self, name: str) -> Skeleton:
        """The same skeleton with another default IK root (a site or a joint)."""
        self.frame_of(name)
        return replace(self, root=name)

    # -- kinematics shortcuts --------------------------------------------------
    def frame_transforms(self, q: np.ndarray, world_from_root: np.ndarray | None = None) -> np.ndarray:
        """World transforms (n_frames, 4, 4) of every frame for angles ``q`` (n_dofs,) [rad].

        ``world_from_root`` (4, 4) pins the root frame; by default the skeleton
        stands where its definition puts it.
        """
        from gsik.kinematics import frame_transforms

        return frame_transforms(self, q, world_from_root)

    def effector_poses(self, q: np.ndarray, world_from_root: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """``{effector name: world transform (4, 4)}`` for angles ``q`` (n_dofs,) [rad]."""
        T = self.frame_transforms(q, world_from_root)
        return {n: T[self.frame_of(n)] for n in self.effector_names}

    def joint_positions(self, q: np.ndarray, world_from_root: np.ndarray | None = None) -> np.ndarray:
        """World positions (n_joints, 3) [m] of the primary joints."""
        return self.frame_transforms(q, world_from_root)[self.joint_frame, :3, 3]

    def clip(self, q: np.ndarray) -> np.ndarray:
        """``q`` (n_dofs,) clamped into the joint limits."""
        return np.clip(q, self.lower, self.upper)

    def validate_q(self, q) -> np.ndarray:
        """``q`` as a float array (n_dofs,), or :class:`SkeletonError` naming the problem."""
        a = np.asarray(q, dtype=float)
        if a.shape != (self.n_dofs,):
            raise SkeletonError(f"joint angles must have shape ({self.n_dofs},), got {a.shape}")
        if not np.all(np.isfinite(a)):
            bad = [self.dof_names[i] for i in np.flatnonzero(~np.isfinite(a))]
            raise SkeletonError(f"joint angles are not finite for {choices(bad)}")
        return a


def _axis_label(axis, k: int) -> str:
    for label, a in AXES.items():
        if np.allclose(axis, a):
            return label
    return f"r{k}"


def _vector(value, what: str) -> tuple[float, float, float]:
    return vector(value, 3, what, SkeletonError)


def _orientation(value, what: str) -> np.ndarray:
    if value is None:
        return np.eye(3)
    R = np.asarray(value, dtype=float)
    if not is_rotation_matrix(R):
        raise SkeletonError(f"{what} must be a rotation matrix, got {value!r}")
    return R


class _Frames:
    """The frame table under construction: one row per frame, in topological order."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.parent: list[int] = []
        self.offset: list = []
        self.rotation: list = []
        self.axis: list = []
        self.dof: list[int] = []

    def add(self, name: str, parent: int, offset, rotation, axis=(0.0, 0.0, 0.0), dof: int = -1) -> int:
        """Append one frame; returns its index."""
        self.names.append(name)
        self.parent.append(parent)
        self.offset.append(offset)
        self.rotation.append(rotation)
        self.axis.append(axis)
        self.dof.append(dof)
        return len(self.names) - 1


class _Dofs:
    """The DOF table under construction: one row per one-DOF rotation."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.frame: list[int] = []
        self.lower: list[float] = []
        self.upper: list[float] = []
        self.rest: list[float] = []

    def add(self, name: str, frame: int, lower: float, upper: float, rest: float) -> int:
        """Append one DOF; returns its index."""
        self.names.append(name)
        self.frame.append(frame)
        self.lower.append(lower)
        self.upper.append(upper)
        self.rest.append(rest)
        return len(self.names) - 1


class _SkeletonBuilder:
    """Raw specs → :class:`Skeleton` by named steps (ozz-animation's raw → runtime builder).

    Each step checks one thing or fills one table; :meth:`skeleton` freezes the tables.
    """

    def __init__(self, source: str) -> None:
        self.source = source
        self.frames = _Frames()
        self.dofs = _Dofs()
        self.by_name: dict[str, JointSpec] = {}
        self.order: list[str] = []
        self.joint_frame: dict[str, int] = {}
        self.joint_dofs: dict[str, tuple[int, ...]] = {}
        self.site_names: list[str] = []
        self.site_frame: list[int] = []
        self.index: dict[str, int] = {}
        self.segment_names: list[str] = []
        self.bones: list[tuple[int, int]] = []
        self.bone_segment: list[int] = []
        self.effectors: tuple[str, ...] = ()
        self.root = ""

    def fail(self, msg: str):
        raise SkeletonError(f"{self.source}: {msg}")

    # --- names and the tree --------------------------------------------------------------
    def index_joints(self, joints: Sequence[JointSpec]) -> None:
        """Every joint named once, with a non-empty string."""
        if not joints:
            self.fail("a skeleton needs at least one joint")
        for j in joints:
            if not isinstance(j.name, str) or not j.name:
                self.fail(f"joint name must be a non-empty string, got {j.name!r}")
            if j.name in self.by_name:
                self.fail(f"duplicate joint name {j.name!r}")
            self.by_name[j.name] = j

    def check_sites(self, sites: Sequence[SiteSpec]) -> None:
        """Site names unique among joints and sites, each site hung on a joint."""
        counts = Counter(s.name for s in sites)
        for s in sites:
            if s.name in self.by_name or counts[s.name] > 1:
                self.fail(f"duplicate name {s.name!r} (joint and site names share one namespace)")
            if s.parent not in self.by_name:
                self.fail(f"site {s.name!r}: parent {s.parent!r} is not a joint; joints: {choices(self.by_name)}")
        self.site_names = [s.name for s in sites]

    def top_joint(self, joints: Sequence[JointSpec]) -> str:
        """The one joint without a parent; every other parent must be a joint."""
        tops = [j.name for j in joints if j.parent is None]
        for j in joints:
            if j.parent is not None and j.parent not in self.by_name:
                self.fail(f"joint {j.name!r}: parent {j.parent!r} is not a joint; joints: {choices(self.by_name)}")
        if not tops:
            self.fail("no joint without a parent: the joints form a cycle")
        if len(tops) != 1:
            self.fail(f"exactly one joint may have no parent, found {len(tops)}: {choices(tops)}")
        return tops[0]

    def order_joints(self, joints: Sequence[JointSpec], top: str) -> None:
        """Topological order: depth first from ``top``, keeping the file's order among siblings."""
        children: dict[str, list[str]] = {j.name: [] for j in joints}
        for j in joints:
            if j.parent is not None:
                children[j.parent].append(j.name)
        stack = [top]
        while stack:
            n = stack.pop()
            self.order.append(n)
            stack.extend(reversed(children[n]))
        if len(self.order) != len(joints):
            cyclic = sorted(set(children) - set(self.order))
            self.fail(f"joints {choices(cyclic)} form a cycle (none of them leads back to {top!r})")

    # --- the frame and DOF tables --------------------------------------------------------
    def add_joint(self, j: JointSpec) -> None:
        """Frames (and DOFs) of one joint whose parent is already in the table."""
        what = f"joint {j.name!r}"
        p = -1 if j.parent is None else self.joint_frame[j.parent]
        off = _vector(j.offset, f"{what} offset")
        R0 = _orientation(j.orientation, f"{what} orientation")
        if not j.rotations:
            self.joint_frame[j.name] = self.frames.add(j.name, p, off, R0)
            self.joint_dofs[j.name] = ()
            return
        labels = [r.label or _axis_label(r.axis, k) for k, r in enumerate(j.rotations)]
        if len(set(labels)) != len(labels):
            self.fail(f"{what}: rotations need distinct labels, got {labels}")
        mine = []
        for k, (r, label) in enumerate(zip(j.rotations, labels)):
            axis, lo, hi, rs = self.check_rotation(r, f"{what} rotation {label}")
            name = f"{j.name}.{label}"
            if k > 0:  # later rotations hang on the previous one by a zero-length link
                p, off, R0 = len(self.frames.names) - 1, (0.0, 0.0, 0.0), np.eye(3)
            frame = self.frames.add(name, p, off, R0, axis, len(self.dofs.names))
            mine.append(self.dofs.add(name, frame, lo, hi, rs))
        self.joint_frame[j.name] = len(self.frames.names) - 1
        self.joint_dofs[j.name] = tuple(mine)

    def check_rotation(self, r: RotationSpec, what: str) -> tuple[tuple, float, float, float]:
        """``(unit axis, lower, upper, rest)`` of one rotation, checked."""
        a = np.asarray(_vector(r.axis, f"{what} axis"))
        norm = np.linalg.norm(a)
        if norm < 1e-9:
            self.fail(f"{what}: axis must not be zero")
        lo, hi, rs = (float(r.lower), float(r.upper), float(r.rest))
        if not all(np.isfinite(v) for v in (lo, hi, rs)):
            self.fail(f"{what}: limits and rest must be finite, got lower={lo}, upper={hi}, rest={rs}")
        if lo > hi:
            self.fail(f"{what}: lower limit {lo} is above upper limit {hi}")
        if not lo <= rs <= hi:
            self.fail(f"{what}: rest angle {rs} is outside the limits [{lo}, {hi}]")
        return tuple(a / norm), lo, hi, rs

    def add_sites(self, sites: Sequence[SiteSpec]) -> None:
        """One fixed frame per site; then every joint and site name gets its frame index."""
        for s in sites:
            self.site_frame.append(self.frames.add(
                s.name, self.joint_frame[s.parent], _vector(s.offset, f"site {s.name!r} offset"),
                _orientation(s.orientation, f"site {s.name!r} orientation")))
        self.index = {n: i for i, n in enumerate(self.frames.names)}
        self.index.update(self.joint_frame)

    def add_segments(self, segments: Sequence[SegmentSpec]) -> None:
        """Bones (start frame, end frame) of each segment; every end a joint or site."""
        seg_index: dict[str, int] = {}
        for seg in segments:
            if seg.name in seg_index:
                self.fail(f"duplicate segment name {seg.name!r}")
            if not seg.ends:
                self.fail(f"segment {seg.name!r} needs at least one end")
            for end in (seg.start, *seg.ends):
                if end not in self.index:
                    self.fail(f"segment {seg.name!r}: {end!r} is not a joint or site; joints: "
                              f"{choices(self.order)}; sites: {choices(self.site_names)}")
            for end in seg.ends:
                self.bones.append((self.index[seg.start], self.index[end]))
                self.bone_segment.append(len(seg_index))
            seg_index[seg.name] = len(seg_index)
        self.segment_names = list(seg_index)

    def set_effectors(self, effectors: Sequence[str]) -> None:
        """Effectors are sites, each listed once."""
        self.effectors = tuple(effectors)
        sites = set(self.site_names)
        for e in self.effectors:
            if e not in sites:
                self.fail(f"effector {e!r} is not a site; sites: {choices(self.site_names)}")
        if len(set(self.effectors)) != len(self.effectors):
            self.fail(f"effectors are listed twice: {list(self.effectors)}")

    def set_root(self, root: str | None) -> None:
        """The IK root: a joint or site, the top joint by default."""
        self.root = self.order[0] if root is None else root
        if self.root not in self.index:
            self.fail(f"root {self.root!r} is not a joint or site; sites: {choices(self.site_names)}")

    # --- runtime structure ---------------------------------------------------------------
    def skeleton(self, name: str) -> Skeleton:
        """The frozen structure-of-arrays from the checked tables."""
        frames, dofs, order = self.frames, self.dofs, self.order
        joint_row = {n: i for i, n in enumerate(order)}
        joint_parent = [-1 if self.by_name[n].parent is None else joint_row[self.by_name[n].parent] for n in order]
        return Skeleton(
            name=name,
            root=self.root,
            frame_names=tuple(frames.names),
            frame_parent=frozen(frames.parent, np.int64),
            frame_offset=frozen(np.reshape(frames.offset, (-1, 3))),
            frame_rotation=frozen(np.reshape(frames.rotation, (-1, 3, 3))),
            frame_axis=frozen(np.reshape(frames.axis, (-1, 3))),
            frame_dof=frozen(frames.dof, np.int64),
            dof_names=tuple(dofs.names),
            dof_frame=frozen(dofs.frame, np.int64),
            lower=frozen(dofs.lower),
            upper=frozen(dofs.upper),
            rest=frozen(dofs.rest),
            joint_names=tuple(order),
            joint_frame=frozen([self.joint_frame[n] for n in order], np.int64),
            joint_parent=frozen(joint_parent, np.int64),
            joint_dofs=tuple(self.joint_dofs[n] for n in order),
            site_names=tuple(self.site_names),
            site_frame=frozen(self.site_frame, np.int64),
            effector_sites=self.effectors,
            segment_names=tuple(self.segment_names),
            bone_frames=frozen(np.reshape(self.bones, (-1, 2)), np.int64),
            bone_segment=frozen(self.bone_segment, np.int64),
            source=self.source,
        )


def build_skeleton(
    name: str,
    joints: Sequence[JointSpec],
    sites: Sequence[SiteSpec] = (),
    segments: Sequence[SegmentSpec] = (),
    effectors: Sequence[str] = (),
    root: str | None = None,
    source: str = "<memory>",
) -> Skeleton:
    """Validate specs and compile them into a :class:`Skeleton`.

    Raises:
        SkeletonError: naming ``source``, the item and the bad value for
            duplicate names, unknown parents, cycles, several tops, limits
            with ``lower > upper``, non-finite numbers, zero axes, unknown
            effectors, segment ends or root.
    """
    b = _SkeletonBuilder(source)
    b.index_joints(joints)
    b.check_sites(sites)
    b.order_joints(joints, b.top_joint(joints))
    for jname in b.order:
        b.add_joint(b.by_name[jname])
    b.add_sites(sites)
    b.add_segments(segments)
    b.set_effectors(effectors)
    b.set_root(root)
    return b.skeleton(name)
