"""The IK solver: Projected Gauss-Seidel on the damped normal equations.

Each frame step linearises the effectors' errors at the current angles,
builds ``(J^T W J + delta I) dq = J^T W e`` and runs Gauss-Seidel sweeps on
it, clamping every unknown as it is updated so that ``q + dq`` stays within
the joint limits (Projected Gauss-Seidel, Kenwright 2012). The previous
frame's ``dq`` is the next frame's starting guess (warm start).
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from dataclasses import replace
from typing import NamedTuple

import numpy as np

from gsik import control, kernels
from gsik.balance import center_of_mass
from gsik.errors import SolverError, TargetError, choices
from gsik.kernels import O_COST, O_ITERATIONS, O_RESIDUAL, O_STATUS, O_STEP_NORM, O_SWEEPS, TargetArrays
from gsik.kernels import step as step_kernels
from gsik.kernels.kinematics import forward_kinematics
from gsik.kinematics import Topology, kinematic_model, topology
from gsik.rotations import matrix_from_rotvec, rotvec_from_matrix, transform
from gsik.skeleton import Skeleton
from gsik.settings import PAPER_METHOD, SolverSettings, setting_names
from gsik.targets import Target

__all__ = ["PAPER_METHOD", "SolveResult", "Solver", "SolverSettings", "Status", "setting_names"]


class Status(enum.IntEnum):
    """How a step or a solve ended; the values are the kernels' status codes."""

    #: Every enabled effector is within the position and orientation tolerances.
    CONVERGED = kernels.CONVERGED
    #: Not converged, and the pose no longer changes: the best reach.
    STALLED = kernels.STALLED
    #: The iteration budget ran out while the pose was still improving.
    BUDGET_EXHAUSTED = kernels.BUDGET_EXHAUSTED

    @property
    def label(self) -> str:
        """Words for people: "converged", "stalled", "budget exhausted"."""
        return self.name.lower().replace("_", " ")


