"""Solver settings: every field checked once, when the settings are made."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from numbers import Integral, Real
from types import MappingProxyType

import numpy as np

from gsik.errors import SolverError, show_value
from gsik.kernels import KernelSettings


#: The settings that turn the defaults into the paper's plain method, in :meth:`Solver.step` and
#: :meth:`Solver.solve` alike: fixed delta, PGS sweeps only, no step limit, no adaptive damping, no settling,
#: no subspace minimisation, all rows from the start.
PAPER_METHOD = MappingProxyType(dict(adaptive_damping=False, subspace_minimization=False, max_step=0.0,
                                     settle_tolerance=0.0, positions_first=False, solve_max_step=0.0,
                                     posture_tolerance=0.0))


#: Largest value of each whole-number setting: far above any useful value, low enough that every call ends soon
#: (a compiled loop cannot be interrupted, and NumPy's integers stop at int64).
MAX_COUNTS = MappingProxyType(dict(sweeps=10_000, solve_sweeps=10_000, max_iterations=10_000, restarts=1_000,
                                   seed=2**63 - 1, tracking_steps=100))

#: Largest value of a real-valued setting (weights, tolerances, damping, step): beyond it products overflow.
MAX_SETTING = 1e6


@dataclass(frozen=True)
class SolverSettings:
    """Solver settings; every field is checked when the settings are made.

    Every setting reaches both :meth:`Solver.step` and :meth:`Solver.solve`,
    except ``sweeps``, ``max_step`` and ``tracking_steps`` (a step's; a solve's linearisations
    use ``solve_sweeps`` and ``solve_max_step``) and ``positions_first``, ``posture_tolerance``
    and ``max_iterations`` to ``seed``, which only a solve reads. ``residual_tolerance`` and
    ``update_tolerance`` end the PGS sweeps; with ``subspace_minimization``
    each linear system is solved exactly instead, in a step as in a solve.

    Attributes:
        damping: delta, added to the diagonal of ``J^T W J`` (paper: 0.001).
        sweeps: Gauss-Seidel sweeps per step (test 1, the iteration limit).
        residual_tolerance: Stop sweeping when the projected ``|Ax - b|`` is
            below this (test 2); 0 disables.
        update_tolerance: Stop sweeping when a sweep changes ``dq`` by less
            than this [rad] (test 3); 0 disables.
        stall_tolerance: Stop sweeping when ``dq`` equals the previous
            frame's within this [rad] (test 4); 0 disables. Also the step size
            [rad] below which a pose counts as no longer changing.
        max_step: Largest change of any one angle in one frame step [rad]; 0
            for none: it keeps an interactive drag smooth.
        adaptive_damping: Halve or refuse a step that raises the error and
            raise the damping (Levenberg-Marquardt); while steps succeed the
            damping falls, down to ``damping / 10``. Off gives the paper's
            plain fixed-delta method.
        settle_tolerance: With adaptive damping, a step that lowers the
            weighted error by less than this fraction is not taken: the pose
            is held as the best reach instead of creeping (also ends
            :meth:`Solver.solve` attempts). 0 disables.
        subspace_minimization: After the PGS sweeps, solve the unknowns that
            are not on a limit exactly (Cholesky) and project: each step
            then solves its linear system exactly, where the paper's few
            sweeps solve it roughly. Off is the paper's method.
        positions_first: Each :meth:`Solver.solve` attempt first meets the
            effector positions (orientation rows off), then all rows; again
            from where that stalls while it lowers the error. It steers the
            solve away from poses the joint limits trap (see
            :mod:`gsik.kernels.solve`). With priorities, posture or balance
            the first prioritised steps of each attempt go for the positions
            alone. Off is the paper's method. A step ignores it: a frame goes
            straight for every row; so does a solve on a skeleton with one
            effector (a single arm or leg), where going for every row at
            once took fewer linearisations (bench_peers' 7-DOF arm: 9.5
            against 12.5, 6-DOF leg: 6 against 11, medians).
        tracking_steps: Most prioritised steps (linearisations) one :meth:`Solver.step` makes with priorities,
            posture or balance: another while the last was taken and left a target off by more than
            :data:`gsik.control.TRACKING_ERROR` times its tolerance (a first-level target above lower levels'
            targets, a pin: more than its tolerance), so a dragged target keeps up (the studio's default is 3). 1: one
            linearisation a step, as the single level's.
        posture_tolerance: A :meth:`Solver.solve` attempt with a posture (and no balance) ends at a step that
            starts and ends with every target within its tolerances and whose estimate of the posture's change still
            to come (its Gauss-Newton step) is at most this on every DOF [rad]; its steps take the share of the
            posture's step that a secant along the last two moves calls for (:class:`gsik.stall.PostureSettle`),
            and with a full posture (the learned prior) they learn the targets' curvature
            (:mod:`gsik.kernels.curvature`). 0 disables all three: the attempt goes on until a step gains less than
            ``settle_tolerance`` or the stall window ends it. :meth:`Solver.step` ignores it.
        warm_start: Start each frame's sweeps from the previous frame's ``dq``
            (in a solve, each linearisation's from the last step taken).
        orientation_weight: Weight of orientation rows relative to position
            rows [m/rad].
        position_tolerance: Converged when every position error is below this [m].
        orientation_tolerance: ... and every orientation error below this [rad].
        max_iterations: Linearisations per attempt in :meth:`Solver.solve`.
        solve_sweeps: Gauss-Seidel sweeps per linearisation in :meth:`Solver.solve`.
        solve_max_step: Largest change of any one angle in one linearisation
            of :meth:`Solver.solve` [rad]; 0 for none (the adaptive damping
            bounds the steps). A larger step is scaled down as a whole. The
            step() bound of 0.25 rad here gave the first attempt 58-60% reach
            instead of 61% (500 poses), and more linearisations.
        restarts: Further attempts :meth:`Solver.solve` makes when the first
            one does not converge (a continuation, then random restarts).
        seed: Seed of the random restarts, so solves are repeatable.

    :meth:`paper` gives the paper's plain method. Every field is stored as a Python ``bool``, ``int`` or
    ``float`` (a NumPy scalar is converted), whole numbers at most :data:`MAX_COUNTS`, reals at most
    :data:`MAX_SETTING`.
    """

    damping: float = 1e-3
    sweeps: int = 10
    residual_tolerance: float = 1e-10
    update_tolerance: float = 1e-10
    stall_tolerance: float = 1e-9
    max_step: float = 0.25
    adaptive_damping: bool = True
    settle_tolerance: float = 1e-6
    subspace_minimization: bool = True
    positions_first: bool = True
    warm_start: bool = True
    orientation_weight: float = 0.5
    position_tolerance: float = 1e-4
    orientation_tolerance: float = 1e-3
    max_iterations: int = 200
    solve_sweeps: int = 5
    solve_max_step: float = 0.0
    restarts: int = 20
    seed: int = 0
    tracking_steps: int = 1
    posture_tolerance: float = 1e-3

    def __post_init__(self):
        for f in fields(self):
            object.__setattr__(self, f.name, _check_setting(f.name, f.type, getattr(self, f.name)))
        for name in ("sweeps", "max_iterations", "solve_sweeps", "tracking_steps"):
            if getattr(self, name) < 1:
                raise SolverError(f"setting {name} must be at least 1, got {getattr(self, name)!r}")
        if self.damping <= 0:
            raise SolverError(f"setting damping must be > 0 (it keeps J^T W J + delta I invertible), "
                              f"got {self.damping!r}")

    @classmethod
    def paper(cls, **overrides) -> SolverSettings:
        """Kenwright's plain method (:data:`PAPER_METHOD`): fixed delta, PGS sweeps only, no safeguards."""
        return cls(**{**PAPER_METHOD, **overrides})

    def kernel_settings(self, for_solve: bool = False) -> KernelSettings:
        """The settings the kernels read: a step's, or (``for_solve``) a solve's sweeps and step bound."""
        return KernelSettings(
            damping=float(self.damping), sweeps=int(self.solve_sweeps if for_solve else self.sweeps),
            residual_tolerance=float(self.residual_tolerance), update_tolerance=float(self.update_tolerance),
            stall_tolerance=float(self.stall_tolerance),
            max_step=float(self.solve_max_step if for_solve else self.max_step),
            adaptive_damping=bool(self.adaptive_damping), warm_start=bool(self.warm_start),
            position_tolerance=float(self.position_tolerance), orientation_tolerance=float(self.orientation_tolerance),
            settle_tolerance=float(self.settle_tolerance), subspace_minimization=bool(self.subspace_minimization),
            positions_first=bool(self.positions_first),
        )


def _check_setting(name: str, kind: str, v):
    """One field as a Python value: a bool, or a finite number in [0, its maximum] (whole for an int)."""
    if kind == "bool":
        if not isinstance(v, (bool, np.bool_)):
            raise SolverError(f"setting {name} must be True or False, got {show_value(v)}")
        return bool(v)
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, Real):
        raise SolverError(f"setting {name} must be a number, got {show_value(v)}")
    return _check_count(name, v) if kind == "int" else _check_real(name, v)


def _check_count(name: str, v: Real) -> int:
    """A count setting: a whole number in [0, its maximum in :data:`MAX_COUNTS`]."""
    if not (isinstance(v, Integral) or float(v).is_integer()):
        raise SolverError(f"setting {name} must be a whole number, got {show_value(v)}")
    top = MAX_COUNTS[name]
    if not 0 <= v <= top:
        raise SolverError(f"setting {name} must be between 0 and {top:,}, got {show_value(v)}")
    return int(v)


def _check_real(name: str, v: Real) -> float:
    """A real setting: finite, in [0, :data:`MAX_SETTING`]."""
    try:
        x = float(v)
    except OverflowError:  # an integer beyond float's range
        x = math.inf
    if not 0.0 <= x <= MAX_SETTING:  # NaN fails too
        raise SolverError(f"setting {name} must be finite and >= 0 (at most {MAX_SETTING:g}), got {show_value(v)}")
    return x


def setting_names() -> tuple[str, ...]:
    """Names of every solver setting."""
    return tuple(f.name for f in fields(SolverSettings))
