"""The compiled kernels and their named contracts (pinocchio's Model / Data split).

- :class:`KinematicModel`: the immutable structure-of-arrays a skeleton seen
  from one root gives (built in one place, :func:`gsik.kinematics.kinematic_model`),
  read by forward kinematics, the Jacobian and the solver.
- :class:`KernelSettings`: the solver settings the kernels read
  (made by :meth:`gsik.SolverSettings.kernel_settings`).
- :class:`TargetArrays`: the packed targets, one row per effector.
- :class:`Workspace`: the state kept between steps (:func:`make_workspace`); :class:`Scratch`: a call's buffers.

Modules: :mod:`~gsik.kernels.kinematics` (FK, errors, Jacobian, normal
equations), :mod:`~gsik.kernels.pgs` (Projected Gauss-Seidel, bounded
solve), :mod:`~gsik.kernels.step` (a frame step), :mod:`~gsik.kernels.solve` (a solve's attempt),
:mod:`~gsik.kernels.priority` (the strict-priority step), :mod:`~gsik.kernels.control` (the prioritised step's
level evaluation, packing and trial), :mod:`~gsik.kernels.buffers` (the plain step's arrays in two buffers,
cut into these contracts inside the compiled call). Nothing
here validates anything: the public modules check their inputs first.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik._jit import njit, python_function

# Indices into the statistics vector the kernels fill. O_FINITE: 1.0 if the angles and the used rows' errors a
# step or solve leaves are all finite, else 0.0 (a step then leaves the angles as they were).
O_SWEEPS, O_RESIDUAL, O_UPDATE, O_COST, O_STEP_NORM, O_STATUS, O_ITERATIONS, O_FINITE = range(8)
N_STATS = 8
# Status codes the kernels write into stats[O_STATUS]; gsik.solver.Status has these values.
CONVERGED, STALLED, BUDGET_EXHAUSTED = 0, 1, 2


class KinematicModel(NamedTuple):
    """A skeleton seen from one IK root, as the kernels read it (read-only arrays).

    Attributes:
        frame_parent: (n_frames,) parent frame index, -1 for the top; topological order.
        frame_offset: (n_frames, 3) position in the parent frame [m].
        frame_rotation: (n_frames, 3, 3) fixed rotation in the parent frame.
        frame_axis: (n_frames, 3) the DOF's axis in the frame (unit), zero without a DOF.
        frame_dof: (n_frames,) the frame's DOF index, -1 for none.
        dof_frame: (n_dofs,) the frame each DOF turns.
        lower, upper: (n_dofs,) joint limits [rad].
        effector_frame: (m,) frame index of each effector.
        sign: (m, n_dofs) +1 / -1 / 0: how DOF ``d`` turns effector ``k`` seen from the root.
        effector_dofs: (m, n_dofs) the DOFs with a non-zero sign, first ``effector_dof_count[k]`` valid.
        effector_dof_count: (m,).
    """

    frame_parent: np.ndarray
    frame_offset: np.ndarray
    frame_rotation: np.ndarray
    frame_axis: np.ndarray
    frame_dof: np.ndarray
    dof_frame: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    effector_frame: np.ndarray
    sign: np.ndarray
    effector_dofs: np.ndarray
    effector_dof_count: np.ndarray


class KernelSettings(NamedTuple):
    """The settings a step or a solve reads (see :class:`gsik.SolverSettings` for their meaning)."""

    damping: float
    sweeps: int
    residual_tolerance: float
    update_tolerance: float
    stall_tolerance: float
    max_step: float
    adaptive_damping: bool
    warm_start: bool
    position_tolerance: float
    orientation_tolerance: float
    settle_tolerance: float
    subspace_minimization: bool
    positions_first: bool


class TargetArrays(NamedTuple):
    """The targets, one row per effector of the model.

    Attributes:
        position: (m, 3) world positions [m].
        rotation: (m, 3, 3) world orientations.
        row_weight: (m, 6) weights of the 3 position then 3 orientation rows (0: row unused).
    """

    position: np.ndarray
    rotation: np.ndarray
    row_weight: np.ndarray


class Workspace(NamedTuple):
    """The state a step reads and writes, kept between calls (allocated once per model).

    Attributes:
        R: (n_frames, 3, 3) world rotations at the current ``q``.
        p: (n_frames, 3) world positions [m] at the current ``q``.
        err: (2, m) position [m] and orientation [rad] errors at the current ``q``.
        stats: (N_STATS,) what the last call did (indices ``O_*``).
        x: (n_dofs,) the last step [rad], the next step's warm start.
        lam: (1,) the adaptive damping carried between frames.
    """

    R: np.ndarray
    p: np.ndarray
    err: np.ndarray
    stats: np.ndarray
    x: np.ndarray
    lam: np.ndarray


class Scratch(NamedTuple):
    """Per-call buffers of a step or a solve, made inside the kernel by :func:`make_scratch`.

    Allocating it in compiled code costs less than unboxing twelve arrays
    passed in from Python (measured: ~0.55 µs for the twelve).

    Attributes:
        e: (6m,) error vector. A: (n_dofs, n_dofs) ``J^T W J``; A_damped: its damped copy (solve only).
        b, lo, hi, x_prev, q_new: (n_dofs,); x_solve: (n_dofs,) a solve's step (solve only).
        R_new, p_new, err_new: frames and errors at a trial ``q``. M: (3, 3).
        v: (2, n_dofs, 6) one effector's compact Jacobian block and its weighted copy.
        free_M: (n_dofs, n_dofs), free_r: (n_dofs,), free_index: (n_dofs,) int64, free_mask: (n_dofs,) bool: the
            work arrays of :func:`~gsik.kernels.pgs.bounded_solve_in` (the free set's system, its indices, its mask).
    """

    e: np.ndarray
    A: np.ndarray
    A_damped: np.ndarray
    b: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    x_prev: np.ndarray
    q_new: np.ndarray
    x_solve: np.ndarray
    R_new: np.ndarray
    p_new: np.ndarray
    err_new: np.ndarray
    M: np.ndarray
    v: np.ndarray
    free_M: np.ndarray
    free_r: np.ndarray
    free_index: np.ndarray
    free_mask: np.ndarray


def make_workspace(n_frames: int, n_dofs: int, n_effectors: int, err: np.ndarray | None = None) -> Workspace:
    """A zeroed :class:`Workspace`; ``err`` (2, m) may be given to share a caller's buffer."""
    return Workspace(R=np.zeros((n_frames, 3, 3)), p=np.zeros((n_frames, 3)),
                     err=np.zeros((2, n_effectors)) if err is None else err, stats=np.zeros(N_STATS),
                     x=np.zeros(n_dofs), lam=np.zeros(1))


@njit(cache=True, inline="always")
def _scratch_ends(n_frames, n, m, for_solve):
    """Where each field of a :class:`Scratch` ends in its buffer (A first: the sweeps read it row by row)."""
    k = n if for_solve else 0
    a = n * n
    ad = a + k * k
    e = ad + 6 * m
    b = e + n
    lo = b + n
    hi = lo + n
    xp = hi + n
    qn = xp + n
    xs = qn + k
    Rn = xs + 9 * n_frames
    pn = Rn + 3 * n_frames
    en = pn + 2 * m
    M = en + 9
    v = M + 12 * n
    fM = v + n * n
    fr = fM + n
    return a, ad, e, b, lo, hi, xp, qn, xs, Rn, pn, en, M, v, fM, fr


def scratch_size(n_frames: int, n: int, m: int, for_solve: bool) -> int:
    """Float64 entries a :class:`Scratch` takes (what :func:`cut_scratch` needs of its buffer)."""
    return python_function(_scratch_ends)(n_frames, n, m, for_solve)[-1]


@njit(cache=True, inline="always")
def cut_scratch(buf, n_frames, n, m, for_solve):
    """A :class:`Scratch` cut from ``buf`` (at least :func:`scratch_size` float64 entries; contents unused); its two
    integer and boolean work arrays are allocated."""
    k = n if for_solve else 0
    a, ad, e, b, lo, hi, xp, qn, xs, Rn, pn, en, M, v, fM, fr = _scratch_ends(n_frames, n, m, for_solve)
    return Scratch(buf[ad:e], buf[:a].reshape((n, n)), buf[a:ad].reshape((k, k)), buf[e:b], buf[b:lo], buf[lo:hi],
                   buf[hi:xp], buf[xp:qn], buf[qn:xs], buf[xs:Rn].reshape((n_frames, 3, 3)),
                   buf[Rn:pn].reshape((n_frames, 3)), buf[pn:en].reshape((2, m)), buf[en:M].reshape((3, 3)),
                   buf[M:v].reshape((2, n, 6)), buf[v:fM].reshape((n, n)), buf[fM:fr], np.empty(n, dtype=np.int64),
                   np.zeros(n, dtype=np.bool_))


@njit(cache=True)
def make_scratch(n_frames, n, m, for_solve):
    """A :class:`Scratch` (uninitialised) for ``n`` DOFs and ``m`` effectors; ``for_solve`` adds a solve's buffers.

    One float allocation, cut into the fields (and the two work arrays :func:`cut_scratch` allocates): each further
    allocation would cost as much as the cutting. The ends are
    plain integers (an array of sizes and its cumulative sum would be two allocations more: 0.3-0.5 µs of a step).
    """
    return cut_scratch(np.empty(_scratch_ends(n_frames, n, m, for_solve)[-1]), n_frames, n, m, for_solve)


def compiled_entry(kernel, *args):
    """``kernel``'s compiled code for the types of ``args``, callable without numba's type dispatch.

    Dispatch types every argument on every call, which costs microseconds
    for NamedTuples of arrays; a caller that always passes the same types
    (the solver: persistent buffers) calls the entry point instead. Without
    numba, the plain function.
    """
    if not hasattr(kernel, "overloads"):
        return kernel
    return kernel.compile(tuple(kernel.typeof_pyval(a) for a in args))
