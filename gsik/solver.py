"""The IK solver: Projected Gauss-Seidel on the damped normal equations.

Each frame step linearises the effectors' errors at the current angles,
builds ``(J^T W J + delta I) dq = J^T W e`` and runs Gauss-Seidel sweeps on
it, clamping every unknown as it is updated so that ``q + dq`` stays within
the joint limits (Projected Gauss-Seidel, Kenwright 2012). The previous
frame's ``dq`` is the next frame's starting guess (warm start).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from gsik import control, kernels
from gsik.attempts import SETTLED_AGREEMENT, SETTLED_REPEATS, AttemptPolicy  # noqa: F401  (re-exported)
from gsik.balance import center_of_mass
from gsik.control_frame import ControlFrame
from gsik.errors import SolverError, choices, show_value
from gsik.kernels import O_ITERATIONS, O_RESIDUAL, O_STATUS, O_STEP_NORM, O_SWEEPS
from gsik.kernels import solve as solve_kernels  # noqa: F401  (gsik.solver.solve_kernels, as before)
from gsik.kernels import buffers as kernel_buffers
from gsik.kernels import plain as plain_kernels
from gsik.kernels import step as step_kernels
from gsik.kernels import step_inputs
from gsik.kernels.kinematics import forward_kinematics
from gsik.kinematics import Topology, kinematic_model, topology
from gsik.result import (_STATUSES, SolveResult, Status, errors_by_effector, max_orientation_error,  # noqa: F401
                         max_position_error)  # re-exported: gsik.solver's names as before the split
from gsik.result_arrays import ResultArrays
from gsik.rotations import transform
from gsik.skeleton import Skeleton
from gsik.solver_targets import MAX_PRIORITY_LEVELS, MAX_TARGETS, TargetSetting  # noqa: F401  (re-exported)
from gsik.settings import PAPER_METHOD, SolverSettings, setting_names
from gsik.targets import MAX_COORDINATE, Target

#: Largest posture weight (or precision entry) [1/rad^2]: a prior's precision is about 1e3; beyond 1e12 the step's
#: system loses every digit of the targets to the posture.
MAX_POSTURE_WEIGHT = 1e12

_new_tuple = tuple.__new__

__all__ = ["PAPER_METHOD", "SolveResult", "Solver", "SolverSettings", "Status", "setting_names"]


class Solver(TargetSetting, AttemptPolicy, ControlFrame):
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
        self._settled = None  # (what a solve depended on, its statistics) after a solve ended at a best reach
        self._warm = None  # (angles, posture) a solve converged to: a solve starting there is warm
        self._work_done = [0, 0]  # linearisations and sweeps of the current solve
        self._posture: control.Posture | None = None
        self._balance = False
        self._controller: control.Controller | None = None  # None: to be made (or retargeted) before use
        self._last_controller: control.Controller | None = None
        self._controller_for: tuple = (None,) * 4  # (root, packed layout, posture, settings) it was last made for
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
        try:
            W = np.array(world_from_root, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise SolverError(f"world_from_root must be a (4, 4) transform, got {show_value(world_from_root)}") \
                from None
        if W.shape != (4, 4) or not np.isfinite(W).all():
            raise SolverError(f"world_from_root must be a finite (4, 4) transform, got shape {W.shape}")
        if max(map(abs, W[:3, 3].tolist())) > MAX_COORDINATE:  # plain floats: cheaper than NumPy for three values
            raise SolverError(f"world_from_root must place the root within {MAX_COORDINATE:g} m of the origin "
                              f"in x, y and z, got {W[:3, 3].tolist()}")
        return W

    def _set_topology(self, root: str, q: np.ndarray, lam: float) -> None:
        """Model, targets and workspace for ``root``, at angles ``q`` [rad]; ``lam`` the damping carried over."""
        self._skeleton = self._skeleton.with_root(root)
        self._topo: Topology = topology(self._skeleton, root)
        self._model = kinematic_model(self._skeleton, self._topo)
        sk = self._skeleton
        self._target_frames = frozenset(sk.target_names)  # once, not per target set: set_targets runs per frame
        self._valid_names = (self._target_frames | set(self._topo.effector_names)) - {root}  # what a target may aim
        m = len(self._topo.effector_names)
        # Targets, root transform, angles and workspace are views of one buffer the step kernel takes whole
        # (gsik.kernels.buffers); q and the errors lead it, so a result copies them at once.
        self._buffers = kernel_buffers.make_buffers(self._model, self._topo.root_frame)
        self._packed, W, self._q, self._ws = kernel_buffers.python_views(self._buffers)
        W[:] = self._W
        self._W = W
        self._state = self._buffers.floats[: sk.n_dofs + 2 * m]
        n = sk.n_dofs  # where q, the position errors and the orientation errors lie in _state
        self._result_slices = (slice(0, n), slice(n, n + m), slice(n + m, n + 2 * m))
        self._result_arrays = ResultArrays(self._state, self._result_slices)
        self._q[:] = q
        self._q_before = np.empty(sk.n_dofs)  # a prioritised step's starting angles, to undo a non-finite one
        self._ws.lam[0] = lam
        self._fk = kernels.compiled_entry(forward_kinematics, self._model, self._q, self._topo.root_frame, self._W,
                                          self._ws.R, self._ws.p)
        self._plain = self._moves = self._fast_rows = self._row_bytes = None  # at first use
        self._row_of = {name: k for k, name in enumerate(self._topo.effector_names)}
        self._layout = None  # the targets' layout the packed rows hold: None packs every row again
        self._refresh_frames()
        self._pack_targets()

    def _refresh_frames(self) -> None:
        self._fk(self._model, self._q, self._topo.root_frame, self._W, self._ws.R, self._ws.p)

    def _pack_targets(self, layout: tuple | None = None) -> None:
        """The targets into the kernels' rows. When only their positions and orientations changed since the last
        packing (a drag's every frame: same names, weights, position-only flags and priorities, ``layout`` if
        given), only those are written; the rows without a target keep what the last full packing put there
        (weight 0: unused)."""
        self._controller = None
        self._fast_rows = None  # move_target's rows: made again at its next call
        if layout is None:
            layout = tuple([(name, t.weight, t.position_only, t.priority) for name, t in self._targets.items()])
        if layout == self._layout:
            self._write_target_rows()
            self._is_controlled = self._posture is not None or self._balance or self._layout_controlled
            return
        self._layout, self._layout_controlled = layout, self._controlled_targets()
        self._is_controlled = self._posture is not None or self._balance or self._layout_controlled
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

    def configure(self, **changes) -> None:
        """Change settings by name (validated); unknown names raise :class:`SolverError`."""
        self._settings = self._make_settings(self._settings, changes)
        self._plain = None  # the kernels' cached calls: made again at first use
        self._ws.lam[0] = self._settings.damping
        self._layout = None  # the orientation weight may have changed: pack every row again
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
    # -- solving --------------------------------------------------------------
    def step(self, targets: Mapping[str, Target | None] | None = None) -> SolveResult:
        """One frame: one linearisation and up to ``settings.sweeps`` PGS sweeps (with priorities, posture or
        balance, up to ``settings.tracking_steps`` prioritised steps while a target lags).

        ``targets`` (optional) replaces all targets first, as :meth:`set_targets`.
        """
        if targets is not None:
            self.set_targets(targets)
        if self._is_controlled:
            result = self._frame_step()  # a drag's frame in one compiled call (gsik.control_frame), else None
            if result is not None:
                return result
            self._q_before[:] = self._q
            try:
                result, finite = self._control_step()
                if finite:
                    return result
            except np.linalg.LinAlgError:  # its least squares met non-finite numbers
                pass
            return self._control_refused()  # the prioritised step went non-finite: undone as the plain one is
        run = self._plain or self._plain_inputs()
        finite, status, iterations, sweeps, residual, step_norm = run[0](run[2])
        if finite:  # the result _new_result makes, inline: a frame's one method call fewer
            out = self._result_arrays.take()
            return _new_tuple(SolveResult, (out[2], _STATUSES[status], iterations, sweeps, residual,
                                            self._topo.effector_names, out[3], out[4], step_norm, 1))
        # stats[O_FINITE] 0: the kernel did not take the step, the angles are the last finite ones
        self._refuse_non_finite(None, self._ws.stats)
        return self._result(self._ws.stats, O_RESIDUAL, 1)

    def _plain_inputs(self) -> tuple:
        """``(compiled step_plain, compiled solve_plain, their PlainInputs)`` (:mod:`gsik.kernels.plain`) over the
        buffers: persistent arrays, so this is built once per configuration."""
        inputs = plain_kernels.make_plain_inputs(self._settings.kernel_settings(), self._solve_settings(),
                                                 *self._buffers)
        self._plain = (kernels.compiled_entry(plain_kernels.step_plain, inputs),
                       kernels.compiled_entry(plain_kernels.solve_plain, inputs, 0, False), inputs)
        return self._plain

    def _kernel_inputs(self) -> tuple:
        """``(step kernel, its named arguments)`` over the same memory (Table 1's kernel columns time it)."""
        inputs = (self._model, self._settings.kernel_settings(), self._packed, self._topo.root_frame, self._W,
                  self._q, self._ws)
        return kernels.compiled_entry(step_kernels.step, *inputs), inputs

    def _result(self, st: np.ndarray, residual_index: int, attempts: int) -> SolveResult:
        """The result of the statistics ``st`` (N_STATS,) a kernel wrote, its residual ``st[residual_index]``."""
        stats = st.tolist()
        return self._new_result(int(stats[O_STATUS]), int(stats[O_ITERATIONS]), int(stats[O_SWEEPS]),
                                stats[residual_index], stats[O_STEP_NORM], attempts)

    def _new_result(self, status: int, iterations: int, sweeps: int, residual: float, step_norm: float,
                    attempts: int) -> SolveResult:
        """A single-level result: the current angles and errors, with these statistics (``status`` a code)."""
        # q and the (2, m) errors: views of one copy, a dropped result's when the caller holds none of it.
        out = self._result_arrays.take()
        # tuple.__new__: every field given, so NamedTuple's own __new__ (a Python call with defaults) is skipped.
        return _new_tuple(SolveResult, (out[2], _STATUSES[status], iterations, sweeps, residual,
                                        self._topo.effector_names, out[3], out[4], step_norm, attempts))

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

    def _make_controller(self, rows: bool = False) -> control.Controller:
        """The controller for the current targets: the last one retargeted if only their values changed.
        ``rows``: the packed rows hold the targets' values (a frame's step; a solve's continuation stages others
        there), so a drag's moved targets are gathered from them (:meth:`gsik.control.Controller.retarget_rows`)."""
        if self._controller is None:
            sk, ow = self._skeleton, self._settings.orientation_weight
            last = self._fitting_controller()  # made for this root, packed layout, posture and settings
            if last is not None:
                if not (rows and last.retarget_rows(self._packed)):
                    last.retarget_targets(self._targets, ow)
            else:
                last = self._last_controller
                balance = control.support(sk, self._targets, self._ws.p) if self._balance else None
                key = control.structure_of(sk.root, {n: t.priority for n, t in self._targets.items()},
                                           self._posture, balance, self._settings)
                if last is not None and last.key == key:
                    last.retarget_targets(self._targets, ow)
                else:
                    last = control.Controller(sk, control.frame_tasks(sk, self._targets, ow), self._posture,
                                              balance, self._settings)
                last.use_rows(self._row_of)
                # Balance's support depends on the feet's heights: its key is made every time.
                self._controller_for = (None,) * 4 if self._balance else (sk.root, self._layout, self._posture,
                                                                           self._settings)
            self._controller = self._last_controller = last
        return self._controller

    def _control_step(self) -> tuple[SolveResult, bool]:
        """Up to ``settings.tracking_steps`` prioritised steps (linearisations): another while the last was taken
        and left a target lagging (:data:`gsik.control.TRACKING_ERROR`), so a dragged target is met in its frame
        as the single level's step meets it. ``step_norm``: the whole change of the angles [rad]. Returns the
        result and whether its angles are finite."""
        c = self._make_controller(rows=True)
        for iterations in range(1, self._settings.tracking_steps + 1):
            st = c.step(self._q, self._W, self._ws.R, self._ws.p, self._ws.lam)
            if not st.lagging or st.held or not st.accepted:
                break
        # Not converged while the posture's share of a step is bounded: it has further to go (kernels.posture_level)
        converged = st.converged and not c.share_bounded()
        status = Status.CONVERGED if converged else Status.STALLED if st.held else Status.BUDGET_EXHAUSTED
        if iterations == 1:  # the one step's own norm: the same difference and sum (0 when it did not move)
            step_norm = st.step_norm
        else:
            step_norm = step_inputs.norm(self._q - self._q_before)  # one sum for every controlled step's norm
        report = self._control_report(left=True)
        return self._control_result(status, iterations, st.cost, step_norm, 1, report), report.finite

    def _control_result(self, status: Status, iterations: int, residual: float, step_norm: float,
                        attempts: int, report: control.ControlReport | None = None) -> SolveResult:
        """A result naming every effector, then the other targeted frames, with their errors: ``report`` (the
        controller's, :class:`gsik.control.ControlReport`), or evaluated at the current pose."""
        names, values, _ = report or self._control_report()
        n, k = len(self._q), len(names)  # q and the errors share one buffer: three views the caller owns
        return _new_tuple(SolveResult, (values[:n], status, iterations, 0, residual, names, values[n:n + k],
                                        values[n + k:], step_norm, attempts))

    def _control_report(self, left: bool = False) -> control.ControlReport:
        """The controller's report at the current pose (``left``: the pose its last step left, errors as it found)."""
        return (self._controller or self._make_controller()).report(self._topo.effector_names, self._q, self._ws.R,
                                                                   self._ws.p, left)


def _posture_precision(weights, n: int) -> np.ndarray:
    """Posture weights as a precision: (n,) per DOF, or (n, n); checked."""
    try:
        P = np.array(weights, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise SolverError(f"posture weights must be numbers, got {show_value(weights)}") from None
    if P.ndim == 0:
        P = np.full(n, float(P))
    if P.shape not in ((n,), (n, n)) or not np.all(np.isfinite(P)):
        raise SolverError(f"posture weights must be finite: a scalar, ({n},) or ({n}, {n}), got shape {P.shape}")
    if np.any(np.abs(P) > MAX_POSTURE_WEIGHT):
        raise SolverError(f"posture weights must be at most {MAX_POSTURE_WEIGHT:g} in magnitude, got "
                          f"{float(np.abs(P).max()):g}")
    if P.ndim == 1 and np.any(P < 0):
        raise SolverError(f"posture weights must be >= 0, got {P[P < 0][0]!r}")
    if P.ndim == 2 and (not np.allclose(P, P.T) or np.linalg.eigvalsh(P).min() < -1e-9 * max(1.0, abs(P).max())):
        raise SolverError("posture weights as a matrix must be symmetric positive semi-definite")
    return P
