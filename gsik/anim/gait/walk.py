"""Solving a gait plan frame by frame, warm-started, swapping the root at each plant."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from gsik.anim.gait.params import GAIT_SITES, WALK_SETTINGS, WALK_STEPS_PER_FRAME, GaitPlan, WalkParameters
from gsik.anim.gait.plan import plan_walk
from gsik import validate
from gsik.anim.motion import Motion
from gsik.errors import GaitError
from gsik.kinematics import world_frames
from gsik.skeleton import Skeleton
from gsik.solver import SolveResult, Solver, SolverSettings, Status


class WalkFrame(NamedTuple):
    """One solved frame of a walk.

    Attributes:
        index: Frame number.
        root: The IK root (the stance foot).
        world_from_root: (4, 4) world transform of the root.
        result: The last :class:`SolveResult` of the frame (its ``q`` is the pose).
        sweeps: Gauss-Seidel sweeps spent on the frame.
    """

    index: int
    root: str
    world_from_root: np.ndarray
    result: SolveResult
    sweeps: int


def walk_frames(solver: Solver, plan: GaitPlan, steps_per_frame: int = WALK_STEPS_PER_FRAME) -> Iterator[WalkFrame]:
    """Solve a plan frame by frame, warm-started; a generator, so a caller can stop at any frame.

    The solver is reset to the rest pose, placed as the skeleton's definition
    places it, with the plan's first root. After each yielded frame the solver
    holds that frame's pose, so stopping leaves it in a valid, editable state.

    Args:
        solver: A solver of the plan's skeleton (its settings are used as they are).
        plan: From :func:`plan_walk`.
        steps_per_frame: Solver steps (linearisations) per frame, >= 1.
    """
    validate.whole(steps_per_frame, "steps_per_frame", GaitError, 1)
    skeleton = solver.skeleton
    if skeleton.frame_names != plan.skeleton.frame_names:
        raise GaitError(f"the solver's skeleton {skeleton.name!r} is not the plan's {plan.skeleton.name!r}")
    R0, p0 = world_frames(skeleton, skeleton.rest)
    start_root = plan.roots[0]
    f = skeleton.frame_of(start_root)
    W0 = np.eye(4)
    W0[:3, :3], W0[:3, 3] = R0[f], p0[f]
    if solver.root != start_root:
        solver.set_root(start_root)
    solver.set_world_from_root(W0)
    solver.set_q(skeleton.rest)
    for i in range(plan.n_frames):
        if plan.roots[i] != solver.root:
            solver.set_root(plan.roots[i])
        solver.set_targets(plan.targets_at(i))
        sweeps = 0
        for _ in range(steps_per_frame):
            result = solver.step()
            sweeps += result.sweeps
            if result.status is Status.CONVERGED:
                break  # within tolerance: more steps this frame would change nothing
        yield WalkFrame(i, solver.root, solver.world_from_root, result, sweeps)


@dataclass(frozen=True, eq=False)
class WalkResult:
    """A solved walk.

    Attributes:
        plan: The target trajectories (:class:`GaitPlan`).
        motion: The walk as a :class:`gsik.anim.motion.Motion`.
        position_errors: (n_frames, 6) distance to each target of :data:`GAIT_SITES` [m]
            after the frame's solve (0 for the root foot, which is pinned).
        orientation_errors: (n_frames, 6) the same for orientations [rad].
        sweeps: (n_frames,) Gauss-Seidel sweeps per frame.
        statuses: (n_frames,) :class:`Status` of each frame's last step.
        steps_per_frame: Solver steps per frame.
    """

    plan: GaitPlan
    motion: Motion
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    sweeps: np.ndarray
    statuses: tuple[Status, ...]
    steps_per_frame: int


def walk(
    skeleton: Skeleton,
    params: WalkParameters | None = None,
    *,
    settings: SolverSettings | None = None,
    steps_per_frame: int = WALK_STEPS_PER_FRAME,
    progress: Callable[[int, int], None] | None = None,
    **overrides,
) -> WalkResult:
    """Generate a walk and solve it frame by frame.

    Args:
        skeleton: A skeleton with the sites of :data:`GAIT_SITES` (the biped).
        params: The walk; default :class:`WalkParameters()`.
        settings: Solver settings, default :data:`WALK_SETTINGS`; keyword
            ``overrides`` change fields of it (``sweeps=30``).
        steps_per_frame: Solver steps (linearisations) per frame.
        progress: Called as ``progress(frames_done, n_frames)`` after each frame.

    Raises:
        GaitError: bad parameters or a skeleton that cannot walk.
        SolverError: unknown or invalid solver settings.
    """
    plan = plan_walk(skeleton, params)
    solver = Solver(skeleton, settings=WALK_SETTINGS if settings is None else settings, **overrides)
    n = plan.n_frames
    q = np.empty((n, skeleton.n_dofs))
    W = np.empty((n, 4, 4))
    roots = []
    pos_err = np.zeros((n, len(GAIT_SITES)))
    ori_err = np.zeros((n, len(GAIT_SITES)))
    sweeps = np.zeros(n, dtype=np.int64)
    statuses = []
    col = {name: k for k, name in enumerate(GAIT_SITES)}
    for frame in walk_frames(solver, plan, steps_per_frame):
        i = frame.index
        q[i] = frame.result.q
        W[i] = frame.world_from_root
        roots.append(frame.root)
        for name, pe, oe in zip(frame.result.effector_names, frame.result.position_errors,
                                frame.result.orientation_errors):
            if name in col:
                pos_err[i, col[name]] = pe
                ori_err[i, col[name]] = oe
        sweeps[i] = frame.sweeps
        statuses.append(frame.result.status)
        if progress is not None:
            progress(i + 1, n)
    motion = Motion(skeleton, q, tuple(roots), W, plan.params.frame_time)
    for a in (pos_err, ori_err, sweeps):
        a.flags.writeable = False
    return WalkResult(plan, motion, pos_err, ori_err, sweeps, tuple(statuses), int(steps_per_frame))
