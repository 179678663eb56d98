"""Running scenarios the way the interactive app does (Kenwright 2012, section IX.C).

:func:`run_scenario` starts from the rest pose and takes one warm-started
:meth:`Solver.step` per frame until the solver settles; then it keeps stepping
for a while and records the largest joint change (a settled pose must not
creep or oscillate) and whether any NaN appeared.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from gsik import validate
from gsik.anim.motion import Motion
from gsik.errors import ScenarioError
from gsik.kinematics import world_frames
from gsik.solver import (SolveResult, Solver, SolverSettings, Status, errors_by_effector, max_orientation_error,
                         max_position_error)

if TYPE_CHECKING:
    from gsik.anim.scenarios import Scenario


class ScenarioReport(NamedTuple):
    """How the solver did on one scenario (:func:`run_scenario`). Lengths [m], angles [rad].

    Attributes:
        name: The scenario.
        root: Its IK root.
        reachable: Whether its targets can be met.
        settled: The solver settled within the frame budget.
        settle_frames: Frames from the last target change to settling (``None`` if it did not).
        settle_sweeps: Gauss-Seidel sweeps spent until then (all frames, from the rest pose).
        reach_frames: Frames from the last target change until every effector is within
            :data:`REACH_TOLERANCE` (``None`` if never: always for an impossible scenario).
        status: :class:`Status` of the last frame.
        effector_names: (m,) the effectors, in the order of the error arrays.
        position_errors: (m,) final distance to each target.
        orientation_errors: (m,) final angle to each target orientation.
        tracking_error: Largest position error while the targets moved (0 for a held pose).
        hold_frames: Frames stepped from settling on (the quiet run and the hold).
        hold_max_dq: Largest change of any joint angle from one frame to the next after settling.
        hold_max_move: Largest world displacement of any joint from one frame to the next after settling.
        finite: No NaN or infinity in any frame.
        ms_per_frame: Mean wall time per frame [ms] (informative; machines differ).
        motion: Every frame of the run as a :class:`Motion`.
    """

    name: str
    root: str
    reachable: bool
    settled: bool
    settle_frames: int | None
    settle_sweeps: int
    reach_frames: int | None
    status: Status
    effector_names: tuple[str, ...]
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    tracking_error: float
    hold_frames: int
    hold_max_dq: float
    hold_max_move: float
    finite: bool
    ms_per_frame: float
    motion: Motion

    max_position_error = property(lambda self: max_position_error(self),
                                  doc="Largest final position error [m].")
    max_orientation_error = property(lambda self: max_orientation_error(self),
                                     doc="Largest final orientation error [rad].")

    def errors(self) -> dict[str, tuple[float, float]]:
        """``{effector: (position error [m], orientation error [rad])}``."""
        return errors_by_effector(self)


#: Step statuses that count as settled (nothing more to gain from stepping).
SETTLED = (Status.CONVERGED, Status.STALLED)
#: Settled steps in a row after which a run counts as settled: one stalled step (a refused step while the
#: damping adapts) can be followed by progress, so a single one is not the end. The studio uses the same rule.
QUIET_FRAMES = 10
#: "Visually there": every effector within 1 mm and 1 degree of its target.
REACH_TOLERANCE = (1e-3, math.radians(1.0))


def run_scenario(
    scenario: Scenario,
    settings: SolverSettings | None = None,
    *,
    max_frames: int = 600,
    hold_frames: int = 60,
    quiet_frames: int = QUIET_FRAMES,
    progress: Callable[[int, int], None] | None = None,
    **overrides,
) -> ScenarioReport:
    """Run a scenario like the interactive app: one warm-started step per frame from the rest pose.

    The targets are set at frame 0 (a jump from the rest pose, the hardest
    case) and follow the scenario's animation, if any. The solver has
    settled at the first frame that starts ``quiet_frames`` frames in a row
    whose step reports converged or stalled (best reach), counted from the
    last target change. It then keeps stepping ``hold_frames`` more frames,
    and the largest change of the pose from frame to frame over the quiet and
    hold frames is recorded: a stable solver keeps it at zero. A run that
    does not settle within ``max_frames`` is watched the same way over the
    frames that follow.

    Args:
        scenario: The scenario.
        settings: Solver settings (default :class:`SolverSettings()`);
            keyword ``overrides`` change fields of it.
        max_frames: Frame budget after the targets stop moving.
        hold_frames: Frames stepped after settling.
        quiet_frames: Consecutive settled frames that count as settled.
        progress: Called as ``progress(frames_done, frames_at_most)`` after each frame.

    Raises:
        ScenarioError: a frame count below 1.
        SolverError: bad solver settings.
    """
    for what, v in (("max_frames", max_frames), ("hold_frames", hold_frames), ("quiet_frames", quiet_frames)):
        validate.whole(v, what, ScenarioError, 1)
    solver = Solver(scenario.skeleton, world_from_root=scenario.world_from_root, settings=settings, **overrides)
    watch = _Watch(scenario.n_frames - 1, max_frames, quiet_frames, hold_frames)
    qs = [solver.q]  # qs[k + 1] is the pose after frame k
    sweeps = [0]
    start = time.perf_counter()
    i = 0
    while i < watch.limit:
        if i < scenario.n_frames:
            solver.set_targets(scenario.targets_at(i))
        result = solver.step()
        qs.append(result.q)
        sweeps.append(result.sweeps)
        watch.observe(i, result)
        i += 1
        if progress is not None:
            progress(i, watch.limit)
    ms_per_frame = 1e3 * (time.perf_counter() - start) / i
    return _report(scenario, watch, np.array(qs), sweeps, result, ms_per_frame)


class _Watch:
    """Follows a run frame by frame: tracking error, when it reaches, settles, and which frames to hold.

    Attributes:
        last_change: The frame of the last target change.
        limit: Frames to run at most (shrinks once the hold is known).
        tracking: Largest position error while the targets moved [m].
        reached_at: First frame within :data:`REACH_TOLERANCE` after the last change, or ``None``.
        settled_at: First frame of the quiet run, or ``None``.
        hold_from: The frame from which the pose is watched for changes, or ``None``.
    """

    def __init__(self, last_change: int, max_frames: int, quiet_frames: int, hold_frames: int) -> None:
        self.last_change = last_change
        self.max_frames, self.quiet_frames, self.hold_frames = max_frames, quiet_frames, hold_frames
        self.limit = last_change + max_frames + quiet_frames + hold_frames
        self.tracking = 0.0
        self.reached_at: int | None = None
        self.settled_at: int | None = None
        self.hold_from: int | None = None
        self.quiet = 0

    def observe(self, i: int, result) -> None:
        """Take in frame ``i``'s step result."""
        if i < self.last_change:
            self.tracking = max(self.tracking, result.max_position_error)
        elif self.hold_from is None:
            self._settle(i, result)

    def _settle(self, i: int, result) -> None:
        if self.reached_at is None and result.max_position_error <= REACH_TOLERANCE[0] \
                and result.max_orientation_error <= REACH_TOLERANCE[1]:
            self.reached_at = i
        self.quiet = self.quiet + 1 if result.status in SETTLED else 0
        if self.quiet == self.quiet_frames:
            self.settled_at = self.hold_from = i - self.quiet_frames + 1
        elif i - self.last_change + 1 >= self.max_frames:
            self.hold_from = i + 1 - self.quiet_frames  # never settled: watch the frames that follow all the same
        if self.hold_from is not None:
            self.limit = self.hold_from + self.quiet_frames + self.hold_frames


