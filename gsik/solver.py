"""The IK solver: Projected Gauss-Seidel on the damped normal equations.

Each frame step linearises the effectors' errors at the current angles,
builds ``(J^T W J + delta I) dq = J^T W e`` and runs Gauss-Seidel sweeps on
it, clamping every unknown as it is updated so that ``q + dq`` stays within
the joint limits (Projected Gauss-Seidel, Kenwright 2012). The previous
frame's ``dq`` is the next frame's starting guess (warm start).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from gsik import _kernels
from gsik.errors import SolverError, TargetError, choices
from gsik.kinematics import Topology, model_arrays, topology
from gsik.rotations import matrix_from_rotvec, rotvec_from_matrix, transform
from gsik.skeleton import Skeleton
from gsik.targets import Target


class Status(enum.Enum):
    """How a step or a solve ended."""

    #: Every enabled effector is within the position and orientation tolerances.
    CONVERGED = "converged"
    #: Not converged, and the pose no longer changes: the best reach.
    STALLED = "stalled"
    #: The iteration budget ran out while the pose was still improving.
    BUDGET_EXHAUSTED = "budget exhausted"


#: The settings that turn the defaults into the paper's plain method: fixed delta, PGS sweeps only,
#: no step limit, no adaptive damping, no settling, no subspace minimisation.
PAPER_METHOD = MappingProxyType(dict(adaptive_damping=False, subspace_minimization=False, max_step=0.0,
                                     settle_tolerance=0.0))


@dataclass(frozen=True)
class SolverSettings:
    """Solver settings; every field is checked when the settings are made.

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
        max_step: Largest change of any one angle in one step [rad]; 0 for none.
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

    :meth:`paper` gives the paper's plain method.
        warm_start: Start each frame's sweeps from the previous frame's ``dq``.
        orientation_weight: Weight of orientation rows relative to position
            rows [m/rad].
        position_tolerance: Converged when every position error is below this [m].
        orientation_tolerance: ... and every orientation error below this [rad].
        max_iterations: Linearisations per attempt in :meth:`Solver.solve`.
        solve_sweeps: Gauss-Seidel sweeps per linearisation in :meth:`Solver.solve`.
        restarts: Further attempts :meth:`Solver.solve` makes when the first
            one does not converge (a continuation, then random restarts).
        seed: Seed of the random restarts, so solves are repeatable.
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
    warm_start: bool = True
    orientation_weight: float = 0.5
    position_tolerance: float = 1e-4
    orientation_tolerance: float = 1e-3
    max_iterations: int = 200
    solve_sweeps: int = 5
    restarts: int = 20
    seed: int = 0

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if f.type in ("bool",):
                if not isinstance(v, (bool, np.bool_)):
                    raise SolverError(f"setting {f.name} must be True or False, got {v!r}")
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise SolverError(f"setting {f.name} must be a number, got {v!r}")
            if not math.isfinite(v) or v < 0:
                raise SolverError(f"setting {f.name} must be finite and >= 0, got {v!r}")
            if f.type == "int" and int(v) != v:
                raise SolverError(f"setting {f.name} must be a whole number, got {v!r}")
        for name in ("sweeps", "max_iterations", "solve_sweeps"):
            if getattr(self, name) < 1:
                raise SolverError(f"setting {name} must be at least 1, got {getattr(self, name)!r}")
        if self.damping <= 0:
            raise SolverError(f"setting damping must be > 0 (it keeps J^T W J + delta I invertible), got {self.damping!r}")

    @classmethod
    def paper(cls, **overrides) -> SolverSettings:
        """Kenwright's plain method (:data:`PAPER_METHOD`): fixed delta, PGS sweeps only, no safeguards."""
        return cls(**{**PAPER_METHOD, **overrides})

    def vector(self, sweeps: int | None = None) -> np.ndarray:
        """The settings the kernels read, as a float vector."""
        v = np.zeros(_kernels.N_SETTINGS)
        v[_kernels.S_DAMPING] = self.damping
        v[_kernels.S_SWEEPS] = self.sweeps if sweeps is None else sweeps
        v[_kernels.S_RES_TOL] = self.residual_tolerance
        v[_kernels.S_UPD_TOL] = self.update_tolerance
        v[_kernels.S_STALL_TOL] = self.stall_tolerance
        v[_kernels.S_MAX_STEP] = self.max_step
        v[_kernels.S_ADAPTIVE] = float(self.adaptive_damping)
        v[_kernels.S_WARM] = float(self.warm_start)
        v[_kernels.S_POS_TOL] = self.position_tolerance
        v[_kernels.S_ORI_TOL] = self.orientation_tolerance
        v[_kernels.S_SETTLE_TOL] = self.settle_tolerance
        v[_kernels.S_SUBSPACE] = float(self.subspace_minimization)
        return v


