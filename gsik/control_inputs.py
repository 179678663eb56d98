"""What a :class:`gsik.control.Controller` is given: targets on frames, balance, a posture; and what a step did.

:func:`frame_tasks` packs a solver's targets, :func:`support` the feet that may carry the body, :func:`structure`
names what a controller is built for apart from the target values (equal keys retarget instead of rebuilding).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.balance import MassModel
from gsik.errors import SolverError


class FrameTask(NamedTuple):
    """A target on one frame, packed.

    Attributes:
        name: The joint or site name.
        frame: Its frame index.
        position: (3,) world target position [m].
        rotation: (3, 3) world target orientation.
        row_weight: (6,) weights of the 3 position and 3 orientation rows (0: unused).
        priority: Level; 0 is the most important.
    """

    name: str
    frame: int
    position: np.ndarray
    rotation: np.ndarray
    row_weight: np.ndarray
    priority: int


class Balance(NamedTuple):
    """What balance needs: the mass model and the feet that may carry the body.

    Attributes:
        mass: The :class:`~gsik.balance.MassModel`.
        feet: (k,) frame index of each foot that may support the body.
        soles: k sole polygons (c, 2) [m] in each foot frame's x-y plane.
    """

    mass: MassModel
    feet: tuple[int, ...]
    soles: tuple[np.ndarray, ...]


class Posture(NamedTuple):
    """The preferred pose ``reference`` (n_dofs,) [rad] and its precision: weights (n_dofs,) or (n_dofs, n_dofs)."""

    reference: np.ndarray
    precision: np.ndarray


class ControlStats(NamedTuple):
    """What a controller step did.

    Attributes:
        accepted: The step was kept.
        held: The pose is at rest: no level would change by more than the settle tolerance, or even the
            largest damping's step is refused (the studio's frame loop may idle).
        converged: Every target is within the position and orientation tolerances.
        cost: Weighted squared error ``0.5 e^T W e`` of the targets, all levels.
        step_norm: Size of the change of ``q`` [rad].
        lagging: A target is off by more than :data:`gsik.control.TRACKING_ERROR` times its tolerance.
    """

    accepted: bool
    held: bool
    converged: bool
    cost: float
    step_norm: float
    lagging: bool = False


def held_pose(q: np.ndarray, W: np.ndarray, damping: float, converged: bool, cost: float, lagging: bool) -> tuple:
    """What a controller keeps of a step that held the pose until the targets change (``Controller._held``):
    ``(q (n,) [rad] copied, world_from_root (4, 4) copied, damping, ControlStats)``; the stats those a step from
    there reports again (held, not accepted, step norm 0), made directly (no ``_replace``: a warm solve's call)."""
    return q.copy(), W.copy(), damping, tuple.__new__(ControlStats, (False, True, converged, cost, 0.0, lagging))


def _ordered(tasks) -> list[FrameTask]:
    """Tasks by priority, then name: one order for building and retargeting."""
    return sorted(tasks, key=lambda t: (t.priority, t.name))


def structure(skeleton, tasks, posture, balance, settings) -> tuple:
    """What a :class:`Controller` is built for, apart from the target values: equal keys can retarget."""
    return structure_of(skeleton.root, {t.name: t.priority for t in tasks}, posture, balance, settings)


def structure_of(root: str, priorities: dict, posture, balance, settings) -> tuple:
    """:func:`structure` from ``{target name: priority}``: no :class:`FrameTask` needs making to compare keys."""
    feet = None if balance is None else balance.feet
    return (root, tuple(sorted((p, n) for n, p in priorities.items())), id(posture), feet, id(settings))


def row_weights(target, orientation_weight: float) -> tuple[float, ...]:
    """The 6 row weights of a ``gsik.Target``: its weight on the position rows, scaled by ``orientation_weight`` on
    the orientation rows (0 for a position-only target)."""
    wp = target.weight
    wo = wp * orientation_weight if target.uses_orientation else 0.0
    return (wp, wp, wp, wo, wo, wo)


def frame_tasks(skeleton, targets, orientation_weight: float) -> list[FrameTask]:
    """The :class:`FrameTask` of each ``{name: gsik.Target}``."""
    tasks = []
    for name, t in targets.items():
        w = np.array(row_weights(t, orientation_weight), dtype=float)
        tasks.append(FrameTask(name, skeleton.frame_of(name), t.position, t.rotation, w, t.priority))
    return tasks


#: A target lags while it is off by more than this many times its tolerance (1 mm, 0.01 rad at the defaults): with
#: ``settings.tracking_steps`` above 1 a ``Solver.step()`` then linearises again. Measured on bench_drag's studio
#: default (pins and the bundled prior, hands dragged 6 mm a frame round a circle): one linearisation a frame kept
#: both hands within 1 mm in 243 of 300 frames (the posture's move, flat only to first order, leaves them up to
#: 7 mm off), up to three in 300 (a third of the frames take two).
TRACKING_ERROR = 10.0
#: ... for the first level's targets when a lower level holds targets (pins above dragged hands): constraints, they
#: lag beyond their tolerance (at 10 the studio's dragged pinned foot stayed 0.04-0.12 mm off in 190 of 300 frames).
CONSTRAINT_TRACKING_ERROR = 1.0


def lag_factors(task_level: np.ndarray) -> np.ndarray:
    """(m,) each task's lag threshold over its tolerance, from its level (m,) int: :data:`CONSTRAINT_TRACKING_ERROR`
    on the first level when a lower level holds targets, else :data:`TRACKING_ERROR`."""
    constraint = (task_level == 0) & (task_level.max(initial=0) > 0)
    return np.where(constraint, CONSTRAINT_TRACKING_ERROR, TRACKING_ERROR)


#: A foot whose target is within this height [m] of the standing foot is on the ground too.
GROUND_TOLERANCE = 0.01


def support(skeleton, targets, p: np.ndarray) -> Balance:
    """The :class:`Balance` of ``skeleton`` seen from its root: the root foot, and every other foot with a
    sole whose target is on the ground (the root foot's height); ``p`` (n_frames, 3) the world positions [m]."""
    if skeleton.total_mass <= 0.0:
        raise SolverError(f"balance needs segment masses; skeleton {skeleton.name!r} gives none "
                          "(see skeletons/README.md: segments' mass)")
    ground = p[skeleton.frame_of(skeleton.root)][2] if skeleton.root in skeleton.soles else 0.0
    feet = [n for n in skeleton.soles if n == skeleton.root
            or (n in targets and abs(targets[n].position[2] - ground) <= GROUND_TOLERANCE)]
    return Balance(skeleton.mass_model, tuple(skeleton.frame_of(n) for n in feet),
                   tuple(skeleton.soles[n] for n in feet))
