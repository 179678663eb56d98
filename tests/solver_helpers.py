"""Helpers shared by the solver tests (imported as a module: conftest names collide across folders)."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

import gsik


def random_q(skeleton: gsik.Skeleton, rng: np.random.Generator) -> np.ndarray:
    """A pose drawn uniformly within the joint limits."""
    return rng.uniform(skeleton.lower, skeleton.upper)


def targets_at(skeleton: gsik.Skeleton, q: np.ndarray, world_from_root: np.ndarray) -> dict[str, gsik.Target]:
    """Full 6-DOF targets on every effector, where the effectors are at ``q``."""
    return {n: gsik.Target.from_transform(T) for n, T in skeleton.effector_poses(q, world_from_root).items()}


def studio_drag_targets(poses: dict[str, np.ndarray], frame: int, right_weight: float = 1.0) -> dict[str, gsik.Target]:
    """Frame ``frame`` of the studio's drag: pelvis and left foot pinned where ``poses`` (4, 4) put them, both hands
    at priority 1, position only, round a 0.1 m circle of 40 frames (the right hand's weight ``right_weight``)."""
    angle = 2.0 * np.pi * frame / 40
    targets = {n: gsik.Target.from_transform(poses[n]) for n in ("pelvis", "left_foot")}
    circle = 0.1 * np.array([np.cos(angle) - 1.0, 0.15, np.sin(angle)])
    for hand, weight in (("left_hand", 1.0), ("right_hand", right_weight)):
        targets[hand] = gsik.Target(poses[hand][:3, 3] + circle, position_only=True, priority=1, weight=weight)
    return targets


def studio_drag_solver(studio: bool) -> tuple[gsik.Solver, dict[str, np.ndarray]]:
    """``(solver, rest effector poses (4, 4))`` for :func:`studio_drag_targets`: the start pose as the posture, one
    tracking step, or (``studio``) the bundled prior with three."""
    from gsik.prior import bundled_prior, use_prior

    solver = gsik.Solver(gsik.load_skeleton("biped"), tracking_steps=3 if studio else 1)
    poses = solver.effector_poses()
    if studio:
        use_prior(solver, bundled_prior("biped"))
    else:
        solver.set_posture(solver.q)
    return solver, poses


def hard_level(draw, rng: np.random.Generator, m: int, n: int, error_scale: float = 1.0):
    """A random :class:`gsik.priority.Level` of ``m`` rows on ``n`` DOFs for a hypothesis strategy (``draw``): maybe
    a duplicated row or a zero row (rank-deficient), maybe DOFs it does not move."""
    from gsik.priority import Level

    J = rng.normal(size=(m, n))
    if m >= 2 and draw(st.booleans()):
        J[-1] = J[0]
    if m >= 1 and draw(st.booleans()):
        J[rng.integers(m)] = 0.0
    if draw(st.booleans()):
        J[:, rng.random(n) < 0.3] = 0.0
    return Level(J, rng.normal(size=m) * error_scale, rng.uniform(0.1, 2.0, size=m))