def _hold_move(scenario: Scenario, hold: np.ndarray, finite: bool) -> float:
    """Largest world displacement [m] of any joint or site from one held frame to the next."""
    if not finite:
        return math.inf
    if hold.shape[0] <= 1:
        return 0.0
    sk = scenario.skeleton
    points = np.concatenate([sk.joint_frame, sk.site_frame])
    P = np.stack([world_frames(sk, q, scenario.world_from_root, sk.root)[1][points] for q in hold])
    return float(np.linalg.norm(np.diff(P, axis=0), axis=2).max())


def _report(scenario: Scenario, watch: _Watch, Q: np.ndarray, sweeps: list[int], result: SolveResult,
            ms_per_frame: float) -> ScenarioReport:
    """The figures of a finished run: ``Q`` (n_frames + 1, n_dofs) [rad] holds the rest pose, then each frame."""
    sk = scenario.skeleton
    settled = watch.settled_at is not None
    hold = Q[watch.hold_from + 1:]
    finite = bool(np.all(np.isfinite(Q)))
    W = np.tile(scenario.world_from_root, (Q.shape[0], 1, 1))
    return ScenarioReport(
        name=scenario.name,
        root=sk.root,
        reachable=scenario.reachable,
        settled=settled,
        settle_frames=(watch.settled_at - watch.last_change) if settled else None,
        settle_sweeps=int(sum(sweeps[: watch.settled_at + 2])) if settled else int(sum(sweeps)),
        reach_frames=None if watch.reached_at is None else watch.reached_at - watch.last_change,
        status=result.status,
        effector_names=result.effector_names,
        position_errors=result.position_errors,
        orientation_errors=result.orientation_errors,
        tracking_error=float(watch.tracking),
        hold_frames=hold.shape[0],
        hold_max_dq=float(np.abs(np.diff(hold, axis=0)).max(initial=0.0)) if finite else math.inf,
        hold_max_move=_hold_move(scenario, hold, finite),
        finite=finite,
        ms_per_frame=ms_per_frame,
        motion=Motion(sk, Q, (sk.root,) * Q.shape[0], W, scenario.frame_time),
    )