_STATUSES = tuple(Status)  # by code: a tuple index costs less than Status(code)


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
        if world_from_root is None:
            R = np.empty((skeleton.n_frames, 3, 3))
            p = np.empty((skeleton.n_frames, 3))
            forward_kinematics(kinematic_model(skeleton), np.ascontiguousarray(q, dtype=float), -1, np.eye(4), R, p)
            f = skeleton.frame_of(skeleton.root)
            world_from_root = transform(R[f], p[f])
        self._W = self._check_world_from_root(world_from_root)
        self._targets: dict[str, Target] = {}
        self._posture: control.Posture | None = None
        self._balance = False
        self._controller: control.Controller | None = None  # None: to be made (or retargeted) before use
        self._last_controller: control.Controller | None = None
        self._set_topology(skeleton.root, q, self._settings.damping)

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

    @staticmethod
    def _check_world_from_root(world_from_root) -> np.ndarray:
        W = np.array(world_from_root, dtype=float)
        if W.shape != (4, 4) or not np.all(np.isfinite(W)):
            raise SolverError(f"world_from_root must be a finite (4, 4) transform, got shape {W.shape}")
        return W

    def _set_topology(self, root: str, q: np.ndarray, lam: float) -> None:
        """Model, targets and workspace for ``root``, at angles ``q`` [rad]; ``lam`` the damping carried over."""
        self._skeleton = self._skeleton.with_root(root)
        self._topo: Topology = topology(self._skeleton, root)
        self._model = kinematic_model(self._skeleton, self._topo)
        sk = self._skeleton
        m = len(self._topo.effector_names)
        self._packed = TargetArrays(np.zeros((m, 3)), np.tile(np.eye(3), (m, 1, 1)), np.zeros((m, 6)))
        # q and the errors live in one buffer so a result copies them at once.
        self._state = np.zeros(sk.n_dofs + 2 * m)
        self._q = self._state[: sk.n_dofs]
        self._q[:] = q
        self._ws = kernels.make_workspace(sk.n_frames, sk.n_dofs, m, err=self._state[sk.n_dofs:].reshape(2, m))
        self._ws.lam[0] = lam
        self._inputs = None
        self._refresh_frames()
        self._pack_targets()

    def _refresh_frames(self) -> None:
        forward_kinematics(self._model, self._q, self._topo.root_frame, self._W, self._ws.R, self._ws.p)

    def _pack_targets(self) -> None:
        self._controller = None
        self._is_controlled = self._posture is not None or self._balance or self._controlled_targets()
        ow = self._settings.orientation_weight
        tp, tR, row_w = self._packed
        row_w[:] = 0.0
        for k, name in enumerate(self._topo.effector_names):
            t = self._targets.get(name)
            if t is None:
                tp[k] = self._ws.p[self._topo.effector_frame[k]]
                tR[k] = np.eye(3)
                continue
            tp[k] = t.position
            tR[k] = t.rotation
            row_w[k, :3] = t.weight
            if t.uses_orientation:
                row_w[k, 3:] = t.weight * ow

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
    def target_names(self) -> tuple[str, ...]:
        """Every name a target may aim at: the effectors first, then the other joints and sites (not the root)."""
        rest = (n for n in self._skeleton.target_names if n not in self._topo.effector_names and n != self.root)
        return self._topo.effector_names + tuple(rest)

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
        self._inputs = None
        self._ws.lam[0] = self._settings.damping
        self._pack_targets()

    def set_q(self, q) -> None:
        """Set the joint angles (n_dofs,) [rad]; the root stays pinned where it is."""
        self._q[:] = self._check_q(q)
        self._ws.x[:] = 0.0
        self._ws.lam[0] = self._settings.damping
        self._refresh_frames()

    def reset(self) -> None:
        """Back to the rest pose, the root staying where it is; targets are kept."""
        self.set_q(self._skeleton.rest)

    def set_world_from_root(self, world_from_root) -> None:
        """Move the whole character: pin the root at a new world transform (4, 4)."""
        self._W[:] = self._check_world_from_root(world_from_root)  # in place: the kernel inputs hold it
        self._refresh_frames()

    def frame_transforms(self) -> np.ndarray:
        """World transforms (n_frames, 4, 4) of every frame at the current angles."""
        T = np.zeros((self._skeleton.n_frames, 4, 4))
        T[:, :3, :3] = self._ws.R
        T[:, :3, 3] = self._ws.p
        T[:, 3, 3] = 1.0
        return T

    def world_positions(self) -> np.ndarray:
        """World positions (n_frames, 3) [m] of every frame (a copy)."""
        return self._ws.p.copy()

    def world_rotations(self) -> np.ndarray:
        """World rotations (n_frames, 3, 3) of every frame (a copy)."""
        return self._ws.R.copy()

    def effector_poses(self) -> dict[str, np.ndarray]:
        """``{effector: world transform (4, 4)}`` of the current effectors, as achieved."""
        return {n: transform(self._ws.R[f], self._ws.p[f]) for n, f in zip(self._topo.effector_names,
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

    @property
    def _target_frames(self) -> frozenset:
        return frozenset(self._skeleton.target_names)

    def _check_targets(self, targets: Mapping[str, Target | None]) -> dict[str, Target]:
        if not isinstance(targets, Mapping):
            raise TargetError(f"targets must be a mapping of effector name to Target, got {type(targets).__name__}")
        out = {}
        for name, t in targets.items():
            if name not in self._topo.effector_names and (name == self.root or name not in self._target_frames):
                extra = f" ({name!r} is the IK root)" if name == self.root else ""
                others = [n for n in self.target_names if n not in self._topo.effector_names]
                raise TargetError(f"no effector {name!r}{extra}; effectors: {choices(self._topo.effector_names)}; "
                                  f"other joints and sites: {choices(others)}")
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
        if self._is_controlled:
            return self._control_step()
        step, inputs = self._inputs or self._kernel_inputs()
        step(*inputs)
        return self._result(self._ws.stats, O_RESIDUAL, 1)

    def _kernel_inputs(self) -> tuple:
        """``(step kernel, its arguments)``: persistent arrays, so this is built once per configuration."""
        inputs = (self._model, self._settings.kernel_settings(), self._packed, self._topo.root_frame, self._W,
                  self._q, self._ws)
        self._inputs = (kernels.compiled_entry(step_kernels.step, *inputs), inputs)
        return self._inputs

    def _result(self, st: np.ndarray, residual_index: int, attempts: int) -> SolveResult:
        # q and the (2, m) errors share one buffer: one copy, three views the caller owns.
        out = self._state.copy()
        n, m = self._q.shape[0], len(self._topo.effector_names)
        stats = st.tolist()
        return SolveResult(out[:n], _STATUSES[int(stats[O_STATUS])], int(stats[O_ITERATIONS]), int(stats[O_SWEEPS]),
                           stats[residual_index], self._topo.effector_names, out[n:n + m], out[n + m:],
                           stats[O_STEP_NORM], attempts)

    def solve(self, targets: Mapping[str, Target | None] | None = None, q0=None) -> SolveResult:
        """Solve to convergence (or best reach) from ``q0`` (default: the current angles).

        Levenberg-Marquardt over PGS steps (:func:`gsik.kernels.step.solve`). If
        that does not converge, up to ``settings.restarts`` more attempts:
        first a continuation (the targets approached in stages from the
        current effector poses), then random restarts inside the limits.
        The best attempt (lowest weighted error) is kept and becomes the
        solver's state. With priorities, posture or balance each attempt runs
        prioritised steps until the pose holds (:mod:`gsik.control`),
        attempts are compared level by level, and the first further attempt
        starts from the posture; a converged attempt whose posture is not met
        is compared with one from the posture too, as the targets may be met
        on another branch nearer to it.
        """
        if targets is not None:
            self.set_targets(targets)
        if q0 is not None:
            self.set_q(q0)
        s = self._settings
        start = self._q.copy()
        stats = self._solve_from(start)
        attempts = 1
        if stats[O_STATUS] != Status.CONVERGED and s.restarts > 0:
            stats, attempts = self._restart(start, stats)
        elif s.restarts > 0 and self._posture is not None and self._attempt_rank(stats)[-1] > 0.0:
            stats, attempts = self._posture_attempt(stats)
        self._ws.x[:] = 0.0
        self._ws.lam[0] = s.damping
        if self._is_controlled:
            return self._control_result(_STATUSES[int(stats[O_STATUS])], int(stats[O_ITERATIONS]),
                                        float(stats[O_COST]), float(stats[O_STEP_NORM]), attempts)
        return self._result(stats, O_COST, attempts)

    def _restart(self, start: np.ndarray, stats: np.ndarray) -> tuple[np.ndarray, int]:
        """Further attempts after a failed first one; leaves the best attempt as the state."""
        s = self._settings
        sk = self._skeleton
        best = (self._attempt_rank(stats), self._q.copy(), stats)
        rng = np.random.default_rng(s.seed)
        attempts = 1
        while stats[O_STATUS] != Status.CONVERGED and attempts <= s.restarts:
            if attempts == 1 and self._posture is not None:
                stats = self._solve_from(self._posture.reference)  # the pose the artist prefers: a natural start
            elif attempts == 1:
                stats = self._solve_by_continuation(start)
            else:
                # Random restarts: ever bolder blends of the start with a random pose within the limits.
                alpha = min(1.0, 0.25 * attempts)
                stats = self._solve_from(start + alpha * (rng.uniform(sk.lower, sk.upper) - start))
            attempts += 1
            rank = self._attempt_rank(stats)
            if stats[O_STATUS] == Status.CONVERGED or rank < best[0]:
                best = (rank, self._q.copy(), stats)
        if best[2] is not stats:
            # An earlier attempt was best: make it the state again (frames and errors included).
            self._solve_from(best[1], iterations=0)
        return best[2], attempts

    def _posture_attempt(self, stats: np.ndarray) -> tuple[np.ndarray, int]:
        """A second attempt from the posture after a converged first one; the better one stays the state."""
        first = (self._attempt_rank(stats), self._q.copy(), stats)
        second = self._solve_from(self._posture.reference)
        if second[O_STATUS] == Status.CONVERGED and self._attempt_rank(second) < first[0]:
            return second, 2
        self._solve_from(first[1], iterations=0)
        return first[2], 2

    def _attempt_rank(self, stats: np.ndarray) -> tuple:
        """How good the attempt that just ended is (lower is better): its weighted error, or with
        priorities its levels' errors in order, so no attempt is preferred for a lower level's sake."""
        if self._is_controlled:
            return self._make_controller().rank(self._q, self._ws.R, self._ws.p)
        return (float(stats[O_COST]),)

    def _solve_from(self, q0: np.ndarray, iterations: int | None = None) -> np.ndarray:
        """One Levenberg-Marquardt attempt from ``q0``; returns a copy of its statistics."""
        s = self._settings
        if self._is_controlled:
            return self._control_solve(q0, s.max_iterations if iterations is None else iterations)
        self._q[:] = np.clip(q0, self._skeleton.lower, self._skeleton.upper)
        step_kernels.solve(self._model, s.kernel_settings(sweeps=s.solve_sweeps), self._packed,
                           self._topo.root_frame, self._W, self._q, s.max_iterations if iterations is None else iterations,
                           self._ws)
        return self._ws.stats.copy()

    def _solve_by_continuation(self, q0: np.ndarray, stages: int = 4) -> np.ndarray:
        """Approach the targets in ``stages`` from where the effectors are at ``q0``."""
        tp, tR = self._packed.position, self._packed.rotation
        final_p, final_R = tp.copy(), tR.copy()
        self._q[:] = q0
        self._refresh_frames()
        start_p = self._ws.p[self._topo.effector_frame].copy()
        start_R = self._ws.R[self._topo.effector_frame].copy()
        sweeps_total = 0
        try:
            for k in range(1, stages):
                a = k / stages
                for i in range(len(final_p)):
                    tp[i] = (1 - a) * start_p[i] + a * final_p[i]
                    tR[i] = matrix_from_rotvec(a * rotvec_from_matrix(final_R[i] @ start_R[i].T)) @ start_R[i]
                sweeps_total += self._solve_from(self._q.copy())[O_SWEEPS]
        finally:
            tp[:], tR[:] = final_p, final_R
        stats = self._solve_from(self._q.copy())
        stats[O_SWEEPS] += sweeps_total
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
        R, p = self._ws.R, self._ws.p
        W_new = transform(R[new_frame], p[new_frame])
        old_pose = transform(R[old_frame], p[old_frame])
        self._targets.pop(name, None)
        self._W = W_new
        self._set_topology(name, self._q.copy(), self._ws.lam[0])
        if old in self._topo.effector_names:
            self._targets[old] = Target.from_transform(old_pose)
            self._pack_targets()
        self._ws.x[:] = 0.0

    # -- artist control: priorities, targets on any frame, posture, balance ------------------
    def set_posture(self, q=None, weights=None) -> None:
        """Prefer the pose ``q`` (n_dofs,) [rad] (default: the rest pose), below every target.

        The posture is the lowest priority level: it only chooses among the
        poses that meet the targets as well as they can be met, so it never
        costs target accuracy. ``weights``: ``None`` (1 for every DOF), a
        scalar or one per DOF (n_dofs,) (>= 0; 0 turns the posture off), or a symmetric positive semi-definite
        precision matrix (n_dofs, n_dofs); the posture minimises
        ``(q - q_ref)^T P (q - q_ref)`` with ``P = diag(weights)`` or that matrix.
        """
        sk = self._skeleton
        ref = sk.rest.copy() if q is None else np.clip(sk.validate_q(q), sk.lower, sk.upper)
        P = _posture_precision(1.0 if weights is None else weights, sk.n_dofs)
        self._posture = None if not np.any(P) else control.Posture(ref, P)
        self._pack_targets()

    @property
    def posture(self) -> control.Posture | None:
        """The preferred posture (reference (n_dofs,) [rad], precision), or ``None`` when off."""
        return self._posture

    def set_balance(self, on: bool = True) -> None:
        """Hold the centre of mass's ground projection over the support polygon (or stop).

        The support is the root foot's sole, and the sole of every other foot
        whose target lies on the ground (the root foot's height, within 1 cm):
        the convex hull of both feet when the free foot is planted. Balance
        ranks below the targets of priority 0 and above those of priority 1
        (:data:`gsik.control.BALANCE_PRIORITY`): a hand pulled at priority 1
        cannot tip the body over.

        Raises:
            SolverError: if the skeleton gives no segment masses.
        """
        if on:
            self._mass_model()
        self._balance = bool(on)
        self._pack_targets()

    @property
    def balance(self) -> bool:
        """True while balance is on."""
        return self._balance

    def center_of_mass(self) -> np.ndarray:
        """The centre of mass (3,) in the world [m] at the current angles.

        Raises:
            SolverError: if the skeleton gives no segment masses.
        """
        return center_of_mass(self._mass_model(), self._ws.R, self._ws.p)

    def _mass_model(self):
        if self._skeleton.total_mass <= 0.0:
            raise SolverError(f"the centre of mass needs segment masses; skeleton {self._skeleton.name!r} gives "
                              "none (see skeletons/README.md: segments' mass)")
        return self._skeleton.mass_model

    def _controlled_targets(self) -> bool:
        """True if the targets need the prioritised path: several levels, or a target off the effectors."""
        levels = {t.priority for t in self._targets.values()}
        return len(levels) > 1 or any(n not in self._topo.effector_names for n in self._targets)

    def _make_controller(self) -> control.Controller:
        """The controller for the current targets: the last one retargeted if only their values changed."""
        if self._controller is None:
            sk = self._skeleton
            tasks = control.frame_tasks(sk, self._targets, self._settings.orientation_weight)
            balance = control.support(sk, self._targets, self._ws.p) if self._balance else None
            last = self._last_controller
            if last is not None and last.key == control.structure(sk, tasks, self._posture, balance, self._settings):
                last.retarget(tasks)
            else:
                last = control.Controller(sk, tasks, self._posture, balance, self._settings)
            self._controller = self._last_controller = last
        return self._controller

    def _control_step(self) -> SolveResult:
        st = self._make_controller().step(self._q, self._W, self._ws.R, self._ws.p, self._ws.lam)
        status = Status.CONVERGED if st.converged else Status.STALLED if st.held else Status.BUDGET_EXHAUSTED
        return self._control_result(status, 1, st.cost, st.step_norm, 1)

    def _control_solve(self, q0: np.ndarray, iterations: int) -> np.ndarray:
        """One attempt of prioritised steps from ``q0`` until the pose holds; statistics as the kernel's solve."""
        c = self._make_controller()
        self._q[:] = np.clip(q0, self._skeleton.lower, self._skeleton.upper)
        self._refresh_frames()
        lam = np.array([self._settings.damping])
        settles = self._posture is not None or self._balance  # keep going after convergence until they hold
        st = None
        it = 0
        for it in range(1, iterations + 1):
            st = c.step(self._q, self._W, self._ws.R, self._ws.p, lam)
            if st.held or (st.converged and not settles):
                break
        stats = np.zeros(kernels.N_STATS)
        converged = c.converged(self._ws.R, self._ws.p)
        stats[O_STATUS] = (Status.CONVERGED if converged else Status.STALLED if st is not None and st.held
                                    else Status.BUDGET_EXHAUSTED)
        stats[O_ITERATIONS] = it if iterations else 0
        stats[O_COST] = c.target_cost(self._ws.R, self._ws.p)
        stats[O_STEP_NORM] = 0.0 if st is None else st.step_norm
        return stats

    def _control_result(self, status: Status, iterations: int, residual: float, step_norm: float,
                        attempts: int) -> SolveResult:
        """A result naming every effector, then the other targeted frames, with their errors."""
        names, pos, ori = self._make_controller().report(self._topo.effector_names, self._ws.R, self._ws.p)
        return SolveResult(self._q.copy(), status, iterations, 0, residual, names, pos, ori, step_norm, attempts)


def _posture_precision(weights, n: int) -> np.ndarray:
    """Posture weights as a precision: (n,) per DOF, or (n, n); checked."""
    try:
        P = np.array(weights, dtype=float)
    except (TypeError, ValueError):
        raise SolverError(f"posture weights must be numbers, got {weights!r}") from None
    if P.ndim == 0:
        P = np.full(n, float(P))
    if P.shape not in ((n,), (n, n)) or not np.all(np.isfinite(P)):
        raise SolverError(f"posture weights must be finite: a scalar, ({n},) or ({n}, {n}), got shape {P.shape}")
    if P.ndim == 1 and np.any(P < 0):
        raise SolverError(f"posture weights must be >= 0, got {P[P < 0][0]!r}")
    if P.ndim == 2 and (not np.allclose(P, P.T) or np.linalg.eigvalsh(P).min() < -1e-9 * max(1.0, abs(P).max())):
        raise SolverError("posture weights as a matrix must be symmetric positive semi-definite")
    return P
