"""Ways to learn a pose prior from several performers: mirrored poses, and the performer normalised away.

Both are measured against the plain Gaussian of :func:`gsik.prior.fit_prior`
by leave-one-performer-out (``benchmarks/bench_prior.py``; the README says
which won):

* :func:`mirror_poses`: every pose's left/right mirror image, so a prior
  learned from poses and mirrors has no handedness.
* :func:`fit_prior_by_performer`: each performer's poses centred on that
  performer's own mean before the covariance is taken (what varies between
  performers, their stance, is not counted as variation of a pose), and the
  mean the average of the performers' means, each performer weighing the same
  however long their clips are.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gsik.errors import PriorError
from gsik.prior import PosePrior, choose_shrinkage, regularised, training_poses
from gsik.skeleton import Skeleton

#: The reflection x -> -x: a gsik skeleton's sagittal plane is x = 0 (its right side is +x; the biped, the
#: humanoid).
MIRROR = np.diag([-1.0, 1.0, 1.0])


def mirror_signs(skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Each DOF's mirror twin (n_dofs,) int and sign (n_dofs,): ``mirrored[:, twin] = sign * q``.

    A ``left_*`` DOF's twin is the ``right_*`` one of the same name and back
    (by name, so on any skeleton: wrists, clavicles, ...); any other DOF is its
    own twin. Reflecting a rotation about axis ``a`` in
    the plane x = 0 gives the rotation about ``-M a`` by the same angle, so a
    pitch (x) keeps its sign and a roll (y) or twist (z) changes it.

    Raises:
        PriorError: a DOF whose twin's axis is not its mirror image.
    """
    names = list(skeleton.dof_names)
    twin = np.arange(len(names))
    sign = np.ones(len(names))
    for i, name in enumerate(names):
        other = {"left_": "right_", "right_": "left_"}
        side = next((s for s in other if name.startswith(s)), None)
        j = names.index(other[side] + name[len(side):]) if side and other[side] + name[len(side):] in names else i
        a = -MIRROR @ skeleton.frame_axis[skeleton.dof_frame[i]]
        d = float(a @ skeleton.frame_axis[skeleton.dof_frame[j]])
        if abs(abs(d) - 1.0) > 1e-6:
            raise PriorError(f"skeleton {skeleton.name!r}: DOF {names[j]!r} is not the mirror image of {name!r}")
        twin[i], sign[i] = j, np.sign(d)
    return twin, sign


def mirror_poses(Q: np.ndarray, skeleton: Skeleton) -> np.ndarray:
    """The left/right mirror images (n, n_dofs) [rad] of poses ``Q`` (n, n_dofs), within the limits."""
    twin, sign = mirror_signs(skeleton)
    Q = np.asarray(Q, dtype=float)
    out = np.empty_like(Q)
    out[:, twin] = Q * sign
    return np.clip(out, skeleton.lower, skeleton.upper)


def fit_prior_by_performer(poses: Mapping[str, np.ndarray], skeleton: Skeleton, shrinkage: float | None = None,
                           source: str = "") -> PosePrior:
    """A Gaussian with the performer normalised away: ``poses`` maps each performer to (n_p, n_dofs) [rad].

    Mean: the average of the performers' means. Covariance: of the poses, each
    centred on its own performer's mean and weighted so every performer counts
    the same, shrunk (``shrinkage`` or cross-validated) and floored as
    :func:`gsik.prior.regularised`.
    """
    if len(poses) < 1:
        raise PriorError("a pose prior by performer needs at least one performer's poses")
    groups = [training_poses(Q, skeleton, 0.0, f"performer {p!r}'s poses")[0] for p, Q in poses.items()]
    means = np.array([Q.mean(axis=0) for Q in groups])
    centred = np.concatenate([Q - m for Q, m in zip(groups, means)])
    w = np.concatenate([np.full(len(Q), 1.0 / len(Q)) for Q in groups])
    S = np.cov(centred.T, aweights=w, bias=True)
    a = choose_shrinkage(centred) if shrinkage is None else float(shrinkage)
    return PosePrior(skeleton.name, tuple(skeleton.dof_names), means.mean(axis=0), regularised(S, a),
                     int(sum(len(Q) for Q in groups)), a, source)


def learn_prior(poses: Mapping[str, np.ndarray], skeleton: Skeleton, source: str = "") -> PosePrior:
    """The bundled prior's recipe (what won leave-one-performer-out, ``benchmarks/bench_prior.py``): each
    performer's poses (performer -> (n_p, n_dofs) [rad]) with their mirror images, the performer normalised
    away (:func:`fit_prior_by_performer`)."""
    return fit_prior_by_performer({p: np.concatenate([Q, mirror_poses(Q, skeleton)]) for p, Q in poses.items()},
                                  skeleton, source=source)
