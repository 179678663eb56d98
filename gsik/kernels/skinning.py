"""Linear blend skinning's per-vertex loop, compiled (see :mod:`gsik.skinning` for the maths and the contract)."""

from __future__ import annotations

import math

import numpy as np

from gsik._jit import njit


@njit(cache=True)
def blend_skin(M: np.ndarray, slots: np.ndarray, weights: np.ndarray, positions: np.ndarray,
               normals: np.ndarray, out_points: np.ndarray, out_normals: np.ndarray) -> None:
    """Skin every vertex: ``M`` (n_slots, 3, 4) slot matrices, ``slots``/``weights`` (n, k), bind ``positions``
    and ``normals`` (n, 3); writes ``out_points`` and unit ``out_normals`` (n, 3) in place."""
    n, k = slots.shape
    for v in range(n):
        px = py = pz = nx = ny = nz = 0.0
        x, y, z = positions[v, 0], positions[v, 1], positions[v, 2]
        a, b, c = normals[v, 0], normals[v, 1], normals[v, 2]
        for i in range(k):
            w = weights[v, i]
            if w == 0.0:
                continue
            s = slots[v, i]
            px += w * (M[s, 0, 0] * x + M[s, 0, 1] * y + M[s, 0, 2] * z + M[s, 0, 3])
            py += w * (M[s, 1, 0] * x + M[s, 1, 1] * y + M[s, 1, 2] * z + M[s, 1, 3])
            pz += w * (M[s, 2, 0] * x + M[s, 2, 1] * y + M[s, 2, 2] * z + M[s, 2, 3])
            nx += w * (M[s, 0, 0] * a + M[s, 0, 1] * b + M[s, 0, 2] * c)
            ny += w * (M[s, 1, 0] * a + M[s, 1, 1] * b + M[s, 1, 2] * c)
            nz += w * (M[s, 2, 0] * a + M[s, 2, 1] * b + M[s, 2, 2] * c)
        out_points[v, 0], out_points[v, 1], out_points[v, 2] = px, py, pz
        length = max(math.sqrt(nx * nx + ny * ny + nz * nz), 1e-12)
        out_normals[v, 0], out_normals[v, 1], out_normals[v, 2] = nx / length, ny / length, nz / length
