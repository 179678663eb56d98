"""The plain step's arrays in two buffers, behind the named contracts, cut once (:mod:`gsik.kernels.plain`).

Passing the :class:`~gsik.kernels.KinematicModel`, :class:`~gsik.kernels.TargetArrays`, the root's transform, the
angles and the :class:`~gsik.kernels.Workspace` field by field makes numba unbox 23 arrays a call (about 0.1 µs
each: half of an idle frame's kernel call on a chain). Here they live in one float64 buffer and one int64 buffer
(:func:`make_buffers`); :func:`views` cuts the same named contracts out of them in compiled code, once per
configuration (:mod:`gsik.kernels.plain` holds them), and the :class:`~gsik.solver.Solver` holds NumPy views of the
same memory, so nothing is copied between them. The step's scratch (:class:`~gsik.kernels.Scratch`) is cut from the
float buffer too: no allocation a frame.

Float buffer, in order: ``q`` (n), ``err`` (2, m) (adjacent: a result copies both at once), ``stats`` (N_STATS),
``x`` (n), ``lam`` (1), ``R`` (nf, 3, 3), ``p`` (nf, 3), the targets' ``position`` (m, 3), ``rotation`` (m, 3, 3),
``row_weight`` (m, 6), ``W`` (4, 4), the model's ``frame_offset`` (nf, 3), ``frame_rotation`` (nf, 3, 3),
``frame_axis`` (nf, 3), ``lower``, ``upper`` (n), ``sign`` (m, n), then the scratch. Int buffer: ``frame_parent``,
``frame_dof`` (nf), ``dof_frame`` (n), ``effector_frame`` (m), ``effector_dofs`` (m, n), ``effector_dof_count`` (m).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik._jit import njit, python_function
from gsik.kernels import N_STATS, KinematicModel, TargetArrays, Workspace, cut_scratch, scratch_size


class Sizes(NamedTuple):
    """What the buffers are cut for: frames, DOFs, effectors, and the IK root's frame (-1: none)."""

    n_frames: int
    n_dofs: int
    n_effectors: int
    root: int


class Buffers(NamedTuple):
    """The two buffers and their :class:`Sizes` (what a compiled call takes)."""

    floats: np.ndarray
    ints: np.ndarray
    sizes: Sizes


@njit(cache=True, inline="always")
def _float_ends(nf, n, m):
    """Where each field of the float buffer ends (see the module's docstring for the order)."""
    q = n
    err = q + 2 * m
    stats = err + N_STATS
    x = stats + n
    lam = x + 1
    R = lam + 9 * nf
    p = R + 3 * nf
    tp = p + 3 * m
    tR = tp + 9 * m
    tw = tR + 6 * m
    W = tw + 16
    off = W + 3 * nf
    rot = off + 9 * nf
    axis = rot + 3 * nf
    lower = axis + n
    upper = lower + n
    sign = upper + m * n
    return q, err, stats, x, lam, R, p, tp, tR, tw, W, off, rot, axis, lower, upper, sign


@njit(cache=True, inline="always")
def _int_ends(nf, n, m):
    parent = nf
    dof = parent + nf
    dof_frame = dof + n
    eff = dof_frame + m
    eff_dofs = eff + m * n
    count = eff_dofs + m
    return parent, dof, dof_frame, eff, eff_dofs, count


@njit(cache=True, inline="always")
def views(floats, ints, sizes):
    """``(model, targets, W, q, ws, sc)``: the named contracts over the buffers, and the step's scratch."""
    nf, n, m = sizes.n_frames, sizes.n_dofs, sizes.n_effectors
    q, err, stats, x, lam, R, p, tp, tR, tw, W, off, rot, axis, lower, upper, sign = _float_ends(nf, n, m)
    parent, dof, dof_frame, eff, eff_dofs, count = _int_ends(nf, n, m)
    model = KinematicModel(ints[:parent], floats[W:off].reshape((nf, 3)), floats[off:rot].reshape((nf, 3, 3)),
                           floats[rot:axis].reshape((nf, 3)), ints[parent:dof], ints[dof:dof_frame],
                           floats[axis:lower], floats[lower:upper], ints[dof_frame:eff],
                           floats[upper:sign].reshape((m, n)), ints[eff:eff_dofs].reshape((m, n)),
                           ints[eff_dofs:count])
    targets = TargetArrays(floats[p:tp].reshape((m, 3)), floats[tp:tR].reshape((m, 3, 3)),
                           floats[tR:tw].reshape((m, 6)))
    ws = Workspace(floats[lam:R].reshape((nf, 3, 3)), floats[R:p].reshape((nf, 3)), floats[q:err].reshape((2, m)),
                   floats[err:stats], floats[stats:x], floats[x:lam])
    sc = cut_scratch(floats[sign:], nf, n, m, False)
    return model, targets, floats[tw:W].reshape((4, 4)), floats[:q], ws, sc


def make_buffers(model: KinematicModel, root: int) -> Buffers:
    """Buffers for ``model`` with the IK root's frame ``root``: the model's arrays copied in, the targets'
    rotations the identity, everything else zero."""
    nf, n, m = model.frame_parent.shape[0], model.lower.shape[0], model.effector_frame.shape[0]
    f_ends, i_ends = python_function(_float_ends)(nf, n, m), python_function(_int_ends)(nf, n, m)
    floats = np.zeros(f_ends[-1] + scratch_size(nf, n, m, False))
    ints = np.zeros(i_ends[-1], dtype=np.int64)
    sizes = Sizes(nf, n, m, int(root))
    for a, b, values in zip((f_ends[-7],) + f_ends[-6:-1], f_ends[-6:],
                            (model.frame_offset, model.frame_rotation, model.frame_axis, model.lower, model.upper,
                             model.sign)):
        floats[a:b] = values.ravel()
    for a, b, values in zip((0,) + i_ends[:-1], i_ends, (model.frame_parent, model.frame_dof, model.dof_frame,
                                                          model.effector_frame, model.effector_dofs,
                                                          model.effector_dof_count)):
        ints[a:b] = values.ravel()
    rotations, end = f_ends[7:9]
    floats[rotations:end].reshape(m, 3, 3)[:] = np.eye(3)
    return Buffers(floats, ints, sizes)


def target_rows_at(sizes: Sizes) -> tuple[int, int]:
    """Where in the float buffer the targets' positions (m, 3) and rotations (m, 3, 3) begin."""
    ends = python_function(_float_ends)(sizes.n_frames, sizes.n_dofs, sizes.n_effectors)
    return ends[6], ends[7]


def python_views(buffers: Buffers) -> tuple[TargetArrays, np.ndarray, np.ndarray, Workspace]:
    """``(targets, W, q, ws)``: NumPy views of the float buffer, the same memory the compiled call cuts."""
    floats, (nf, n, m, _) = buffers.floats, buffers.sizes
    q, err, stats, x, lam, R, p, tp, tR, tw, W = python_function(_float_ends)(nf, n, m)[:11]
    targets = TargetArrays(floats[p:tp].reshape(m, 3), floats[tp:tR].reshape(m, 3, 3), floats[tR:tw].reshape(m, 6))
    ws = Workspace(floats[lam:R].reshape(nf, 3, 3), floats[R:p].reshape(nf, 3), floats[q:err].reshape(2, m),
                   floats[err:stats], floats[stats:x], floats[x:lam])
    return targets, floats[tw:W].reshape(4, 4), floats[:q], ws
