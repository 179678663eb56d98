"""The hot loops: forward kinematics, the Jacobian, the normal equations, PGS.

Plain functions over arrays, compiled by numba when it is installed. The
public modules (:mod:`gsik.kinematics`, :mod:`gsik.pgs`, :mod:`gsik.solver`)
check their inputs and call these; nothing here validates anything.

Conventions: ``R`` (n_frames, 3, 3) and ``p`` (n_frames, 3) hold world
rotations and positions [m]; an effector's 6 rows are 3 position rows then 3
orientation rows; ``sign[e, d]`` is +1 where DOF ``d`` lies above effector
``e`` but not above the root, -1 where it lies above the root but not above
the effector (it turns the other way round seen from the root), else 0.
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit

# Indices into the settings vector passed to the kernels.
(S_DAMPING, S_SWEEPS, S_RES_TOL, S_UPD_TOL, S_STALL_TOL, S_MAX_STEP, S_ADAPTIVE, S_WARM, S_POS_TOL, S_ORI_TOL,
 S_SETTLE_TOL, S_SUBSPACE) = range(12)
N_SETTINGS = 12
# Indices into the statistics vector the kernels fill.
O_SWEEPS, O_RESIDUAL, O_UPDATE, O_COST, O_STEP_NORM, O_ACCEPTED, O_LAMBDA, O_STATUS, O_ITERATIONS = range(9)
N_STATS = 9
# With adaptive damping, lam may fall to this fraction of delta while steps succeed: near a
# solution the steps come closer to Gauss-Newton and the last millimetre takes tens of frames, not hundreds
# (measured on gsik.anim.scenarios; 0.01 settles faster still but tracks a fast wave worse).
ADAPTIVE_FLOOR = 0.1
# Status codes, in the order of gsik.solver.Status.
CONVERGED, STALLED, BUDGET_EXHAUSTED = 0, 1, 2


@njit(cache=True)
def log_map_into(R, out, off):
    """Write the rotation vector [rad] of rotation matrix ``R`` (3, 3) into ``out[off:off + 3]``.

    Accurate at every angle: atan2 (not acos, which loses half the digits
    near 0 and pi), and past 120 degrees the axis from the symmetric part.
    """
    wx = R[2, 1] - R[1, 2]
    wy = R[0, 2] - R[2, 0]
    wz = R[1, 0] - R[0, 1]
    s = 0.5 * math.sqrt(wx * wx + wy * wy + wz * wz)  # sin(angle)
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)  # cos(angle)
    angle = math.atan2(s, c)
    if angle < 1e-6:
        out[off] = 0.5 * wx
        out[off + 1] = 0.5 * wy
        out[off + 2] = 0.5 * wz
        return
    if c > -0.5:
        f = angle / (2.0 * s)
        out[off] = wx * f
        out[off + 1] = wy * f
        out[off + 2] = wz * f
        return
    # (R + R^T) / 2 - c I = (1 - c) a a^T exactly; take its largest column.
    i = 0
    best = -1.0
    for k in range(3):
        mk = R[k, k] - c
        if mk > best:
            best = mk
            i = k
    norm = math.sqrt(max(best * (1.0 - c), 1e-300))
    dot = 0.0
    for k in range(3):
        a = (0.5 * (R[k, i] + R[i, k]) - (c if k == i else 0.0)) / norm
        out[off + k] = a
        dot += a * (wx if k == 0 else (wy if k == 1 else wz))
    if dot < 0.0:
        angle = -angle
    for k in range(3):
        out[off + k] *= angle


@njit(cache=True)
def rotvec_from_matrix(R):
    """Log map: rotation vector (3,) [rad] of a rotation matrix (3, 3)."""
    out = np.empty(3)
    log_map_into(R, out, 0)
    return out


@njit(cache=True)
def forward_kinematics(parent, offset, rotation, axis, dof, q, root, W, R, p):
    """World frames into ``R`` (n, 3, 3), ``p`` (n, 3), with frame ``root`` at ``W`` (4, 4).

    A root of -1 leaves the skeleton where its definition puts it.
    """
    n = parent.shape[0]
    for i in range(n):
        d = dof[i]
        k = parent[i]
        if d >= 0:
            ax = axis[i, 0]
            ay = axis[i, 1]
            az = axis[i, 2]
            sn = math.sin(q[d])
            cs = math.cos(q[d])
            t = 1.0 - cs
            # Rodrigues for the DOF's rotation.
            r00 = t * ax * ax + cs
            r01 = t * ax * ay - sn * az
            r02 = t * ax * az + sn * ay
            r10 = t * ax * ay + sn * az
            r11 = t * ay * ay + cs
            r12 = t * ay * az - sn * ax
            r20 = t * ax * az - sn * ay
            r21 = t * ay * az + sn * ax
            r22 = t * az * az + cs
        else:
            r00 = r11 = r22 = 1.0
            r01 = r02 = r10 = r12 = r20 = r21 = 0.0
        # parent_from_frame rotation = fixed rotation @ DOF rotation; world = R[parent] @ that.
        for a in range(3):
            if k < 0:
                m0 = rotation[i, a, 0]
                m1 = rotation[i, a, 1]
                m2 = rotation[i, a, 2]
                p[i, a] = offset[i, a]
            else:
                m0 = R[k, a, 0] * rotation[i, 0, 0] + R[k, a, 1] * rotation[i, 1, 0] + R[k, a, 2] * rotation[i, 2, 0]
                m1 = R[k, a, 0] * rotation[i, 0, 1] + R[k, a, 1] * rotation[i, 1, 1] + R[k, a, 2] * rotation[i, 2, 1]
                m2 = R[k, a, 0] * rotation[i, 0, 2] + R[k, a, 1] * rotation[i, 1, 2] + R[k, a, 2] * rotation[i, 2, 2]
                p[i, a] = p[k, a] + R[k, a, 0] * offset[i, 0] + R[k, a, 1] * offset[i, 1] + R[k, a, 2] * offset[i, 2]
            R[i, a, 0] = m0 * r00 + m1 * r10 + m2 * r20
            R[i, a, 1] = m0 * r01 + m1 * r11 + m2 * r21
            R[i, a, 2] = m0 * r02 + m1 * r12 + m2 * r22
    if root < 0:
        return
    # world_from_model = W @ inv(model_from_root), applied to every frame.
    g00 = W[0, 0] * R[root, 0, 0] + W[0, 1] * R[root, 0, 1] + W[0, 2] * R[root, 0, 2]
    g01 = W[0, 0] * R[root, 1, 0] + W[0, 1] * R[root, 1, 1] + W[0, 2] * R[root, 1, 2]
    g02 = W[0, 0] * R[root, 2, 0] + W[0, 1] * R[root, 2, 1] + W[0, 2] * R[root, 2, 2]
    g10 = W[1, 0] * R[root, 0, 0] + W[1, 1] * R[root, 0, 1] + W[1, 2] * R[root, 0, 2]
    g11 = W[1, 0] * R[root, 1, 0] + W[1, 1] * R[root, 1, 1] + W[1, 2] * R[root, 1, 2]
    g12 = W[1, 0] * R[root, 2, 0] + W[1, 1] * R[root, 2, 1] + W[1, 2] * R[root, 2, 2]
    g20 = W[2, 0] * R[root, 0, 0] + W[2, 1] * R[root, 0, 1] + W[2, 2] * R[root, 0, 2]
    g21 = W[2, 0] * R[root, 1, 0] + W[2, 1] * R[root, 1, 1] + W[2, 2] * R[root, 1, 2]
    g22 = W[2, 0] * R[root, 2, 0] + W[2, 1] * R[root, 2, 1] + W[2, 2] * R[root, 2, 2]
    rx = p[root, 0]
    ry = p[root, 1]
    rz = p[root, 2]
    gx = W[0, 3] - (g00 * rx + g01 * ry + g02 * rz)
    gy = W[1, 3] - (g10 * rx + g11 * ry + g12 * rz)
    gz = W[2, 3] - (g20 * rx + g21 * ry + g22 * rz)
    for i in range(n):
        px = p[i, 0]
        py = p[i, 1]
        pz = p[i, 2]
        p[i, 0] = gx + g00 * px + g01 * py + g02 * pz
        p[i, 1] = gy + g10 * px + g11 * py + g12 * pz
        p[i, 2] = gz + g20 * px + g21 * py + g22 * pz
        for b in range(3):
            c0 = R[i, 0, b]
            c1 = R[i, 1, b]
            c2 = R[i, 2, b]
            R[i, 0, b] = g00 * c0 + g01 * c1 + g02 * c2
            R[i, 1, b] = g10 * c0 + g11 * c1 + g12 * c2
            R[i, 2, b] = g20 * c0 + g21 * c1 + g22 * c2


@njit(cache=True)
def effector_errors(R, p, eff_frame, target_p, target_R, row_w, e, err, M):
    """Error vector ``e`` (6m,) (target minus current) and per-effector errors ``err`` (2, m).

    Returns the weighted cost ``0.5 * sum(row_w * e**2)``. ``err`` (2, m)
    holds position errors [m] then orientation errors [rad]. ``M`` (3, 3) is scratch.
    """
    m = eff_frame.shape[0]
    cost = 0.0
    for k in range(m):
        f = eff_frame[k]
        for a in range(3):
            e[6 * k + a] = target_p[k, a] - p[f, a]
        # Orientation error: log(target @ current^T), a world-frame rotation vector.
        for a in range(3):
            for b in range(3):
                M[a, b] = target_R[k, a, 0] * R[f, b, 0] + target_R[k, a, 1] * R[f, b, 1] + target_R[k, a, 2] * R[f, b, 2]
        log_map_into(M, e, 6 * k + 3)
        err[0, k] = math.sqrt(e[6 * k] ** 2 + e[6 * k + 1] ** 2 + e[6 * k + 2] ** 2)
        err[1, k] = math.sqrt(e[6 * k + 3] ** 2 + e[6 * k + 4] ** 2 + e[6 * k + 5] ** 2)
        for r in range(6):
            cost += 0.5 * row_w[k, r] * e[6 * k + r] ** 2
    return cost


@njit(cache=True)
def jacobian(R, p, axis, dof_frame, eff_frame, sign, eff_dofs, eff_n, J):
    """Fill ``J`` (6m, n_dofs): ``+-[r_d x (e - p_d); r_d]`` where DOF ``d`` moves effector ``e``.

    ``r_d`` is the DOF's world axis and ``p_d`` its world position.
    """
    J[:, :] = 0.0
    m = eff_frame.shape[0]
    for k in range(m):
        f = eff_frame[k]
        for t in range(eff_n[k]):
            d = eff_dofs[k, t]
            g = dof_frame[d]
            s = sign[k, d]
            rx = R[g, 0, 0] * axis[g, 0] + R[g, 0, 1] * axis[g, 1] + R[g, 0, 2] * axis[g, 2]
            ry = R[g, 1, 0] * axis[g, 0] + R[g, 1, 1] * axis[g, 1] + R[g, 1, 2] * axis[g, 2]
            rz = R[g, 2, 0] * axis[g, 0] + R[g, 2, 1] * axis[g, 1] + R[g, 2, 2] * axis[g, 2]
            dx = p[f, 0] - p[g, 0]
            dy = p[f, 1] - p[g, 1]
            dz = p[f, 2] - p[g, 2]
            J[6 * k + 0, d] = s * (ry * dz - rz * dy)
            J[6 * k + 1, d] = s * (rz * dx - rx * dz)
            J[6 * k + 2, d] = s * (rx * dy - ry * dx)
            J[6 * k + 3, d] = s * rx
            J[6 * k + 4, d] = s * ry
            J[6 * k + 5, d] = s * rz


@njit(cache=True)
def linear_system(R, p, axis, dof_frame, eff_frame, sign, eff_dofs, eff_n, e, row_w, A, b, v):
    """``A = J^T W J`` and ``b = J^T W e`` straight from the frames, never forming J.

    Same numbers as ``J^T W J`` from :func:`jacobian`; each
    effector's Jacobian block is built compactly, (dofs on its path, 6),
    so the products run over contiguous memory. ``v`` (2, n_dofs, 6) is scratch.
    """
    A[:, :] = 0.0
    b[:] = 0.0
    m = eff_frame.shape[0]
    for k in range(m):
        f = eff_frame[k]
        n_k = eff_n[k]
        for t in range(n_k):
            d = eff_dofs[k, t]
            g = dof_frame[d]
            s = sign[k, d]
            rx = s * (R[g, 0, 0] * axis[g, 0] + R[g, 0, 1] * axis[g, 1] + R[g, 0, 2] * axis[g, 2])
            ry = s * (R[g, 1, 0] * axis[g, 0] + R[g, 1, 1] * axis[g, 1] + R[g, 1, 2] * axis[g, 2])
            rz = s * (R[g, 2, 0] * axis[g, 0] + R[g, 2, 1] * axis[g, 1] + R[g, 2, 2] * axis[g, 2])
            dx = p[f, 0] - p[g, 0]
            dy = p[f, 1] - p[g, 1]
            dz = p[f, 2] - p[g, 2]
            v[0, t, 0] = ry * dz - rz * dy
            v[0, t, 1] = rz * dx - rx * dz
            v[0, t, 2] = rx * dy - ry * dx
            v[0, t, 3] = rx
            v[0, t, 4] = ry
            v[0, t, 5] = rz
            acc = 0.0
            for r in range(6):
                w = row_w[k, r] * v[0, t, r]
                v[1, t, r] = w
                acc += w * e[6 * k + r]
            b[d] += acc
        for t in range(n_k):
            d1 = eff_dofs[k, t]
            for u in range(t, n_k):
                d2 = eff_dofs[k, u]
                acc = (v[1, t, 0] * v[0, u, 0] + v[1, t, 1] * v[0, u, 1] + v[1, t, 2] * v[0, u, 2]
                       + v[1, t, 3] * v[0, u, 3] + v[1, t, 4] * v[0, u, 4] + v[1, t, 5] * v[0, u, 5])
                A[d1, d2] += acc
                if d1 != d2:
                    A[d2, d1] += acc


@njit(cache=True, inline="always")
def _row_residual(A, b, x, i, n):
    """``b[i] - A[i] @ x`` with four accumulators: the add chain, not the multiplies, bounds a sweep."""
    r0 = b[i]
    r1 = 0.0
    r2 = 0.0
    r3 = 0.0
    j = 0
    while j + 4 <= n:
        r0 -= A[i, j] * x[j]
        r1 -= A[i, j + 1] * x[j + 1]
        r2 -= A[i, j + 2] * x[j + 2]
        r3 -= A[i, j + 3] * x[j + 3]
        j += 4
    while j < n:
        r0 -= A[i, j] * x[j]
        j += 1
    return (r0 + r1) + (r2 + r3)


@njit(cache=True)
def _projected_residual(A, b, x, lo, hi):
    """``|b - A x|`` over the unknowns not held at a bound by an outward-pointing residual."""
    res2 = 0.0
    n = b.shape[0]
    for i in range(n):
        r = _row_residual(A, b, x, i, n)
        if not ((x[i] <= lo[i] and r < 0.0) or (x[i] >= hi[i] and r > 0.0)):
            res2 += r * r
    return math.sqrt(res2)


@njit(cache=True)
def projected_gauss_seidel(A, b, x, lo, hi, sweeps, res_tol, upd_tol, x_prev, stall_tol, stats):
    """Projected Gauss-Seidel on ``A x = b`` with ``lo <= x <= hi``, in place on ``x``.

    Stops at the first of the paper's four tests: ``sweeps`` done; the
    projected residual ``|b - A x|`` below ``res_tol``; the sweep's change
    ``|dx|`` below ``upd_tol``; ``|x - x_prev|`` (the previous frame's
    solution) below ``stall_tol``. A tolerance <= 0 disables its test.
    Writes sweeps, residual and last change into ``stats``.
    """
    n = b.shape[0]
    res = 0.0
    upd = 0.0
    it = 0
    for it in range(1, sweeps + 1):
        res2 = 0.0
        upd2 = 0.0
        for i in range(n):
            r = _row_residual(A, b, x, i, n)
            xi = x[i] + r / A[i, i]
            if xi < lo[i]:
                xi = lo[i]
            elif xi > hi[i]:
                xi = hi[i]
            # A component held at a bound by a residual pushing outward satisfies its KKT condition.
            if not ((xi <= lo[i] and r < 0.0) or (xi >= hi[i] and r > 0.0)):
                res2 += r * r
            dx = xi - x[i]
            upd2 += dx * dx
            x[i] = xi
        res = math.sqrt(res2)
        upd = math.sqrt(upd2)
        if upd < upd_tol:
            break
        if res < res_tol:
            # The in-sweep estimate lags (each r_i saw only part of the sweep's updates); confirm it.
            res = _projected_residual(A, b, x, lo, hi)
            if res < res_tol:
                break
        if stall_tol > 0.0:
            d2 = 0.0
            for i in range(n):
                d2 += (x[i] - x_prev[i]) ** 2
            if math.sqrt(d2) < stall_tol:
                break
    stats[O_SWEEPS] = it
    stats[O_RESIDUAL] = res
    stats[O_UPDATE] = upd


@njit(cache=True)
def _finish_errors(row_w, err, pos_tol, ori_tol):
    """Zero the errors of unused rows (no target, position only); True if all are within tolerance."""
    ok = True
    for k in range(err.shape[1]):
        if row_w[k, 0] <= 0.0:
            err[0, k] = 0.0
        elif err[0, k] > pos_tol:
            ok = False
        if row_w[k, 3] <= 0.0:
            err[1, k] = 0.0
        elif err[1, k] > ori_tol:
            ok = False
    return ok


@njit(cache=True)
def _add_clamped(q, x, lower, upper, out):
    """``out = clip(q + x, lower, upper)``: the bounds on x keep q + x inside up to one rounding."""
    for i in range(q.shape[0]):
        out[i] = min(max(q[i] + x[i], lower[i]), upper[i])


@njit(cache=True)
def _bounds(q, lower, upper, max_step, lo, hi):
    for i in range(q.shape[0]):
        lo[i] = lower[i] - q[i]
        hi[i] = upper[i] - q[i]
        if max_step > 0.0:
            lo[i] = max(lo[i], -max_step)
            hi[i] = min(hi[i], max_step)
        # Rounding can leave q a hair outside its limits; never ask PGS for an empty box.
        if lo[i] > 0.0:
            lo[i] = 0.0
        if hi[i] < 0.0:
            hi[i] = 0.0


@njit(cache=True)
def _evaluate(model, q, root, W, target_p, target_R, row_w, R, p, e, err, M):
    parent, offset, rotation, axis, dof, dof_frame, lower, upper, eff_frame, sign, eff_dofs, eff_n = model
    forward_kinematics(parent, offset, rotation, axis, dof, q, root, W, R, p)
    return effector_errors(R, p, eff_frame, target_p, target_R, row_w, e, err, M)


def workspace_size(n_frames: int, n_dofs: int, n_effectors: int) -> int:
    """Length of the float scratch buffer :func:`step` and :func:`solve` carve up (see :func:`_carve`)."""
    n, m = n_dofs, n_effectors
    return 6 * m + 2 * n * n + 6 * n + 12 * n_frames + 2 * m + 9 + 12 * n


@njit(cache=True)
def _carve(work, n_frames, n, m):
    """Views into the scratch buffer: no allocation in the per-frame path."""
    o = 0
    e = work[o:o + 6 * m]
    o += 6 * m
    A = work[o:o + n * n].reshape((n, n))
    o += n * n
    Al = work[o:o + n * n].reshape((n, n))
    o += n * n
    b = work[o:o + n]
    lo = work[o + n:o + 2 * n]
    hi = work[o + 2 * n:o + 3 * n]
    x_prev = work[o + 3 * n:o + 4 * n]
    q_new = work[o + 4 * n:o + 5 * n]
    x2 = work[o + 5 * n:o + 6 * n]
    o += 6 * n
    R2 = work[o:o + 9 * n_frames].reshape((n_frames, 3, 3))
    o += 9 * n_frames
    p2 = work[o:o + 3 * n_frames].reshape((n_frames, 3))
    o += 3 * n_frames
    err2 = work[o:o + 2 * m].reshape((2, m))
    o += 2 * m
    M = work[o:o + 9].reshape((3, 3))
    o += 9
    v = work[o:o + 12 * n].reshape((2, n, 6))
    return e, A, Al, b, lo, hi, x_prev, q_new, x2, R2, p2, err2, M, v


@njit(cache=True)
def step(model, root, W, target_p, target_R, row_w, q, x, lam_state, settings, R, p, err, stats, work):
    """One frame: linearise at ``q``, solve the damped normal equations by PGS, update ``q``.

    ``R``, ``p`` must hold the world frames at the incoming ``q``; on return
    they hold the frames at the new ``q`` and ``err`` (2, m) its errors.
    ``x`` (n_dofs,) carries the previous frame's step in (the warm start) and
    this frame's step out. ``lam_state`` (1,) is the adaptive damping carried
    between frames. ``work`` is scratch of :func:`workspace_size`.
    """
    parent, offset, rotation, axis, dof, dof_frame, lower, upper, eff_frame, sign, eff_dofs, eff_n = model
    n = q.shape[0]
    e, A, Al, b, lo, hi, x_prev, q_new, x2, R2, p2, err2, M, v = _carve(work, R.shape[0], n, eff_frame.shape[0])
    damping = settings[S_DAMPING]
    adaptive = settings[S_ADAPTIVE] > 0.0
    cost0 = effector_errors(R, p, eff_frame, target_p, target_R, row_w, e, err, M)
    err2[:, :] = err
    if _finish_errors(row_w, err2, settings[S_POS_TOL], settings[S_ORI_TOL]):
        # Nothing to do: an idle frame costs one error evaluation.
        err[:, :] = err2
        x[:] = 0.0
        stats[O_SWEEPS] = 0
        stats[O_ITERATIONS] = 0
        stats[O_RESIDUAL] = 0.0
        stats[O_COST] = cost0
        stats[O_STEP_NORM] = 0.0
        stats[O_ACCEPTED] = 1.0
        stats[O_STATUS] = CONVERGED
        return
    linear_system(R, p, axis, dof_frame, eff_frame, sign, eff_dofs, eff_n, e, row_w, A, b, v)
    lam = lam_state[0] if adaptive else damping
    for i in range(n):
        A[i, i] += lam
    _bounds(q, lower, upper, settings[S_MAX_STEP], lo, hi)
    x_prev[:] = x
    if settings[S_WARM] > 0.0:
        for i in range(n):
            x[i] = min(max(x[i], lo[i]), hi[i])
    else:
        x[:] = 0.0
    if settings[S_SUBSPACE] > 0.0:
        bounded_solve(A, b, x, lo, hi, int(settings[S_SWEEPS]), stats)
    else:
        projected_gauss_seidel(A, b, x, lo, hi, int(settings[S_SWEEPS]), settings[S_RES_TOL], settings[S_UPD_TOL],
                               x_prev, settings[S_STALL_TOL], stats)
    _add_clamped(q, x, lower, upper, q_new)
    cost = _evaluate(model, q_new, root, W, target_p, target_R, row_w, R2, p2, e, err2, M)
    accepted = 1.0
    if adaptive:
        # Levenberg-style safeguard: a step that raises the error is halved, then refused,
        # and the damping grows; so a held target can only settle, never oscillate.
        tries = 0
        while cost > cost0 and tries < 3:
            for i in range(n):
                x[i] *= 0.5
            _add_clamped(q, x, lower, upper, q_new)
            cost = _evaluate(model, q_new, root, W, target_p, target_R, row_w, R2, p2, e, err2, M)
            tries += 1
        if cost > cost0:
            accepted = 0.0
            x[:] = 0.0
            lam_state[0] = min(lam * 10.0, 1e6)
            cost = cost0
        elif cost0 - cost <= settings[S_SETTLE_TOL] * cost0:
            # So little left to gain that the pose is held: a best reach settles instead of creeping.
            accepted = 0.0
            x[:] = 0.0
            cost = cost0
        else:
            lam_state[0] = max(lam * (0.5 if tries == 0 else 4.0), damping * ADAPTIVE_FLOOR)
    if accepted > 0.0:
        for i in range(n):
            q[i] = q_new[i]
        R[:, :, :] = R2
        p[:, :] = p2
        err[:, :] = err2
    step_norm = 0.0
    for i in range(n):
        step_norm += x[i] * x[i]
    step_norm = math.sqrt(step_norm)
    stats[O_COST] = cost
    stats[O_STEP_NORM] = step_norm
    stats[O_ACCEPTED] = accepted
    stats[O_LAMBDA] = lam
    stats[O_ITERATIONS] = stats[O_SWEEPS]
    if _finish_errors(row_w, err, settings[S_POS_TOL], settings[S_ORI_TOL]):
        stats[O_STATUS] = CONVERGED
    elif accepted == 0.0 or step_norm <= max(settings[S_STALL_TOL], 1e-12) * 1e3:
        stats[O_STATUS] = STALLED
    else:
        stats[O_STATUS] = BUDGET_EXHAUSTED


@njit(cache=True)
def _cholesky_solve(M, r, nf):
    """Solve ``M[:nf, :nf] y = r[:nf]`` in place in ``r`` (M SPD; overwritten). False if not SPD."""
    for j in range(nf):
        d = M[j, j]
        for k in range(j):
            d -= M[j, k] * M[j, k]
        if d <= 0.0:
            return False
        d = math.sqrt(d)
        M[j, j] = d
        for i in range(j + 1, nf):
            v = M[i, j]
            for k in range(j):
                v -= M[i, k] * M[j, k]
            M[i, j] = v / d
    for i in range(nf):
        v = r[i]
        for k in range(i):
            v -= M[i, k] * r[k]
        r[i] = v / M[i, i]
    for i in range(nf - 1, -1, -1):
        v = r[i]
        for k in range(i + 1, nf):
            v -= M[k, i] * r[k]
        r[i] = v / M[i, i]
    return True


@njit(cache=True)
def bounded_solve(A, b, x, lo, hi, sweeps, stats):
    """Minimise ``0.5 x^T A x - b^T x`` with ``lo <= x <= hi``: PGS with subspace minimisation.

    PGS sweeps find which unknowns sit on a bound; the others (the free set)
    are then solved exactly by Cholesky and projected back into the box,
    a few rounds, and a last PGS pass settles the bounds. Plain PGS needs
    thousands of sweeps on the ill-conditioned systems near a solution;
    this reaches the exact bounded minimiser in a few rounds.
    """
    n = b.shape[0]
    projected_gauss_seidel(A, b, x, lo, hi, sweeps, 0.0, 0.0, x, 0.0, stats)
    total = int(stats[O_SWEEPS])
    free = np.empty(n, dtype=np.int64)
    is_free = np.zeros(n, dtype=np.bool_)
    M = np.empty((n, n))
    r = np.empty(n)
    for _ in range(8):
        nf = 0
        for i in range(n):
            g = -b[i]
            for j in range(n):
                g += A[i, j] * x[j]
            if (x[i] > lo[i] and x[i] < hi[i]) or (x[i] <= lo[i] and g < 0.0) or (x[i] >= hi[i] and g > 0.0):
                free[nf] = i
                nf += 1
        if nf == 0:
            break
        is_free[:] = False
        for a in range(nf):
            is_free[free[a]] = True
        for a in range(nf):
            i = free[a]
            v = b[i]
            for j in range(n):
                if not is_free[j]:
                    v -= A[i, j] * x[j]
            r[a] = v
            for c in range(nf):
                M[a, c] = A[i, free[c]]
        if not _cholesky_solve(M, r, nf):
            break
        inside = True
        for a in range(nf):
            i = free[a]
            v = r[a]
            if v < lo[i]:
                v = lo[i]
                inside = False
            elif v > hi[i]:
                v = hi[i]
                inside = False
            x[i] = v
        if inside:
            break
    projected_gauss_seidel(A, b, x, lo, hi, 3, 0.0, 0.0, x, 0.0, stats)
    stats[O_SWEEPS] = total + int(stats[O_SWEEPS])


@njit(cache=True)
def solve(model, root, W, target_p, target_R, row_w, q, settings, max_iterations, R, p, err, stats, work):
    """Levenberg-Marquardt over bounded steps until the targets are met or progress stops.

    Each iteration linearises, solves ``(J^T W J + lam I) x = J^T W e`` within
    the limits (:func:`bounded_solve`), and keeps the step only if the
    weighted error falls; else ``lam`` grows and it tries again. Sets
    ``stats[O_STATUS]`` (converged; stalled: no step lowers the error or the
    pose stopped changing, a best reach; budget exhausted),
    ``stats[O_ITERATIONS]``, ``stats[O_SWEEPS]`` and ``stats[O_COST]``.
    """
    parent, offset, rotation, axis, dof, dof_frame, lower, upper, eff_frame, sign, eff_dofs, eff_n = model
    n = q.shape[0]
    m = eff_frame.shape[0]
    e, A, Al, b, lo, hi, x_prev, q_try, x, R2, p2, err2, M, v = _carve(work, R.shape[0], n, m)
    x[:] = 0.0
    pgs_stats = np.zeros(N_STATS)
    damping = settings[S_DAMPING]
    pos_tol = settings[S_POS_TOL]
    ori_tol = settings[S_ORI_TOL]
    lam = max(damping, 1e-3)
    sweeps = int(settings[S_SWEEPS])
    cost = _evaluate(model, q, root, W, target_p, target_R, row_w, R, p, e, err, M)
    total_sweeps = 0
    status = BUDGET_EXHAUSTED
    it = 0
    for it in range(max_iterations + 1):
        err2[:, :] = err
        if _finish_errors(row_w, err2, pos_tol, ori_tol):
            status = CONVERGED
            break
        if it == max_iterations:
            break
        linear_system(R, p, axis, dof_frame, eff_frame, sign, eff_dofs, eff_n, e, row_w, A, b, v)
        _bounds(q, lower, upper, settings[S_MAX_STEP], lo, hi)
        accepted = False
        settled = False
        while lam < 1e8:
            Al[:, :] = A
            for i in range(n):
                Al[i, i] += lam
            x[:] = 0.0
            bounded_solve(Al, b, x, lo, hi, sweeps, pgs_stats)
            total_sweeps += int(pgs_stats[O_SWEEPS])
            _add_clamped(q, x, lower, upper, q_try)
            c = _evaluate(model, q_try, root, W, target_p, target_R, row_w, R2, p2, e, err2, M)
            if c < cost:
                accepted = True
                settled = cost - c <= settings[S_SETTLE_TOL] * cost
                cost = c
                q[:] = q_try
                R[:, :, :] = R2
                p[:, :] = p2
                err[:, :] = err2
                lam = max(lam * 0.3, 1e-9)
                break
            lam *= 5.0
        if not accepted or settled or math.sqrt(np.sum(x * x)) < settings[S_STALL_TOL]:
            status = STALLED
            break
    # e and err must describe the final q (a refused trial overwrote them).
    cost = _evaluate(model, q, root, W, target_p, target_R, row_w, R, p, e, err, M)
    _finish_errors(row_w, err, pos_tol, ori_tol)
    if status == STALLED and _finish_errors(row_w, err2, pos_tol, ori_tol):
        status = CONVERGED
    stats[O_STATUS] = status
    stats[O_ITERATIONS] = it
    stats[O_SWEEPS] = total_sweeps
    stats[O_COST] = cost
    stats[O_STEP_NORM] = math.sqrt(np.sum(x * x))
