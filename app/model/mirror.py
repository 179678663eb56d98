"""Mirroring a pose from one side of the body onto the other."""

from __future__ import annotations

import numpy as np

import gsik


def mirror_map(skeleton: gsik.Skeleton, source: str) -> list[tuple[int, int, float]]:
    """``(from_dof, to_dof, sign)`` copying the ``source`` side's angles to the other side.

    The two sides are mirror images in the plane x = 0 (the biped's sagittal
    plane). Reflecting a rotation about axis ``a`` gives the rotation about
    ``-M a`` by the same angle (``M`` = diag(-1, 1, 1)), so a pitch (x) keeps
    its sign and a roll (y) or twist (z) changes it. DOFs whose counterpart
    has an axis that is not the mirror image are skipped.
    """
    if source not in ("left", "right"):
        raise ValueError(f"mirror source must be 'left' or 'right', got {source!r}")
    other = "right" if source == "left" else "left"
    M = np.diag([-1.0, 1.0, 1.0])
    out = []
    for i, name in enumerate(skeleton.dof_names):
        if not name.startswith(source + "_"):
            continue
        twin = other + name[len(source):]
        if twin not in skeleton.dof_names:
            continue
        j = skeleton.dof_names.index(twin)
        a = -M @ skeleton.frame_axis[skeleton.dof_frame[i]]
        b = skeleton.frame_axis[skeleton.dof_frame[j]]
        d = float(a @ b)
        if abs(abs(d) - 1.0) < 1e-6:
            out.append((i, j, 1.0 if d > 0 else -1.0))
    return out
