"""Which posture the solver prefers below every target: the learned pose prior ("natural") or the rest pose.

Plain Python. A skeleton with a pose prior bundled for it (the biped's
``skeletons/biped_prior.npz``, learned from real motion capture of four
performers, see :mod:`gsik.prior`) starts natural (:data:`NATURAL_BY_DEFAULT`,
chosen by the leave-one-performer-out benchmark): among the poses that meet
the targets the solver prefers the likeliest human one. The artist can fall back to the plain
rest pose; a skeleton without a prior has only the rest pose (a bundled one,
such as the humanoid, starts with it; an imported one starts with none: the
plain solver). Either way the posture is the lowest priority level, so it
never costs target accuracy.

Like the posture strength it is solver state (remembered by the studio's
settings, not saved in pose files, not undone).
"""

from __future__ import annotations

import numpy as np

import gsik
from gsik.prior import PosePrior, bundled_prior, use_prior

#: Posture strength a new document starts with: the prior's when one is bundled (as ``bench_prior.py``
#: measures it), the rest pose's for a bundled skeleton without a prior, else off (the plain solver).
NATURAL_STRENGTH = 1.0
#: Whether a document starts natural when a prior is bundled. The rule (issue 18): only if, leaving each shared
#: performer out in turn (``benchmarks/bench_prior.py``, hands and left foot as targets), the bundled prior's
#: recipe is no worse than the rest posture for every held-out performer and at least 2x better on the
#: geometric mean over performers; else the rest posture, the prior one click away. Measured: 2.07, 2.51, 3.75
#: and 1.98x better than the rest posture (performers 001, 002, 003, bvhtools), 2.49x on the geometric mean
#: (README, "Natural poses").
NATURAL_BY_DEFAULT = True


def prior_for(skeleton: gsik.Skeleton) -> PosePrior | None:
    """The pose prior bundled for ``skeleton`` (by its name) when it fits its DOFs, else None."""
    try:
        prior = bundled_prior(skeleton.name)
        prior.check_fits(skeleton)
    except gsik.GsikError:
        return None
    return prior


class Posture:
    """The solver's posture: natural (the prior) or rest, and how strongly it is preferred.

    Args:
        solver: The document's solver; the posture is applied to it at once.

    Attributes:
        prior: The pose prior bundled for the solver's skeleton (None: there is none).
        natural: True while the prior is the posture (always False without a prior).
        strength: The posture's weight (>= 0; 0: no posture).
    """

    def __init__(self, solver: gsik.Solver):
        self._solver = solver
        self.prior = prior_for(solver.skeleton)
        self.natural = self.prior is not None and NATURAL_BY_DEFAULT
        bundled = solver.skeleton.name in gsik.bundled_skeletons()
        self.strength = NATURAL_STRENGTH if self.prior is not None or bundled else 0.0
        self._apply()

    @property
    def can_be_natural(self) -> bool:
        return self.prior is not None

    def set_strength(self, strength: float) -> None:
        """Prefer the posture with weight ``strength`` (>= 0, per DOF; 0 turns it off), below every target."""
        s = float(strength)
        if not np.isfinite(s) or s < 0.0:
            raise gsik.SolverError(f"posture strength must be a number >= 0 (0: off), got {strength!r}")
        self.strength = s
        self._apply()

    def set_natural(self, on: bool) -> None:
        """The prior (True) or the rest pose (False) as the posture; SolverError when no prior is bundled."""
        if on and self.prior is None:
            raise gsik.SolverError(f"no pose prior is bundled for skeleton {self._solver.skeleton.name!r}: "
                                   "its posture is the rest pose")
        self.natural = bool(on)
        self._apply()

    def _apply(self) -> None:
        if self.natural and self.strength > 0.0:
            use_prior(self._solver, self.prior, self.strength)
        else:
            self._solver.set_posture(None, self.strength)