def run_scenarios(scenarios: Sequence[Scenario], settings: SolverSettings | None = None,
                  progress: Callable[[int, int], None] | None = None, **kwargs) -> list[ScenarioReport]:
    """:func:`run_scenario` on each; ``progress(scenarios_done, n_scenarios)`` after each."""
    reports = []
    for k, s in enumerate(scenarios):
        reports.append(run_scenario(s, settings, **kwargs))
        if progress is not None:
            progress(k + 1, len(scenarios))
    return reports


def format_table(reports: Sequence[ScenarioReport]) -> str:
    """The reports as a plain-text table, one row per scenario."""
    header = ("scenario", "root", "status", "settled", "frames", "sweeps", "to 1 mm", "track mm", "pos err mm",
              "ori err deg", "max dq after rad", "max move after m", "NaN")
    rows = [header] + [_table_row(r) for r in reports]
    widths = [max(len(row[c]) for row in rows) for c in range(len(header))]
    lines = []
    for row in rows:
        cells = [cell.ljust(w) if c < 4 else cell.rjust(w) for c, (cell, w) in enumerate(zip(row, widths))]
        lines.append("  ".join(cells).rstrip())
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _dash_or(value) -> str:
    return "-" if value is None else str(value)


def _table_row(r: ScenarioReport) -> tuple[str, ...]:
    return (
        r.name,
        r.root,
        r.status.label,
        "yes" if r.settled else "NO",
        _dash_or(r.settle_frames),
        str(r.settle_sweeps),
        _dash_or(r.reach_frames),
        f"{r.tracking_error * 1e3:.2f}" if r.tracking_error else "-",
        f"{r.max_position_error * 1e3:.3f}",
        f"{math.degrees(r.max_orientation_error):.3f}",
        f"{r.hold_max_dq:.1e}",
        f"{r.hold_max_move:.1e}",
        "none" if r.finite else "YES",
    )


__all__ = ["REACH_TOLERANCE", "ScenarioReport", "format_table", "run_scenario", "run_scenarios"]