def setting_names() -> tuple[str, ...]:
    """Names of every solver setting."""
    return tuple(f.name for f in fields(SolverSettings))


class SolveResult(NamedTuple):
    """What a step or a solve produced. Plain data; arrays are read-only copies.

    Attributes:
        q: Joint angles (n_dofs,) [rad] after the call.
        status: :class:`Status`.
        iterations: Gauss-Seidel sweeps of a step; linearisations of a solve.
        sweeps: Gauss-Seidel sweeps in all.
        residual: Projected ``|Ax - b|`` of the last sweep (a step), or the
            weighted squared error ``0.5 e^T W e`` (a solve).
        effector_names: (m,) effectors, in the order of the error arrays.
        position_errors: (m,) distance to each target [m] (0 without a target).
        orientation_errors: (m,) angle to each target orientation [rad] (0
            where the orientation is not used).
        step_norm: Size of the last change of ``q`` [rad].
        attempts: Attempts :meth:`Solver.solve` made (1 for a step).
    """

    q: np.ndarray
    status: Status
    iterations: int
    sweeps: int
    residual: float
    effector_names: tuple[str, ...]
    position_errors: np.ndarray
    orientation_errors: np.ndarray
    step_norm: float = 0.0
    attempts: int = 1

    @property
    def converged(self) -> bool:
        return self.status is Status.CONVERGED

    max_position_error = property(lambda self: max_position_error(self), doc="Largest position error [m].")
    max_orientation_error = property(lambda self: max_orientation_error(self),
                                     doc="Largest orientation error [rad].")

    def errors(self) -> dict[str, tuple[float, float]]:
        """``{effector: (position error [m], orientation error [rad])}``."""
        return errors_by_effector(self)


# Summaries of any result holding effector_names, position_errors and orientation_errors
# (NamedTuples cannot share a mixin, so the results share these functions).
def max_position_error(result) -> float:
    """Largest position error [m] of a result."""
    return float(result.position_errors.max(initial=0.0))


def max_orientation_error(result) -> float:
    """Largest orientation error [rad] of a result."""
    return float(result.orientation_errors.max(initial=0.0))


def errors_by_effector(result) -> dict[str, tuple[float, float]]:
    """``{effector: (position error [m], orientation error [rad])}`` of a result."""
    return {n: (float(p), float(o)) for n, p, o in zip(result.effector_names, result.position_errors,
                                                       result.orientation_errors)}


_STATUSES = (Status.CONVERGED, Status.STALLED, Status.BUDGET_EXHAUSTED)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a)
    a.flags.writeable = False
    return a


