"""A richer pose prior: a mixture of Gaussians over a skeleton's joint angles.

The mixture has ``K`` components, weights ``w`` (K,), means ``mu`` (K, n)
[rad] and covariances ``Sigma`` (K, n, n) [rad^2], fitted by EM
(:func:`fit_mixture`) with each component's covariance regularised as the
single Gaussian's is (:func:`gsik.prior.regularised`). ``K`` is chosen by the
held-out log-likelihood over contiguous time segments of the training frames,
as the shrinkage is.

The solver uses one component at a time, so a step costs what a step with the
single Gaussian costs (one dense posture level): :func:`solve_with_mixture`
solves with the mixture's overall Gaussian, then with the component most
likely for the pose found (hard assignment, the mixture's EM in the solver's
loop), until the component repeats; :func:`follow_mixture` switches a dragging
solver's posture to the component most likely for its current pose.

File format (``.npz``, read without pickle; :func:`write_mixture`): the
Gaussian's metadata (``skeleton``, ``dof_names``, ``n_frames``,
``shrinkage``, ``source``), ``format`` 2, and arrays ``weights`` (K,),
``means`` (K, n), ``covariances`` (K, n, n).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from gsik.errors import PriorError
from gsik.prior import CV_SEGMENTS, PosePrior, read_npz, regularised, segments, training_poses, use_prior, \
    write_npz

#: Component counts tried when ``K`` is chosen by cross-validation.
COMPONENT_GRID = (1, 2, 3, 4, 6, 8)
#: EM stops after this many iterations, or when the mean log-likelihood gains less than EM_TOLERANCE.
EM_ITERATIONS = 60
EM_TOLERANCE = 1e-4
#: A component never weighs less than this (a component EM empties keeps a finite log-weight).
WEIGHT_FLOOR = 1e-6
#: Solves with a re-chosen component in :func:`solve_with_mixture` after the overall Gaussian's.
MIXTURE_ROUNDS = 3
FORMAT = 2
#: Most components a mixture may have (fitted or read): each is one dense (n, n) covariance.
MAX_COMPONENTS = 32


@dataclass(frozen=True, eq=False)
class PoseMixture:
    """A mixture of Gaussians over a skeleton's joint angles; arrays read-only.

    Attributes:
        skeleton: Name of the skeleton it belongs to.
        dof_names: (n,) the DOFs, in the skeleton's order.
        weights: (K,) component weights (positive, summing to 1).
        means: (K, n) component means [rad].
        covariances: (K, n, n) component covariances [rad^2] (regularised, positive definite).
        n_frames: How many poses it was learned from.
        shrinkage: The shrinkage intensity of every component's covariance.
        source: What it was learned from (clip, licence).
    """

    skeleton: str
    dof_names: tuple[str, ...]
    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray
    n_frames: int
    shrinkage: float
    source: str = ""

    def __post_init__(self):
        w = np.array(self.weights, dtype=float)
        k, n = len(w), len(self.dof_names)
        means, covs = np.array(self.means, dtype=float), np.array(self.covariances, dtype=float)
        if w.ndim != 1 or k < 1 or means.shape != (k, n) or covs.shape != (k, n, n):
            raise PriorError(f"a pose mixture of K components over {n} DOFs needs weights (K,), means (K, {n}) "
                             f"and covariances (K, {n}, {n}); got {w.shape}, {means.shape} and {covs.shape}")
        if not (np.all(w > 0.0) and abs(w.sum() - 1.0) < 1e-9):
            raise PriorError(f"a pose mixture's weights must be positive and sum to 1, got {w.tolist()}")
        for name, a in (("weights", w), ("means", means), ("covariances", covs)):
            a.flags.writeable = False
            object.__setattr__(self, name, a)
        object.__setattr__(self, "dof_names", tuple(self.dof_names))
        self.components  # checks every covariance (PosePrior does)

    @property
    def n_components(self) -> int:
        return len(self.weights)

    @cached_property
    def components(self) -> tuple[PosePrior, ...]:
        """Each component as a :class:`~gsik.prior.PosePrior` (what the solver's posture uses)."""
        return tuple(PosePrior(self.skeleton, self.dof_names, m, c, self.n_frames, self.shrinkage, self.source)
                     for m, c in zip(self.means, self.covariances))

    @cached_property
    def overall(self) -> PosePrior:
        """The single Gaussian with the mixture's mean and covariance (its first two moments)."""
        mean = self.weights @ self.means
        d = self.means - mean
        cov = np.einsum("k,kij->ij", self.weights, self.covariances) + np.einsum("k,ki,kj->ij", self.weights, d, d)
        return PosePrior(self.skeleton, self.dof_names, mean, 0.5 * (cov + cov.T), self.n_frames, self.shrinkage,
                         self.source)

    @cached_property
    def _whitening(self) -> tuple[np.ndarray, np.ndarray]:
        """``(L_k^-1 (K, n, n), log w_k - 0.5 log det Sigma_k (K,))``, with ``Sigma_k = L_k L_k^T``: factored once."""
        return _whitening(self.weights, self.covariances)

    def log_densities(self, q: np.ndarray) -> np.ndarray:
        """``log(w_k N(q; mu_k, Sigma_k))`` (..., K) of poses ``q`` (..., n) [rad], without the ``2 pi`` constant."""
        return _log_densities_whitened(np.asarray(q, dtype=float), self.means, *self._whitening)

    def log_likelihood(self, Q: np.ndarray) -> float:
        """Mean log-likelihood of poses ``Q`` (m, n) [rad] (without the ``2 pi`` constant)."""
        return float(np.mean(_logsumexp(self.log_densities(Q))))

    def most_likely(self, q: np.ndarray) -> int:
        """The component most likely to have produced pose ``q`` (n,) [rad]."""
        return int(np.argmax(self.log_densities(q)))


def _logsumexp(a: np.ndarray) -> np.ndarray:
    top = a.max(axis=-1)
    return top + np.log(np.exp(a - top[..., None]).sum(axis=-1))


def _whitening(weights: np.ndarray, covs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    L = np.linalg.cholesky(covs)                                   # (K, n, n)
    return np.linalg.inv(L), np.log(weights) - np.log(np.diagonal(L, axis1=1, axis2=2)).sum(axis=1)


def _log_densities_whitened(X: np.ndarray, means: np.ndarray, Linv: np.ndarray, log_norm: np.ndarray) -> np.ndarray:
    z = np.einsum("kij,...kj->...ki", Linv, X[..., None, :] - means)  # whitened offsets (..., K, n)
    return log_norm - 0.5 * np.einsum("...ki,...ki->...k", z, z)


def _log_densities(X: np.ndarray, weights: np.ndarray, means: np.ndarray, covs: np.ndarray) -> np.ndarray:
    """``log(w_k N(x; mu_k, Sigma_k))`` (m, K) of rows ``X`` (m, n), without the ``2 pi`` constant."""
    return _log_densities_whitened(X, means, *_whitening(weights, covs))


def _initial_means(X: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """k-means++ seeds, then 10 Lloyd iterations: (k, n) starting means."""
    centres = [X[rng.integers(len(X))]]
    for _ in range(1, k):
        d2 = np.min([np.sum((X - c) ** 2, axis=1) for c in centres], axis=0)
        centres.append(X[rng.choice(len(X), p=d2 / d2.sum())] if d2.sum() > 0 else X[rng.integers(len(X))])
    C = np.array(centres)
    for _ in range(10):
        label = np.argmin(((X[:, None, :] - C) ** 2).sum(axis=2), axis=1)
        C = np.array([X[label == j].mean(axis=0) if np.any(label == j) else C[j] for j in range(k)])
    return C


def em(X: np.ndarray, k: int, shrinkage: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit ``k`` regularised Gaussians to rows ``X`` (m, n): ``(weights (k,), means (k, n), covariances (k, n, n))``."""
    means = _initial_means(X, k, np.random.default_rng(seed))
    S = np.cov(X.T)
    weights, covs = np.full(k, 1.0 / k), np.repeat(regularised(S, shrinkage)[None], k, axis=0)
    last = -np.inf
    for _ in range(EM_ITERATIONS if k > 1 else 1):
        logp = _log_densities(X, weights, means, covs) if k > 1 else np.zeros((len(X), 1))
        ll = _logsumexp(logp)
        resp = np.exp(logp - ll[:, None])                          # responsibilities (m, k)
        counts = resp.sum(axis=0) + 1e-12
        weights = np.maximum(counts / len(X), WEIGHT_FLOOR)
        weights /= weights.sum()
        means = (resp.T @ X) / counts[:, None]
        covs = np.array([regularised(_weighted_cov(X, means[j], resp[:, j], counts[j]), shrinkage)
                         for j in range(k)])
        if ll.mean() - last < EM_TOLERANCE:
            break
        last = ll.mean()
    return weights, means, covs


def _weighted_cov(X: np.ndarray, mean: np.ndarray, r: np.ndarray, count: float) -> np.ndarray:
    d = X - mean
    S = (r[:, None] * d).T @ d / count
    return 0.5 * (S + S.T)


def choose_components(Q: np.ndarray, shrinkage: float, k: int = CV_SEGMENTS) -> tuple[int, dict[int, float]]:
    """The :data:`COMPONENT_GRID` count with the best held-out log-likelihood over ``k`` time segments of ``Q``,
    and every count's mean held-out log-likelihood."""
    scores = {}
    for n_comp in COMPONENT_GRID:
        total = 0.0
        for held in segments(len(Q), k):
            w, m, c = em(np.delete(Q, held, axis=0), n_comp, shrinkage)
            total += float(np.mean(_logsumexp(_log_densities(Q[held], w, m, c))))
        scores[n_comp] = total / k
    return max(scores, key=scores.get), scores


def fit_mixture(Q: np.ndarray, skeleton, components: int | None = None, shrinkage: float | None = None,
                source: str = "") -> PoseMixture:
    """Learn a :class:`PoseMixture` from poses ``Q`` (n_frames, n_dofs) [rad] of ``skeleton``.

    ``components`` >= 1 (default: chosen by :func:`choose_components`);
    ``shrinkage`` in [0, 1] (default: the single Gaussian's, :func:`gsik.prior.choose_shrinkage`).
    """
    Q, a = training_poses(Q, skeleton, shrinkage, "a pose mixture")
    if components is not None and not (isinstance(components, int) and 1 <= components <= MAX_COMPONENTS
                                       and components <= len(Q) // 2):
        raise PriorError(f"components must be an integer in [1, {min(len(Q) // 2, MAX_COMPONENTS)}] (or None: "
                         f"chosen by cross-validation from {list(COMPONENT_GRID)}), got {components!r}")
    k = choose_components(Q, a)[0] if components is None else components
    w, m, c = em(Q, k, a)
    return PoseMixture(skeleton.name, tuple(skeleton.dof_names), w, m, c, len(Q), a, source)


def write_mixture(mixture: PoseMixture, path: str | os.PathLike, follow_symlinks: bool = True) -> None:
    """Write ``mixture`` as a ``.npz`` file (see the module docstring), atomically, as :func:`gsik.prior.write_prior`."""
    write_npz(path, "pose mixture", follow_symlinks, format=FORMAT, skeleton=mixture.skeleton, dof_names=mixture.dof_names,
              weights=mixture.weights, means=mixture.means, covariances=mixture.covariances,
              n_frames=mixture.n_frames, shrinkage=mixture.shrinkage, source=mixture.source)


def read_mixture(path: str | os.PathLike) -> PoseMixture:
    """Read a pose mixture written by :func:`write_mixture` (no pickle)."""
    d = read_npz(path, "pose mixture", FORMAT, ("skeleton", "dof_names", "weights", "means", "covariances",
                                                  "n_frames", "shrinkage", "source"))
    if len(d["weights"]) > MAX_COMPONENTS:
        raise PriorError(f"{path}: a mixture of {len(d['weights']):,} components; the limit is {MAX_COMPONENTS}")
    return PoseMixture(str(d["skeleton"]), tuple(str(s) for s in d["dof_names"]), d["weights"], d["means"],
                       d["covariances"], int(d["n_frames"]), float(d["shrinkage"]), str(d["source"]))


def follow_mixture(solver, mixture: PoseMixture, strength: float = 1.0, current: int | None = None) -> int:
    """Make the component most likely for the solver's pose its posture, unless it is ``current`` already.

    Returns that component's index; call it before each ``step()`` while dragging (it costs ``K`` Mahalanobis
    distances; the posture, and so the solver's prioritised controller, changes only when the component does).
    """
    k = mixture.most_likely(solver.q)
    if k != current:
        use_prior(solver, mixture.components[k], strength)
    return k


def solve_with_mixture(solver, mixture: PoseMixture, targets=None, q0=None, strength: float = 1.0,
                       rounds: int = MIXTURE_ROUNDS):
    """Solve towards ``targets`` with the mixture as the posture, one component at a time.

    The first solve (from ``q0``, as :meth:`gsik.Solver.solve`) uses the
    mixture's overall Gaussian; each further one (at most ``rounds``) starts
    where the last ended, with the component most likely for that pose,
    until the component repeats. Of those solves the one that converged with
    the most likely pose (the mixture's density) is the solver's state and
    result. The solver keeps that component as its posture.
    """
    use_prior(solver, mixture.overall, strength)
    best = result = solver.solve(targets, q0)
    best_key, best_k, chosen = _rank(result, mixture), None, None
    for _ in range(rounds):
        k = mixture.most_likely(result.q)
        if k == chosen:
            break
        chosen = k
        use_prior(solver, mixture.components[k], strength)
        result = solver.solve(None, result.q)
        if _rank(result, mixture) < best_key:
            best, best_key, best_k = result, _rank(result, mixture), k
    if best is not result:
        solver.set_q(best.q)
        use_prior(solver, mixture.overall if best_k is None else mixture.components[best_k], strength)
    return best


def _rank(result, mixture: PoseMixture) -> tuple:
    return (not result.converged, -float(_logsumexp(mixture.log_densities(result.q))))
