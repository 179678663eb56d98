"""Kinematics kernels: forward kinematics, effector errors, the Jacobian, the normal equations.

Conventions: ``R`` (n_frames, 3, 3) and ``p`` (n_frames, 3) hold world
rotations and positions [m]; an effector's 6 rows are 3 position rows then 3
orientation rows; ``sign[e, d]`` is +1 where DOF ``d`` lies above effector
``e`` but not above the root, -1 where it lies above the root but not above
the effector (it turns the other way round seen from the root), else 0.

The kernels that only read and write arrays they are given are compiled without numba's reference counting
(``_nrt=False``): each array argument and each array taken from a tuple was otherwise counted up and down with
atomic operations, about half of a chain's compiled frame step (their callers hold the arrays for the call).
"""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit


@njit(cache=True, _nrt=False)
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


@njit(cache=True, _nrt=False)
def forward_kinematics(model, q, root, W, R, p):
    """World frames of :class:`~gsik.kernels.KinematicModel` ``model`` at ``q`` (n_dofs,) [rad] into
    ``R`` (n, 3, 3), ``p`` (n, 3) [m], with frame ``root`` at ``W`` (4, 4).

    A root of -1 leaves the skeleton where its definition puts it.
    """
    frames_into(model.frame_parent, model.frame_offset, model.frame_rotation, model.frame_axis, model.frame_dof,
                q, root, W, R, p)


@njit(cache=True, inline="always")
def _axis_rotation(axis, i, angle):
    """The rotation by ``angle`` [rad] about the unit ``axis[i]`` (Rodrigues), its 9 entries row by row."""
    ax = axis[i, 0]
    ay = axis[i, 1]
    az = axis[i, 2]
    sn = math.sin(angle)
    cs = math.cos(angle)
    t = 1.0 - cs
    return (t * ax * ax + cs, t * ax * ay - sn * az, t * ax * az + sn * ay,
            t * ax * ay + sn * az, t * ay * ay + cs, t * ay * az - sn * ax,
            t * ax * az - sn * ay, t * ay * az + sn * ax, t * az * az + cs)


@njit(cache=True, inline="always")
def _identity(rotation, i):
    """True if the fixed rotation ``rotation[i]`` (3, 3) is exactly the identity (a site, most URDF joints)."""
    return (rotation[i, 0, 0] == 1.0 and rotation[i, 1, 1] == 1.0 and rotation[i, 2, 2] == 1.0
            and rotation[i, 0, 1] == 0.0 and rotation[i, 0, 2] == 0.0 and rotation[i, 1, 0] == 0.0
            and rotation[i, 1, 2] == 0.0 and rotation[i, 2, 0] == 0.0 and rotation[i, 2, 1] == 0.0)


@njit(cache=True, inline="always")
def _turned_child(R, p, k, i, offset, axis, q, d):
    """Frame ``i`` of parent ``k`` whose fixed rotation is the identity: ``R[k]`` turned by its DOF ``d`` (none:
    -1). The same numbers as the general product with the identity (``x * 1 + y * 0 + z * 0 == x``), for a
    third of its work; the position as the general case computes it."""
    for a in range(3):
        p[i, a] = p[k, a] + R[k, a, 0] * offset[i, 0] + R[k, a, 1] * offset[i, 1] + R[k, a, 2] * offset[i, 2]
    if d < 0:
        for a in range(3):
            R[i, a, 0] = R[k, a, 0]
            R[i, a, 1] = R[k, a, 1]
            R[i, a, 2] = R[k, a, 2]
        return
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = _axis_rotation(axis, i, q[d])
    for a in range(3):
        m0 = R[k, a, 0]
        m1 = R[k, a, 1]
        m2 = R[k, a, 2]
        R[i, a, 0] = m0 * r00 + m1 * r10 + m2 * r20
        R[i, a, 1] = m0 * r01 + m1 * r11 + m2 * r21
        R[i, a, 2] = m0 * r02 + m1 * r12 + m2 * r22


@njit(cache=True, _nrt=False)
def frames_into(parent, offset, rotation, axis, dof, q, root, W, R, p):
    """:func:`forward_kinematics` on the model's arrays: the form the solver's inner loop calls
    (a NamedTuple argument is copied and reference-counted field by field on every call)."""
    n = parent.shape[0]
    for i in range(n):
        d = dof[i]
        k = parent[i]
        if k >= 0 and _identity(rotation, i):
            _turned_child(R, p, k, i, offset, axis, q, d)
            continue
        if d >= 0:
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = _axis_rotation(axis, i, q[d])
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
    if (g00 == 1.0 and g11 == 1.0 and g22 == 1.0 and g01 == 0.0 and g02 == 0.0 and g10 == 0.0 and g12 == 0.0
            and g20 == 0.0 and g21 == 0.0 and gx == 0.0 and gy == 0.0 and gz == 0.0):
        return  # the root already where W puts it: the pass below would change no frame (x * 1 + y * 0 == x)
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


@njit(cache=True, _nrt=False)
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
        err[0, k] = math.hypot(math.hypot(e[6 * k], e[6 * k + 1]), e[6 * k + 2])  # no overflow above 1e154
        err[1, k] = math.sqrt(e[6 * k + 3] ** 2 + e[6 * k + 4] ** 2 + e[6 * k + 5] ** 2)
        for r in range(6):
            cost += 0.5 * row_w[k, r] * e[6 * k + r] ** 2
    return cost


@njit(cache=True, _nrt=False)
def jacobian(model, R, p, J):
    """Fill ``J`` (6m, n_dofs): ``+-[r_d x (e - p_d); r_d]`` where DOF ``d`` moves effector ``e``.

    ``r_d`` is the DOF's world axis and ``p_d`` its world position.
    """
    axis, dof_frame, eff_frame, sign = model.frame_axis, model.dof_frame, model.effector_frame, model.sign
    eff_dofs, eff_n = model.effector_dofs, model.effector_dof_count
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


@njit(cache=True, _nrt=False)
def linear_system(model, R, p, e, row_w, A, b, v):
    """``A = J^T W J`` and ``b = J^T W e`` straight from the frames, never forming J.

    Same numbers as ``J^T W J`` from :func:`jacobian`; each
    effector's Jacobian block is built compactly, (dofs on its path, 6),
    so the products run over contiguous memory. ``v`` (2, n_dofs, 6) is scratch.
    """
    axis, dof_frame, eff_frame, sign = model.frame_axis, model.dof_frame, model.effector_frame, model.sign
    eff_dofs, eff_n = model.effector_dofs, model.effector_dof_count
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
