"""Forward kinematics and the Jacobian, as pure functions of a skeleton and angles.

The IK root is a frame pinned to the world: ``world_from_root`` (4, 4). With
no root given the skeleton stands where its definition places it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gsik.kernels import KinematicModel
from gsik.kernels import kinematics as kernels
from gsik.kernels.kinematics import forward_kinematics

if TYPE_CHECKING:  # annotations only: the skeleton imports this module for its FK shortcuts
    from gsik.skeleton import Skeleton


@dataclass(frozen=True, eq=False)
class Topology:
    """Which DOFs move which effector, seen from one root. Read-only arrays.

    Attributes:
        root_frame: Frame index of the root.
        effector_names: (m,) effector names in row order.
        effector_frame: (m,) frame index of each effector.
        sign: (m, n_dofs) +1 / -1 / 0: how DOF ``d`` turns effector ``k`` as seen
            from the root (-1: the DOF lies between the root and the
            skeleton's top, so it turns the other way round).
        effector_dofs: (m, n_dofs) the DOFs with a non-zero sign, first
            ``effector_dof_count[k]`` entries valid.
        effector_dof_count: (m,).
    """

    root_frame: int
    effector_names: tuple[str, ...]
    effector_frame: np.ndarray
    sign: np.ndarray
    effector_dofs: np.ndarray
    effector_dof_count: np.ndarray


def topology(skeleton: Skeleton, root: str | None = None, effectors: Sequence[str] | None = None) -> Topology:
    """The :class:`Topology` of ``effectors`` (default: the root's effectors) seen from ``root``."""
    root = skeleton.root if root is None else root
    root_frame = skeleton.frame_of(root)
    if effectors is None:
        effectors = [n for n in skeleton.effector_sites if n != root]
    frames = np.array([skeleton.frame_of(n) for n in effectors], dtype=np.int64)
    anc = skeleton.ancestry[skeleton.dof_frame]  # (n_dofs, n_frames)
    sign = (anc[:, frames].astype(float) - anc[:, [root_frame]].astype(float)).T
    m, n = sign.shape
    dofs = np.zeros((m, n), dtype=np.int64)
    count = np.zeros(m, dtype=np.int64)
    for k in range(m):
        nz = np.flatnonzero(sign[k])
        dofs[k, : nz.size] = nz
        count[k] = nz.size
    for a in (frames, sign, dofs, count):
        a.flags.writeable = False
    return Topology(int(root_frame), tuple(effectors), frames, np.ascontiguousarray(sign), dofs, count)


def kinematic_model(skeleton: Skeleton, topo: Topology | None = None) -> KinematicModel:
    """The :class:`~gsik.kernels.KinematicModel` the kernels read: ``skeleton``'s arrays and ``topo``'s
    effectors (none without a topology: enough for forward kinematics)."""
    if topo is None:
        topo = _no_effectors(skeleton.n_dofs)
    return KinematicModel(skeleton.frame_parent, skeleton.frame_offset, skeleton.frame_rotation, skeleton.frame_axis,
                          skeleton.frame_dof, skeleton.dof_frame, skeleton.lower, skeleton.upper,
                          topo.effector_frame, topo.sign, topo.effector_dofs, topo.effector_dof_count)


def _no_effectors(n_dofs: int) -> Topology:
    arrays = (np.zeros(0, dtype=np.int64), np.zeros((0, n_dofs)), np.zeros((0, n_dofs), dtype=np.int64),
              np.zeros(0, dtype=np.int64))
    for a in arrays:
        a.flags.writeable = False  # the same array types as a real topology's: no second compilation
    return Topology(-1, (), *arrays)


def world_frames(
    skeleton: Skeleton, q: np.ndarray, world_from_root: np.ndarray | None = None, root: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations (n_frames, 3, 3) and positions (n_frames, 3) [m] for ``q`` (n_dofs,) [rad]."""
    q = skeleton.validate_q(q)
    R = np.empty((skeleton.n_frames, 3, 3))
    p = np.empty((skeleton.n_frames, 3))
    if world_from_root is None:
        root_frame, W = -1, np.eye(4)
    else:
        root_frame = skeleton.frame_of(skeleton.root if root is None else root)
        W = np.ascontiguousarray(world_from_root, dtype=float)
    forward_kinematics(kinematic_model(skeleton), q, root_frame, W, R, p)
    return R, p


def frame_transforms(skeleton: Skeleton, q: np.ndarray, world_from_root: np.ndarray | None = None) -> np.ndarray:
    """World transforms (n_frames, 4, 4) of every frame for ``q`` (n_dofs,) [rad]."""
    R, p = world_frames(skeleton, q, world_from_root)
    T = np.zeros((skeleton.n_frames, 4, 4))
    T[:, :3, :3] = R
    T[:, :3, 3] = p
    T[:, 3, 3] = 1.0
    return T


def jacobian(
    skeleton: Skeleton,
    q: np.ndarray,
    effectors: Sequence[str] | None = None,
    root: str | None = None,
    world_from_root: np.ndarray | None = None,
) -> np.ndarray:
    """Analytic Jacobian (6m, n_dofs) of the effectors' world poses, root pinned.

    Rows per effector: 3 position rows ``d p / d q`` [m/rad], then 3 rows of
    angular velocity ``d omega / d q`` [rad/rad] (world frame).
    """
    topo = topology(skeleton, root, effectors)
    if world_from_root is None:
        world_from_root = frame_transforms(skeleton, skeleton.validate_q(q))[topo.root_frame]
    R, p = world_frames(skeleton, q, world_from_root, root if root is not None else skeleton.root)
    J = np.empty((6 * len(topo.effector_names), skeleton.n_dofs))
    kernels.jacobian(kinematic_model(skeleton, topo), R, p, J)
    return J
