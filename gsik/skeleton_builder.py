"""The raw skeleton: editable specs (joints with their one-DOF rotations, sites, segments) and the builder that
checks them and turns them into the structure-of-arrays of :class:`gsik.skeleton.Skeleton`.

Use :func:`gsik.build_skeleton`; this module holds its steps (ozz-animation's raw skeleton → runtime skeleton).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from gsik.balance import convex_hull
from gsik.errors import SkeletonError, choices, show_value
from gsik.rotations import is_rotation_matrix
from gsik.validate import frozen, vector

AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}

#: Most degrees of freedom a skeleton may have: the solver's work arrays grow with the square of the DOF count and
#: a step with its cube (2048 DOFs: ~1.5 s a step), so larger skeletons are refused when built, not when solved.
MAX_DOFS = 2048

#: Most frames (a joint without rotations, each one-DOF rotation, each site: one frame) a skeleton may have; the
#: frame-to-frame ancestry table holds the square of it (8192 frames: 64 MB).
MAX_FRAMES = 8192


#: Longest joint, site or DOF name [characters]: names become keys of pose files, and YAML keys stop at 1024.
MAX_NAME_CHARS = 256


#: Longest a skeleton may be: the sum of its offsets' lengths [m]. No pose then puts a frame farther than this from
#: the root, so every frame stays within :data:`gsik.targets.MAX_COORDINATE` of a root near the origin.
MAX_REACH = 1e5


def check_reach(frame_offset: np.ndarray, source: str) -> None:
    """Refuse a skeleton whose offsets ``frame_offset`` (n_frames, 3) [m] add up to more than :data:`MAX_REACH`."""
    with np.errstate(over="ignore", invalid="ignore"):
        reach = float(np.sum(np.linalg.norm(frame_offset, axis=1)))
    if not reach <= MAX_REACH:
        raise SkeletonError(f"{source}: the offsets add up to {reach:.6g} m; a skeleton may reach at most "
                            f"{MAX_REACH:g} m")


def check_size(n_dofs: int, n_frames: int, source: str) -> None:
    """Refuse a skeleton beyond :data:`MAX_DOFS` or :data:`MAX_FRAMES` with a :class:`SkeletonError`."""
    if n_dofs > MAX_DOFS:
        raise SkeletonError(f"{source}: {n_dofs:,} degrees of freedom; gsik's dense solver takes at most "
                            f"{MAX_DOFS:,} (its work grows with the square of the count)")
    if n_frames > MAX_FRAMES:
        raise SkeletonError(f"{source}: {n_frames:,} frames (joints, rotations and sites); gsik takes at most "
                            f"{MAX_FRAMES:,}")


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
        sole: For a foot, the corners ``((x, y), ...)`` [m] of its sole in the
            site frame's x-y plane (at least 3; their convex hull is the
            support polygon balance uses), or ``None``.
    """

    name: str
    parent: str
    offset: tuple[float, float, float]
    orientation: tuple | None = None
    sole: tuple | None = None


@dataclass(frozen=True)
class SegmentSpec:
    """A rigid segment, drawn as bones from one joint or site to one or more others.

    Attributes:
        mass: [kg] (>= 0; 0 for a segment without mass, the default).
        com: Where its centre of mass lies along its first bone: 0 at
            ``start``, 1 at the first end.
    """

    name: str
    start: str
    ends: tuple[str, ...]
    mass: float = 0.0
    com: float = 0.5


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
        raise SkeletonError(f"{what} must be a rotation matrix, got {show_value(value)}")
    return R


class _FrameRow(NamedTuple):
    """One frame of the table under construction (see :class:`Skeleton` for the columns)."""

    name: str
    parent: int
    offset: tuple
    rotation: np.ndarray
    axis: tuple = (0.0, 0.0, 0.0)
    dof: int = -1


class _DofRow(NamedTuple):
    """One one-DOF rotation of the table under construction."""

    name: str
    frame: int
    lower: float
    upper: float
    rest: float


def _add(rows: list, row) -> int:
    """Append ``row``; returns its index."""
    rows.append(row)
    return len(rows) - 1


