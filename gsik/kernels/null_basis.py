"""The free basis of the strict-priority step (:mod:`gsik.kernels.priority`) turned: below a level, and when a DOF
locks at the box.

The free directions are the rows of :class:`gsik.kernels.priority.Work`'s ``Zt`` (one a row, ``Zt[z0:z0 + rz]``
live). Below a level of rank ``k`` they are ``Z Q[:, k:]`` (:func:`null_basis`); a DOF held at a bound drops the one
direction that moves it (:func:`without_dof`, with ``(J Z)^T`` turned alike by :func:`reflect_rows`).
"""

from __future__ import annotations

import math

from gsik._jit import njit
from gsik.kernels.rows import axpy1, rank1, reflect


@njit(cache=True, _nrt=False)
def identity_into(Zt, n):
    """``Zt[:n, :n]`` the identity: the unstored first basis, stored."""
    for i in range(n):
        for d in range(n):
            Zt[i, d] = 0.0
        Zt[i, i] = 1.0


@njit(cache=True, _nrt=False)
def null_basis(wk, k, ra, z0):
    """The free basis below this level, ``(Z Q)^T`` with ``Q = H_0 ... H_(k-1)``: the reflections applied to the
    ``ra`` directions the level sees (rows of ``wk.Zt`` from ``z0``) in place, first to last; rows from ``z0 + k`` on
    then span the directions left free (``Z Q[:, k:]``, then those it does not see), rows ``z0 ... z0 + k - 1`` the
    level's row space. Only the columns where those rows have nonzeros are turned."""
    Zt = wk.Zt
    n = Zt.shape[1]
    first, end = n, 0
    for c in range(z0, z0 + ra):
        for d in range(first):
            if Zt[c, d] != 0.0:
                first = d
                break
        for d in range(n - 1, end - 1, -1):
            if Zt[c, d] != 0.0:
                end = d + 1
                break
    for j in range(k):
        reflect(Zt, z0, wk.V, j, wk.beta[j], j, ra, first, end, wk.zw)


@njit(cache=True, _nrt=False)
def without_dof(Zt, z0, rz, dof, u, w):
    """Turn the live rows of ``Zt`` by the reflection ``I - scale u u^T`` (``u`` (rz,) filled here) so that only the
    first moves DOF ``dof``; returns ``scale`` (the caller then drops that row), or 0 when no row moves it.
    ``w``: (n,) scratch."""
    n = Zt.shape[1]
    s2 = 0.0
    for c in range(rz):
        s2 += Zt[z0 + c, dof] * Zt[z0 + c, dof]
    norm = math.sqrt(s2)
    if norm < 1e-12:
        return 0.0
    # The reflection maps the column's direction onto the first axis; the other rows span its complement.
    uu = 0.0
    for c in range(rz):
        u[c] = Zt[z0 + c, dof] / norm
    u[0] += 1.0 if u[0] >= 0.0 else -1.0
    for c in range(rz):
        uu += u[c] * u[c]
    scale = 2.0 / uu
    w[:] = 0.0
    for c in range(rz):
        if u[c] != 0.0:  # a zero adds exactly nothing
            axpy1(w, u[c], Zt, z0 + c, 0, n)
    for c in range(rz):
        if u[c] != 0.0:
            rank1(Zt, z0 + c, -scale * u[c], w, 0, n)
        Zt[z0 + c, dof] = 0.0  # exactly, not to rounding
    return scale


@njit(cache=True, _nrt=False)
def reflect_rows(AT0, m, rz, u, scale, w):
    """``AT0 = ((I - scale u u^T) AT0)[1:]``: ``(J Z)^T`` after :func:`without_dof` turned ``Z``, without the
    product. ``w``: (m,) scratch."""
    for i in range(m):
        w[i] = 0.0
    for c in range(rz):
        axpy1(w, u[c], AT0, c, 0, m)
    for c in range(1, rz):
        for i in range(m):
            AT0[c - 1, i] = AT0[c, i] - scale * u[c] * w[i]