class Solver:
    """A stateful IK solver for one skeleton.

    The solver keeps the joint angles, the pinned root and the previous
    step between calls, so an interactive loop calls :meth:`step` once per
    frame and converges in a few sweeps when targets move a little.

    Args:
        skeleton: The skeleton; its ``root`` is the initial IK root.
        q0: Initial angles (n_dofs,) [rad]; default the rest pose.
        world_from_root: World transform (4, 4) of the root frame; default
            where the skeleton's definition places it at ``q0``.
        settings: A :class:`SolverSettings`; keyword arguments override fields.

    Example:
        >>> solver = Solver(load_skeleton("biped"), sweeps=5)
        >>> result = solver.step({"left_hand": Target([0.3, 0.3, 1.2])})
    """

    def __init__(self, skeleton: Skeleton, q0=None, world_from_root=None,
                 settings: SolverSettings | None = None, **overrides):
        if not isinstance(skeleton, Skeleton):
            raise SolverError(f"Solver needs a Skeleton (see gsik.load_skeleton), got {type(skeleton).__name__}")
        self._settings = self._make_settings(settings or SolverSettings(), overrides)
        self._skeleton = skeleton
        q = skeleton.rest.copy() if q0 is None else self._check_q(q0)
        self._q = np.ascontiguousarray(q, dtype=float)
        n_frames = skeleton.n_frames
        self._R = np.empty((n_frames, 3, 3))
        self._p = np.empty((n_frames, 3))
        if world_from_root is None:
            _kernels.forward_kinematics(*self._fk_args(-1, np.eye(4)), self._R, self._p)
            f = skeleton.frame_of(skeleton.root)
            world_from_root = transform(self._R[f], self._p[f])
        W = np.array(world_from_root, dtype=float)
        if W.shape != (4, 4) or not np.all(np.isfinite(W)):
            raise SolverError(f"world_from_root must be a finite (4, 4) transform, got shape {W.shape}")
        self._W = W
        self._targets: dict[str, Target] = {}
        self._args = None
        self._solve_vector_for = None
        self._x = np.zeros(skeleton.n_dofs)
        self._lam = np.array([self._settings.damping])
        self._set_topology(skeleton.root)

    # -- construction helpers -------------------------------------------------
    @staticmethod
    def _make_settings(base: SolverSettings, overrides: dict) -> SolverSettings:
        unknown = sorted(set(overrides) - set(setting_names()))
        if unknown:
            raise SolverError(f"unknown solver setting(s) {choices(unknown)}; valid: {choices(setting_names())}")
        return replace(base, **overrides) if overrides else base

    def _check_q(self, q) -> np.ndarray:
        q = self._skeleton.validate_q(q)
        sk = self._skeleton
        bad = np.flatnonzero((q < sk.lower - 1e-9) | (q > sk.upper + 1e-9))
        if bad.size:
            i = int(bad[0])
            raise SolverError(f"angle {sk.dof_names[i]} = {q[i]:.6g} rad is outside its limits "
                              f"[{sk.lower[i]:.6g}, {sk.upper[i]:.6g}]")
        return np.clip(q, sk.lower, sk.upper)

    def _fk_args(self, root_frame: int, W: np.ndarray, q: np.ndarray | None = None) -> tuple:
        sk = self._skeleton
        return (sk.frame_parent, sk.frame_offset, sk.frame_rotation, sk.frame_axis, sk.frame_dof,
                self._q if q is None else q, root_frame, W)

    def _set_topology(self, root: str) -> None:
        self._args = None
        self._skeleton = self._skeleton.with_root(root)
        self._topo: Topology = topology(self._skeleton, root)
        self._model = model_arrays(self._skeleton, self._topo)
        m = len(self._topo.effector_names)
        self._tp = np.zeros((m, 3))
        self._tR = np.tile(np.eye(3), (m, 1, 1))
        self._row_w = np.zeros((m, 6))
        # q and the errors live in one buffer so a result copies them at once.
        state = np.zeros(self._skeleton.n_dofs + 2 * m)
        state[: self._skeleton.n_dofs] = self._q
        self._state = state
        self._q = state[: self._skeleton.n_dofs]
        self._err = state[self._skeleton.n_dofs:].reshape(2, m)
        self._stats = np.zeros(_kernels.N_STATS)
        self._work = np.zeros(_kernels.workspace_size(self._skeleton.n_frames, self._skeleton.n_dofs, m))
        self._refresh_frames()
        self._pack_targets()

    def _refresh_frames(self) -> None:
        _kernels.forward_kinematics(*self._fk_args(self._topo.root_frame, self._W), self._R, self._p)

    def _pack_targets(self) -> None:
        ow = self._settings.orientation_weight
        self._row_w[:] = 0.0
        for k, name in enumerate(self._topo.effector_names):
            t = self._targets.get(name)
            if t is None:
                self._tp[k] = self._p[self._topo.effector_frame[k]]
                self._tR[k] = np.eye(3)
                continue
            self._tp[k] = t.position
            self._tR[k] = t.rotation
            self._row_w[k, :3] = t.weight
            if t.uses_orientation:
                self._row_w[k, 3:] = t.weight * ow

    # -- state ----------------------------------------------------------------
    @property
    def skeleton(self) -> Skeleton:
        """The skeleton, with ``root`` the current IK root."""
        return self._skeleton

    @property
    def settings(self) -> SolverSettings:
        return self._settings

    @property
    def q(self) -> np.ndarray:
        """A copy of the current joint angles (n_dofs,) [rad]."""
        return self._q.copy()

    @property
    def root(self) -> str:
        """Name of the current IK root."""
        return self._skeleton.root

    @property
    def effector_names(self) -> tuple[str, ...]:
        """The effectors for the current root: every effector site but the root."""
        return self._topo.effector_names

    @property
    def world_from_root(self) -> np.ndarray:
        """A copy of the pinned root's world transform (4, 4)."""
        return self._W.copy()

    @property
    def targets(self) -> dict[str, Target]:
        """The current targets (a new dict; targets themselves are immutable)."""
        return dict(self._targets)

    def configure(self, **changes) -> None:
        """Change settings by name (validated); unknown names raise :class:`SolverError`."""
        self._settings = self._make_settings(self._settings, changes)
        self._args = None
        self._lam[0] = self._settings.damping
        self._pack_targets()

    def set_q(self, q) -> None:
        """Set the joint angles (n_dofs,) [rad]; the root stays pinned where it is."""
        self._q[:] = self._check_q(q)
        self._x[:] = 0.0
        self._lam[0] = self._settings.damping
        self._refresh_frames()

    def reset(self) -> None:
        """Back to the rest pose, the root staying where it is; targets are kept."""
        self.set_q(self._skeleton.rest)

    def set_world_from_root(self, world_from_root) -> None:
        """Move the whole character: pin the root at a new world transform (4, 4)."""
        W = np.array(world_from_root, dtype=float)
        if W.shape != (4, 4) or not np.all(np.isfinite(W)):
            raise SolverError(f"world_from_root must be a finite (4, 4) transform, got shape {W.shape}")
        self._W = W
        self._args = None
        self._refresh_frames()

    def frame_transforms(self) -> np.ndarray:
        """World transforms (n_frames, 4, 4) of every frame at the current angles."""
        T = np.zeros((self._skeleton.n_frames, 4, 4))
        T[:, :3, :3] = self._R
        T[:, :3, 3] = self._p
        T[:, 3, 3] = 1.0
        return T

    def world_positions(self) -> np.ndarray:
        """World positions (n_frames, 3) [m] of every frame (a copy)."""
        return self._p.copy()

    def world_rotations(self) -> np.ndarray:
        """World rotations (n_frames, 3, 3) of every frame (a copy)."""
        return self._R.copy()

    def effector_poses(self) -> dict[str, np.ndarray]:
        """``{effector: world transform (4, 4)}`` of the current effectors, as achieved."""
        return {n: transform(self._R[f], self._p[f]) for n, f in zip(self._topo.effector_names,
                                                                      self._topo.effector_frame)}

    # -- targets --------------------------------------------------------------
    def set_targets(self, targets: Mapping[str, Target | None]) -> None:
        """Replace all targets. An effector with no target (``None``, or a disabled one) is free.

        Raises:
            TargetError: for a name that is not one of :attr:`effector_names`
                (the root cannot have a target) or a value that is not a
                :class:`Target`. Nothing changes when it raises.
        """
        checked = self._check_targets(targets)
        self._targets = checked
        self._pack_targets()

    def set_target(self, name: str, target: Target | None) -> None:
        """Set or (with ``None``) remove one effector's target."""
        checked = self._check_targets({name: target})
        self._targets.pop(name, None)
        self._targets.update(checked)
        self._pack_targets()

    def _check_targets(self, targets: Mapping[str, Target | None]) -> dict[str, Target]:
        if not isinstance(targets, Mapping):
            raise TargetError(f"targets must be a mapping of effector name to Target, got {type(targets).__name__}")
        out = {}
        for name, t in targets.items():
            if name not in self._topo.effector_names:
                extra = f" ({name!r} is the IK root)" if name == self.root else ""
                raise TargetError(f"no effector {name!r}{extra}; effectors: {choices(self._topo.effector_names)}")
            if t is None:
                continue
            if not isinstance(t, Target):
                raise TargetError(f"target for {name!r} must be a gsik.Target, got {type(t).__name__}")
            if t.enabled:  # a disabled target leaves its effector free, as no target does
                out[name] = t
        return out

    # -- solving --------------------------------------------------------------
    def step(self, targets: Mapping[str, Target | None] | None = None) -> SolveResult:
        """One frame: one linearisation and up to ``settings.sweeps`` PGS sweeps.

        ``targets`` (optional) replaces all targets first, as :meth:`set_targets`.
        """
        if targets is not None:
            self.set_targets(targets)
        _kernels.step(*(self._args or self._step_args()))
        return self._result(self._stats, _kernels.O_RESIDUAL, 1)

    def _step_args(self) -> tuple:
        """The arguments of :func:`gsik._kernels.step`: persistent arrays, so the tuple is built once."""
        if self._args is None:
            self._args = (self._model, self._topo.root_frame, self._W, self._tp, self._tR, self._row_w, self._q,
                          self._x, self._lam, self._settings.vector(), self._R, self._p, self._err, self._stats,
                          self._work)
        return self._args

    def _result(self, st: np.ndarray, residual_index: int, attempts: int) -> SolveResult:
        # q and the (2, m) errors share one buffer: one copy, three views the caller owns.
        out = self._state.copy()
        n, m = self._q.shape[0], self._err.shape[1]
        stats = st.tolist()
        return SolveResult(out[:n], _STATUSES[int(stats[_kernels.O_STATUS])], int(stats[_kernels.O_ITERATIONS]),
                           int(stats[_kernels.O_SWEEPS]), stats[residual_index], self._topo.effector_names,
                           out[n:n + m], out[n + m:], stats[_kernels.O_STEP_NORM], attempts)

    def solve(self, targets: Mapping[str, Target | None] | None = None, q0=None) -> SolveResult:
        """Solve to convergence (or best reach) from ``q0`` (default: the current angles).

        Levenberg-Marquardt over PGS steps (:func:`gsik._kernels.solve`). If
        that does not converge, up to ``settings.restarts`` more attempts:
        first a continuation (the targets approached in stages from the
        current effector poses), then random restarts inside the limits.
        The best attempt (lowest weighted error) is kept and becomes the
        solver's state.
        """
        if targets is not None:
            self.set_targets(targets)
        if q0 is not None:
            self.set_q(q0)
        s = self._settings
        start = self._q.copy()
        stats = self._solve_from(start)
        attempts = 1
        if stats[_kernels.O_STATUS] != _kernels.CONVERGED and s.restarts > 0:
            stats, attempts = self._restart(start, stats)
        self._x[:] = 0.0
        self._lam[0] = s.damping
        return self._result(stats, _kernels.O_COST, attempts)

    def _restart(self, start: np.ndarray, stats: np.ndarray) -> tuple[np.ndarray, int]:
        """Further attempts after a failed first one; leaves the best attempt as the state."""
        s = self._settings
        sk = self._skeleton
        best = (stats[_kernels.O_COST], self._q.copy(), stats)
        rng = np.random.default_rng(s.seed)
        attempts = 1
        while stats[_kernels.O_STATUS] != _kernels.CONVERGED and attempts <= s.restarts:
            if attempts == 1:
                stats = self._solve_by_continuation(start)
            else:
                # Random restarts: ever bolder blends of the start with a random pose within the limits.
                alpha = min(1.0, 0.25 * attempts)
                stats = self._solve_from(start + alpha * (rng.uniform(sk.lower, sk.upper) - start))
            attempts += 1
            if stats[_kernels.O_STATUS] == _kernels.CONVERGED or stats[_kernels.O_COST] < best[0]:
                best = (stats[_kernels.O_COST], self._q.copy(), stats)
        if best[2] is not stats:
            # An earlier attempt was best: make it the state again (frames and errors included).
            self._solve_from(best[1], iterations=0)
        return best[2], attempts

    def _solve_from(self, q0: np.ndarray, iterations: int | None = None) -> np.ndarray:
        s = self._settings
        if self._solve_vector_for is not s:
            self._solve_vector = s.vector(sweeps=s.solve_sweeps)
            self._solve_vector_for = s
        self._q[:] = np.clip(q0, self._skeleton.lower, self._skeleton.upper)
        stats = np.zeros(_kernels.N_STATS)
        _kernels.solve(self._model, self._topo.root_frame, self._W, self._tp, self._tR, self._row_w, self._q,
                       self._solve_vector, s.max_iterations if iterations is None else iterations,
                       self._R, self._p, self._err, stats, self._work)
        return stats

    def _solve_by_continuation(self, q0: np.ndarray, stages: int = 4) -> np.ndarray:
        """Approach the targets in ``stages`` from where the effectors are at ``q0``."""
        final_p, final_R = self._tp.copy(), self._tR.copy()
        self._q[:] = q0
        self._refresh_frames()
        start_p = self._p[self._topo.effector_frame].copy()
        start_R = self._R[self._topo.effector_frame].copy()
        sweeps_total = 0
        try:
            for k in range(1, stages):
                a = k / stages
                for i in range(len(final_p)):
                    self._tp[i] = (1 - a) * start_p[i] + a * final_p[i]
                    self._tR[i] = matrix_from_rotvec(a * rotvec_from_matrix(final_R[i] @ start_R[i].T)) @ start_R[i]
                sweeps_total += self._solve_from(self._q.copy())[_kernels.O_SWEEPS]
        finally:
            self._tp[:], self._tR[:] = final_p, final_R
        stats = self._solve_from(self._q.copy())
        stats[_kernels.O_SWEEPS] += sweeps_total
        return stats

    def set_root(self, name: str) -> None:
        """Make the joint or site ``name`` the IK root; the pose does not move.

        The new root is pinned at its current world transform. The old root,
        if it is an effector site, becomes an effector whose target is where it
        stands now (so a planted foot stays planted); the new root's target is
        dropped. Angles, limits and their meaning are unchanged.
        """
        new_frame = self._skeleton.frame_of(name)
        old = self.root
        if name == old:
            return
        old_frame = self._topo.root_frame
        W_new = transform(self._R[new_frame], self._p[new_frame])
        old_pose = transform(self._R[old_frame], self._p[old_frame])
        self._targets.pop(name, None)
        self._W = W_new
        self._set_topology(name)
        if old in self._topo.effector_names:
            self._targets[old] = Target.from_transform(old_pose)
            self._pack_targets()
        self._x[:] = 0.0