class SkeletonBuilder:
    """Raw specs → the arrays of a :class:`~gsik.skeleton.Skeleton` by named steps (ozz-animation's raw → runtime builder).

    Each step checks one thing or fills one table; :meth:`arrays` freezes the tables.
    """

    def __init__(self, source: str) -> None:
        self.source = source
        self.frames: list[_FrameRow] = []
        self.dofs: list[_DofRow] = []
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
        self.segment_mass: list[float] = []
        self.segment_com: list[float] = []
        self.soles: dict[str, np.ndarray] = {}
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
            self.check_name(j.name, "joint name")
            if j.name in self.by_name:
                self.fail(f"duplicate joint name {show_value(j.name)}")
            self.by_name[j.name] = j

    def check_name(self, name, what: str) -> None:
        """A non-empty string of at most :data:`MAX_NAME_CHARS` characters that is text (no lone surrogates)."""
        if not isinstance(name, str) or not name:
            self.fail(f"{what} must be a non-empty string, got {show_value(name)}")
        if len(name) > MAX_NAME_CHARS:
            self.fail(f"{what} {show_value(name)} is {len(name):,} characters long; the limit is {MAX_NAME_CHARS}")
        try:
            name.encode("utf-8")
        except UnicodeEncodeError:
            self.fail(f"{what} {show_value(name)} is not text (it holds a lone surrogate)")

    def check_size(self, joints: Sequence[JointSpec], sites: Sequence[SiteSpec]) -> None:
        """Within :data:`MAX_DOFS` and :data:`MAX_FRAMES`, before any table is filled."""
        n_dofs = sum(len(j.rotations) for j in joints)
        check_size(n_dofs, n_dofs + sum(not j.rotations for j in joints) + len(sites), self.source)

    def check_sites(self, sites: Sequence[SiteSpec]) -> None:
        """Site names unique among joints and sites, each site hung on a joint."""
        counts = Counter(s.name for s in sites)
        for s in sites:
            self.check_name(s.name, "site name")
            if s.name in self.by_name or counts[s.name] > 1:
                self.fail(f"duplicate name {show_value(s.name)} (joint and site names share one namespace)")
            if s.parent not in self.by_name:
                self.fail(f"site {show_value(s.name)}: parent {show_value(s.parent)} is not a joint; "
                          f"joints: {choices(self.by_name)}")
        self.site_names = [s.name for s in sites]

    def top_joint(self, joints: Sequence[JointSpec]) -> str:
        """The one joint without a parent; every other parent must be a joint."""
        tops = [j.name for j in joints if j.parent is None]
        for j in joints:
            if j.parent is not None and j.parent not in self.by_name:
                self.fail(f"joint {show_value(j.name)}: parent {show_value(j.parent)} is not a joint; "
                          f"joints: {choices(self.by_name)}")
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
            self.fail(f"joints {choices(cyclic)} form a cycle (none of them leads back to {show_value(top)})")

    # --- the frame and DOF tables --------------------------------------------------------
    def add_joint(self, j: JointSpec) -> None:
        """Frames (and DOFs) of one joint whose parent is already in the table."""
        what = f"joint {show_value(j.name)}"
        p = -1 if j.parent is None else self.joint_frame[j.parent]
        off = _vector(j.offset, f"{what} offset")
        R0 = _orientation(j.orientation, f"{what} orientation")
        if not j.rotations:
            self.joint_frame[j.name] = _add(self.frames, _FrameRow(j.name, p, off, R0))
            self.joint_dofs[j.name] = ()
            return
        labels = [r.label or _axis_label(r.axis, k) for k, r in enumerate(j.rotations)]
        for label in labels:
            self.check_name(f"{j.name}.{label}", "degree of freedom name")
        if len(set(labels)) != len(labels):
            self.fail(f"{what}: rotations need distinct labels, got {labels}")
        mine = []
        for k, (r, label) in enumerate(zip(j.rotations, labels)):
            axis, lo, hi, rs = self.check_rotation(r, f"{what} rotation {label}")
            name = f"{j.name}.{label}"
            if k > 0:  # later rotations hang on the previous one by a zero-length link
                p, off, R0 = len(self.frames) - 1, (0.0, 0.0, 0.0), np.eye(3)
            frame = _add(self.frames, _FrameRow(name, p, off, R0, axis, len(self.dofs)))
            mine.append(_add(self.dofs, _DofRow(name, frame, lo, hi, rs)))
        self.joint_frame[j.name] = len(self.frames) - 1
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
            self.site_frame.append(_add(self.frames, _FrameRow(
                s.name, self.joint_frame[s.parent], _vector(s.offset, f"site {show_value(s.name)} offset"),
                _orientation(s.orientation, f"site {show_value(s.name)} orientation"))))
            if s.sole is not None:
                self.soles[s.name] = self.check_sole(s)
        self.index = {row.name: i for i, row in enumerate(self.frames)}
        self.index.update(self.joint_frame)

    def check_sole(self, s: SiteSpec) -> np.ndarray:
        """A site's sole: at least 3 finite (x, y) corners spanning an area."""
        try:
            sole = np.array(s.sole, dtype=float)
        except (TypeError, ValueError):
            sole = np.zeros((0, 0))
        if sole.ndim != 2 or sole.shape[1] != 2 or len(sole) < 3 or not np.all(np.isfinite(sole)):
            self.fail(f"site {s.name!r}: sole must be at least 3 finite [x, y] corners [m], got {s.sole!r}")
        if len(convex_hull(sole)) < 3:
            self.fail(f"site {s.name!r}: sole corners {s.sole!r} lie on one line (no area)")
        sole.flags.writeable = False
        return sole

    def add_segments(self, segments: Sequence[SegmentSpec]) -> None:
        """Bones (start frame, end frame) of each segment; every end a joint or site."""
        seg_index: dict[str, int] = {}
        for seg in segments:
            if seg.name in seg_index:
                self.fail(f"duplicate segment name {show_value(seg.name)}")
            if not seg.ends:
                self.fail(f"segment {show_value(seg.name)} needs at least one end")
            for end in (seg.start, *seg.ends):
                if end not in self.index:
                    self.fail(f"segment {show_value(seg.name)}: {show_value(end)} is not a joint or site; joints: "
                              f"{choices(self.order)}; sites: {choices(self.site_names)}")
            for end in seg.ends:
                self.bones.append((self.index[seg.start], self.index[end]))
                self.bone_segment.append(len(seg_index))
            mass, com = float(seg.mass), float(seg.com)
            if not (math.isfinite(mass) and mass >= 0.0 and math.isfinite(com)):
                self.fail(f"segment {seg.name!r}: mass must be finite and >= 0 [kg] and com a finite fraction, "
                          f"got mass={seg.mass!r}, com={seg.com!r}")
            self.segment_mass.append(mass)
            self.segment_com.append(com)
            seg_index[seg.name] = len(seg_index)
        self.segment_names = list(seg_index)

    def set_effectors(self, effectors: Sequence[str]) -> None:
        """Effectors are sites, each listed once."""
        self.effectors = tuple(effectors)
        sites = set(self.site_names)
        for e in self.effectors:
            if e not in sites:
                self.fail(f"effector {show_value(e)} is not a site; sites: {choices(self.site_names)}")
        if len(set(self.effectors)) != len(self.effectors):
            self.fail(f"effectors are listed twice: {list(self.effectors)}")

    def set_root(self, root: str | None) -> None:
        """The IK root: a joint or site, the top joint by default."""
        self.root = self.order[0] if root is None else root
        if self.root not in self.index:
            self.fail(f"root {show_value(self.root)} is not a joint or site; sites: {choices(self.site_names)}")

    # --- runtime structure ---------------------------------------------------------------
    def arrays(self, name: str) -> dict:
        """The fields of :class:`~gsik.skeleton.Skeleton`: frozen structure-of-arrays from the checked tables."""
        order = self.order
        frames = _FrameRow(*zip(*self.frames))  # columns; a skeleton has at least one frame
        dofs = _DofRow(*(zip(*self.dofs) if self.dofs else ((),) * len(_DofRow._fields)))
        joint_row = {n: i for i, n in enumerate(order)}
        joint_parent = [-1 if self.by_name[n].parent is None else joint_row[self.by_name[n].parent] for n in order]
        return dict(
            name=name,
            root=self.root,
            frame_names=tuple(frames.name),
            frame_parent=frozen(frames.parent, np.int64),
            frame_offset=frozen(np.reshape(frames.offset, (-1, 3))),
            frame_rotation=frozen(np.reshape(frames.rotation, (-1, 3, 3))),
            frame_axis=frozen(np.reshape(frames.axis, (-1, 3))),
            frame_dof=frozen(frames.dof, np.int64),
            dof_names=tuple(dofs.name),
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
            segment_mass=frozen(self.segment_mass),
            segment_com=frozen(self.segment_com),
            soles=MappingProxyType(dict(self.soles)),
            source=self.source,
        )
