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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from gsik.balance import MassModel, mass_model
from gsik.errors import SkeletonError, choices, show_value
# The raw specs live with their builder; they are part of this module's API.
from gsik.skeleton_builder import AXES, JointSpec, RotationSpec, SegmentSpec, SiteSpec, SkeletonBuilder, check_reach


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
        segment_mass: (n_segments,) [kg] mass of each segment (0: none).
        segment_com: (n_segments,) where each segment's centre of mass lies
            along its first bone (0 at its start, 1 at its first end).
        soles: ``{site: corners (c, 2) [m]}`` of the feet's soles in their
            site frame's x-y plane (what balance stands on).
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
    segment_mass: np.ndarray
    segment_com: np.ndarray
    soles: Mapping[str, np.ndarray]
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

    @property
    def target_names(self) -> tuple[str, ...]:
        """Every name a target may aim at: the joints (their end frames) and the sites."""
        return self.joint_names + self.site_names

    @property
    def total_mass(self) -> float:
        """The body's mass [kg] (0 when the skeleton gives no segment masses)."""
        return float(self.segment_mass.sum())

    @cached_property
    def mass_model(self) -> MassModel:
        """Where the mass sits (:class:`gsik.balance.MassModel`), from the segments' masses at rest.

        Raises:
            SkeletonError: if a segment with mass is not fixed in one joint's frame.
        """
        from gsik.kinematics import world_frames

        R, p = world_frames(self, self.rest)
        try:
            return mass_model(self, self.segment_mass, self.segment_com, R, p)
        except SkeletonError as exc:
            raise SkeletonError(f"{self.source}: {exc}") from None

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

    @cached_property
    def _dof_index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self.dof_names)}

    def dof_index(self, name: str) -> int:
        """Index of a DOF by its name ``"joint.label"``."""
        try:
            return self._dof_index[name]
        except KeyError:
            raise SkeletonError(
                f"skeleton {self.name!r} has no degree of freedom {name!r}; valid: {choices(self.dof_names)}"
            ) from None

    @cached_property
    def ancestry(self) -> np.ndarray:
        """(n_frames, n_frames) bool: ``ancestry[a, f]`` if frame ``a`` is ``f`` or above it."""
        below = np.zeros((self.n_frames, self.n_frames), dtype=bool)  # below[f, a]: the transpose, row by row
        for f, parent in enumerate(self.frame_parent.tolist()):  # parents come first: one row copy per frame
            if parent >= 0:
                below[f] = below[parent]
            below[f, f] = True
        anc = np.ascontiguousarray(below.T)
        anc.flags.writeable = False
        return anc

    @cached_property
    def chain_length(self) -> np.ndarray:
        """(n_frames, n_frames) [m]: the length of the bones between two frames' origins along the tree, the
        farthest apart any pose can put them (each frame keeps its offset's length from its parent)."""
        bone = np.linalg.norm(self.frame_offset, axis=1)
        depth = self.ancestry.T.astype(float) @ np.where(self.frame_parent >= 0, bone, 0.0)  # from the top
        # The deepest frame above both is where their paths meet.
        common = self.ancestry[:, :, None] & self.ancestry[:, None, :]
        meet = np.max(np.where(common, depth[:, None, None], 0.0), axis=0)
        length = depth[:, None] + depth[None, :] - 2.0 * meet
        length.flags.writeable = False
        return length

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
        try:
            a = np.asarray(q, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise SkeletonError(f"joint angles must be numbers, got {show_value(q)}") from None
        if a.shape != (self.n_dofs,):
            raise SkeletonError(f"joint angles must have shape ({self.n_dofs},), got {a.shape}")
        if not np.all(np.isfinite(a)):
            bad = [self.dof_names[i] for i in np.flatnonzero(~np.isfinite(a))]
            raise SkeletonError(f"joint angles are not finite for {choices(bad)}")
        return a


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
            effectors, segment ends or root, negative masses, segments with
            mass that span a moving joint, soles without area, and skeletons beyond
            :data:`~gsik.skeleton_builder.MAX_DOFS` or :data:`~gsik.skeleton_builder.MAX_FRAMES`, or longer than
            :data:`~gsik.skeleton_builder.MAX_REACH`.
    """
    b = SkeletonBuilder(source)
    b.index_joints(joints)
    b.check_size(joints, sites)
    b.check_sites(sites)
    b.order_joints(joints, b.top_joint(joints))
    for jname in b.order:
        b.add_joint(b.by_name[jname])
    b.add_sites(sites)
    b.add_segments(segments)
    b.set_effectors(effectors)
    b.set_root(root)
    arrays = b.arrays(name)
    check_reach(arrays["frame_offset"], source)
    skeleton = Skeleton(**arrays)
    if skeleton.total_mass > 0.0:
        skeleton.mass_model  # every segment with a mass must be fixed in one frame: checked here, once
    return skeleton


__all__ = ["AXES", "JointSpec", "RotationSpec", "SegmentSpec", "SiteSpec", "Skeleton", "build_skeleton"]
