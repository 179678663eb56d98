"""A pose prior learned from motion capture: a Gaussian over a skeleton's joint angles.

The prior is the mean ``mu`` (n_dofs,) [rad] and covariance ``Sigma``
(n_dofs, n_dofs) [rad^2] of retargeted real poses. Solving with it
(:func:`use_prior`) makes it the solver's posture, the lowest priority level:
among the poses that meet the targets, the solver prefers the one nearest
``mu`` in the Mahalanobis sense, ``(q - mu)^T Sigma^-1 (q - mu)``: the posture
term ``lambda Sigma^-1`` enters the step's system and ``lambda Sigma^-1 (mu - q)``
its right-hand side, inside the targets' null space. Targets are met as
exactly as without it.

Regularisation: the sample covariance ``S`` is shrunk towards its diagonal,
``(1 - a) S + a diag(S)``, plus a floor of :data:`VARIANCE_FLOOR` on the
diagonal (a DOF the clip never moves still gets a finite precision). The
shrinkage ``a`` is chosen by cross-validation over contiguous time segments
of the training frames (held-out Gaussian log-likelihood), never by the
frames it is judged on.

File format (``.npz``, read without pickle): arrays ``mean`` (n,),
``covariance`` (n, n), ``dof_names`` (n,) strings, and 0-d ``skeleton``,
``source`` (what it was learned from, with the licence), ``n_frames``,
``shrinkage``, ``format`` (1).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from gsik.errors import PriorError, choices
from gsik.io.bundled import bundled_dir
from gsik.io.files import atomic_write_bytes
from gsik.io.npz import Member, npz_bytes, read_npz_members
from gsik.skeleton import Skeleton
from gsik.skeleton_builder import MAX_DOFS

#: Smallest variance of any angle [rad^2] ((0.02 rad)^2, about 1 degree).
VARIANCE_FLOOR = 4e-4
#: Shrinkage intensities tried when fitting.
SHRINKAGE_GRID = (0.0, 0.01, 0.03, 0.1, 0.2, 0.4, 0.7, 1.0)
#: Contiguous time segments of the training frames used to choose the shrinkage.
CV_SEGMENTS = 5
FORMAT = 1


@dataclass(frozen=True, eq=False)
class PosePrior:
    """A Gaussian over a skeleton's joint angles; arrays read-only.

    Attributes:
        skeleton: Name of the skeleton it belongs to.
        dof_names: (n,) the DOFs, in the skeleton's order.
        mean: (n,) mean angles [rad].
        covariance: (n, n) covariance [rad^2] (regularised, positive definite).
        n_frames: How many poses it was learned from.
        shrinkage: The shrinkage intensity used (0: sample covariance, 1: diagonal).
        source: What it was learned from (clip, licence).
    """

    skeleton: str
    dof_names: tuple[str, ...]
    mean: np.ndarray
    covariance: np.ndarray
    n_frames: int
    shrinkage: float
    source: str = ""

    def __post_init__(self):
        n = len(self.dof_names)
        mean = np.array(self.mean, dtype=float)
        cov = np.array(self.covariance, dtype=float)
        if mean.shape != (n,) or cov.shape != (n, n) or not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
            raise PriorError(f"a pose prior over {n} DOFs needs a finite mean ({n},) and covariance ({n}, {n}); "
                             f"got {mean.shape} and {cov.shape}")
        if not np.allclose(cov, cov.T) or np.linalg.eigvalsh(cov).min() <= 0.0:
            raise PriorError("a pose prior's covariance must be symmetric positive definite")
        for name, a in (("mean", mean), ("covariance", cov)):
            a.flags.writeable = False
            object.__setattr__(self, name, a)
        object.__setattr__(self, "dof_names", tuple(self.dof_names))

    @cached_property
    def precision(self) -> np.ndarray:
        """``Sigma^-1`` (n, n) [1/rad^2], read-only."""
        P = np.linalg.inv(self.covariance)
        P = 0.5 * (P + P.T)
        P.flags.writeable = False
        return P

    def check_fits(self, skeleton: Skeleton) -> None:
        """Raise :class:`PriorError` unless the prior's DOFs are ``skeleton``'s, in order."""
        if tuple(skeleton.dof_names) != self.dof_names:
            raise PriorError(f"pose prior of skeleton {self.skeleton!r} ({len(self.dof_names)} DOFs) does not fit "
                             f"skeleton {skeleton.name!r}: DOFs {choices(skeleton.dof_names)}")

    def mahalanobis(self, q: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of poses ``q`` (..., n) [rad] from the mean (...,)."""
        d = np.asarray(q, dtype=float) - self.mean
        return np.sqrt(np.einsum("...i,ij,...j->...", d, self.precision, d))


