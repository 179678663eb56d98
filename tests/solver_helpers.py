"""Helpers shared by the solver tests (imported as a module: conftest names collide across folders)."""

from __future__ import annotations

import numpy as np

import gsik


def random_q(skeleton: gsik.Skeleton, rng: np.random.Generator) -> np.ndarray:
    """A pose drawn uniformly within the joint limits."""
    return rng.uniform(skeleton.lower, skeleton.upper)


def targets_at(skeleton: gsik.Skeleton, q: np.ndarray, world_from_root: np.ndarray) -> dict[str, gsik.Target]:
    """Full 6-DOF targets on every effector, where the effectors are at ``q``."""
    return {n: gsik.Target.from_transform(T) for n, T in skeleton.effector_poses(q, world_from_root).items()}
