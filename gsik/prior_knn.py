"""A target-conditioned pose prior: the Gaussian of the training poses whose targets are nearest the current ones.

A global Gaussian of every training pose says what poses are likely on
average; which pose is likely depends on where the hands and feet are. Given
targets, :class:`ConditionedPrior` finds the ``k`` training poses whose
targeted frames, placed relative to the solver's IK root, are nearest the
targets' positions (k nearest neighbours, Euclidean over the stacked
positions [m]), and makes their mean and covariance the posture (a local
Gaussian, as MGDM conditions a Gaussian on the target vector: Huang et al.
2017), still the solver's lowest priority level, so targets are met exactly.

The local covariance is the neighbours' sample covariance pulled towards the
global prior's covariance as a normal-inverse-Wishart posterior would, with
:data:`PRIOR_POSES` pseudo-poses of the global covariance (``k`` poses cannot
fill a 30 x 30 covariance on their own).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from gsik.errors import PriorError
from gsik.kinematics import world_frames
from gsik.prior import PosePrior, use_prior
from gsik.skeleton import Skeleton
from gsik.targets import Target

#: Neighbours a local Gaussian is taken from.
NEIGHBOURS = 64
#: Weight of the global covariance in the local one, in poses.
PRIOR_POSES = 30


@dataclass(eq=False)
class ConditionedPrior:
    """Training poses and the global prior they give; :meth:`local` conditions it on targets.

    Attributes:
        base: The global Gaussian of ``poses`` (its covariance is the local ones' anchor).
        poses: (m, n_dofs) training poses [rad], read-only.
        k: Neighbours per local Gaussian.
    """

    base: PosePrior
    poses: np.ndarray
    k: int = NEIGHBOURS
    _features: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        self.poses = np.array(self.poses, dtype=float)
        if self.poses.ndim != 2 or self.poses.shape[1] != len(self.base.dof_names) or len(self.poses) < self.k:
            raise PriorError(f"a conditioned prior needs at least k = {self.k} poses of "
                             f"{len(self.base.dof_names)} DOFs, got {self.poses.shape}")
        self.poses.flags.writeable = False

    def features(self, skeleton: Skeleton, root: str, names: tuple[str, ...]) -> np.ndarray:
        """(m, 3 len(names)) positions [m] of frames ``names`` of every training pose, ``root`` at the origin."""
        key = (root, names)
        if key not in self._features:
            frames = [skeleton.frame_of(n) for n in names]
            self._features[key] = np.array([world_frames(skeleton, q, np.eye(4), root)[1][frames].ravel()
                                            for q in self.poses])
        return self._features[key]

    def local(self, skeleton: Skeleton, root: str, world_from_root: np.ndarray,
              targets: Mapping[str, Target]) -> PosePrior:
        """The local Gaussian for the enabled ``targets`` (world positions) with ``root`` at ``world_from_root``."""
        names = tuple(sorted(n for n, t in targets.items() if t is not None and t.enabled))
        if not names:
            return self.base
        root_from_world = np.linalg.inv(world_from_root)
        x = np.concatenate([root_from_world[:3, :3] @ targets[n].position + root_from_world[:3, 3] for n in names])
        d = np.sum((self.features(skeleton, root, names) - x) ** 2, axis=1)
        near = self.poses[np.argpartition(d, self.k - 1)[:self.k]]
        mean = near.mean(axis=0)
        S = (near - mean).T @ (near - mean)
        cov = (S + PRIOR_POSES * self.base.covariance) / (self.k + PRIOR_POSES)
        return PosePrior(self.base.skeleton, self.base.dof_names, mean, 0.5 * (cov + cov.T), self.k,
                         self.base.shrinkage, self.base.source)

    def apply(self, solver, targets: Mapping[str, Target], strength: float = 1.0) -> PosePrior:
        """Make the local Gaussian for ``targets`` the solver's posture (:func:`gsik.prior.use_prior`); return it."""
        prior = self.local(solver.skeleton, solver.root, solver.world_from_root, targets)
        use_prior(solver, prior, strength)
        return prior