def _log_likelihood(X: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> float:
    """Mean Gaussian log-likelihood of rows ``X`` (m, n) (without the constant)."""
    sign, logdet = np.linalg.slogdet(cov)
    d = X - mean
    return float(-0.5 * (logdet + np.mean(np.einsum("mi,mi->m", d @ np.linalg.inv(cov), d))))


def regularised(S: np.ndarray, a: float) -> np.ndarray:
    """``S`` (n, n) shrunk towards its diagonal by ``a`` in [0, 1], plus :data:`VARIANCE_FLOOR` on the diagonal."""
    return (1.0 - a) * S + a * np.diag(np.diag(S)) + VARIANCE_FLOOR * np.eye(len(S))


def segments(n: int, k: int) -> list[np.ndarray]:
    """``k`` contiguous index ranges covering ``range(n)`` (time segments for cross-validation)."""
    return [np.arange(a, b) for a, b in zip(np.linspace(0, n, k + 1).astype(int)[:-1],
                                            np.linspace(0, n, k + 1).astype(int)[1:])]


def choose_shrinkage(Q: np.ndarray, k: int = CV_SEGMENTS) -> float:
    """The :data:`SHRINKAGE_GRID` value with the best held-out log-likelihood over ``k`` time segments of ``Q``."""
    folds = segments(len(Q), k)
    scores = []
    for a in SHRINKAGE_GRID:
        total = 0.0
        for held in folds:
            train = np.delete(Q, held, axis=0)
            total += _log_likelihood(Q[held], train.mean(axis=0), regularised(np.cov(train.T), a))
        scores.append(total)
    return float(SHRINKAGE_GRID[int(np.argmax(scores))])


def fit_prior(Q: np.ndarray, skeleton: Skeleton, shrinkage: float | None = None, source: str = "") -> PosePrior:
    """Learn a :class:`PosePrior` from poses ``Q`` (n_frames, n_dofs) [rad] of ``skeleton``.

    ``shrinkage`` in [0, 1]; default chosen by :func:`choose_shrinkage`.
    """
    Q, a = training_poses(Q, skeleton, shrinkage, "a pose prior")
    return PosePrior(skeleton.name, tuple(skeleton.dof_names), Q.mean(axis=0), regularised(np.cov(Q.T), a),
                     len(Q), a, source)


def training_poses(Q, skeleton: Skeleton, shrinkage: float | None, what: str) -> tuple[np.ndarray, float]:
    """Poses ``Q`` checked to be (n_frames >= 2 * CV_SEGMENTS, n_dofs) floats, and the shrinkage: ``shrinkage``
    checked to be in [0, 1], or chosen by :func:`choose_shrinkage` when ``None``; ``what`` names the prior in errors."""
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 2 or Q.shape[1] != skeleton.n_dofs or len(Q) < 2 * CV_SEGMENTS:
        raise PriorError(f"{what} needs poses (n_frames >= {2 * CV_SEGMENTS}, {skeleton.n_dofs}), got {Q.shape}")
    a = choose_shrinkage(Q) if shrinkage is None else float(shrinkage)
    if not 0.0 <= a <= 1.0:
        raise PriorError(f"shrinkage must be in [0, 1], got {shrinkage!r}")
    return Q, a


def write_prior(prior: PosePrior, path: str | os.PathLike, follow_symlinks: bool = True) -> None:
    """Write ``prior`` as a ``.npz`` file (see the module docstring), atomically
    (:func:`gsik.io.files.atomic_write_bytes`; ``follow_symlinks=False`` refuses a link at ``path``)."""
    write_npz(path, "pose prior", follow_symlinks, format=FORMAT, skeleton=prior.skeleton, dof_names=prior.dof_names,
              mean=prior.mean, covariance=prior.covariance, n_frames=prior.n_frames, shrinkage=prior.shrinkage,
              source=prior.source)


def read_prior(path: str | os.PathLike) -> PosePrior:
    """Read a pose prior written by :func:`write_prior` (no pickle)."""
    d = read_npz(path, "pose prior", FORMAT, ("skeleton", "dof_names", "mean", "covariance", "n_frames",
                                              "shrinkage", "source"))
    return PosePrior(str(d["skeleton"]), tuple(str(s) for s in d["dof_names"]), d["mean"], d["covariance"],
                     int(d["n_frames"]), float(d["shrinkage"]), str(d["source"]))


def write_npz(path: str | os.PathLike, what: str, follow_symlinks: bool = True, **arrays) -> None:
    """Write ``arrays`` (names to arrays or scalars) as an ``.npz`` file, atomically
    (:func:`gsik.io.files.atomic_write_bytes`: an existing file is replaced whole or left untouched; with
    ``follow_symlinks`` false a link at ``path`` is refused); ``what`` names it in errors."""
    del what  # the atomic writer names the path
    atomic_write_bytes(path, npz_bytes(arrays), follow_symlinks)


#: What each member of a prior file may hold: dtype kinds and number of dimensions.
MEMBERS = {"format": Member("iu", 0), "skeleton": Member("U", 0), "source": Member("U", 0),
           "dof_names": Member("U", 1), "n_frames": Member("iu", 0), "shrinkage": Member("fiu", 0),
           "mean": Member("fiu", 1), "covariance": Member("fiu", 2), "weights": Member("fiu", 1),
           "means": Member("fiu", 2), "covariances": Member("fiu", 3)}

#: Most DOFs a prior may cover (as many as a skeleton may have).
MAX_PRIOR_DOFS = MAX_DOFS


def read_npz(path: str | os.PathLike, what: str, format: int, needed: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The arrays of an ``.npz`` file of ``format`` holding exactly ``needed`` and ``format`` (no pickle; bounded:
    :func:`gsik.io.npz.read_npz_members`), the metadata checked; :class:`PriorError` otherwise."""
    data = read_npz_members(path, what, MEMBERS, PriorError)
    if "format" in data and int(data["format"]) != format:
        raise PriorError(f"{path}: not a format-{format} {what} (format {int(data['format'])}; formats: "
                         f"{FORMAT} a Gaussian pose prior, 2 a pose mixture)")
    missing = [k for k in ("format",) + needed if k not in data]
    if missing:
        raise PriorError(f"{path}: not a format-{format} {what} (missing {choices(missing)})")
    extra = [f"{k}.npy" for k in data if k not in needed and k != "format"]
    if extra:
        raise PriorError(f"{path}: unexpected member {choices(extra)} in a format-{format} {what}")
    _check_metadata(data, path)
    return data


def _check_metadata(data: dict[str, np.ndarray], path) -> None:
    """``n_frames`` >= 0, ``shrinkage`` in [0, 1], at most :data:`MAX_PRIOR_DOFS` DOF names."""
    if int(data["n_frames"]) < 0:
        raise PriorError(f"{path}: n_frames must be >= 0, got {int(data['n_frames'])}")
    if not 0.0 <= float(data["shrinkage"]) <= 1.0:
        raise PriorError(f"{path}: shrinkage must be in [0, 1], got {float(data['shrinkage'])!r}")
    n = len(data["dof_names"])
    if n > MAX_PRIOR_DOFS:
        raise PriorError(f"{path}: {n:,} DOF names; the limit is {MAX_PRIOR_DOFS:,}")
    for key in ("mean", "covariance", "means", "covariances"):
        square = key.startswith("cov")
        if key in data and (data[key].shape[-1] != n or (square and data[key].shape[-2] != n)):
            raise PriorError(f"{path}: {key} has shape {data[key].shape} for {n} DOF names")


def bundled_prior_path(skeleton: str = "biped") -> Path:
    """Where the prior bundled for ``skeleton`` lives (``skeletons/<name>_prior.npz``)."""
    return bundled_dir() / f"{skeleton}_prior.npz"


def bundled_prior(skeleton: str = "biped") -> PosePrior:
    """The pose prior shipped for a bundled skeleton (the biped's and the humanoid's: learned from real motion
    capture, ``gsik learn-prior --onto``)."""
    path = bundled_prior_path(skeleton)
    if not path.exists():
        raise PriorError(f"no pose prior is bundled for skeleton {skeleton!r}; bundled: "
                         f"{choices(p.name[:-10] for p in path.parent.glob('*_prior.npz'))}")
    return read_prior(path)


def use_prior(solver, prior: PosePrior | None, strength: float = 1.0) -> None:
    """Make ``prior`` the solver's posture (lowest priority); ``None`` turns the posture off.

    The posture minimises ``strength * (q - mu)^T Sigma^-1 (q - mu)`` within
    what the targets leave free. ``strength`` > 0 scales it against the
    posture level's damping only: it never trades against a target.
    """
    if prior is None:
        solver.set_posture(None, 0.0)
        return
    prior.check_fits(solver.skeleton)
    if not strength > 0.0:
        raise PriorError(f"prior strength must be > 0, got {strength!r}")
    solver.set_posture(prior.mean, strength * prior.precision)
