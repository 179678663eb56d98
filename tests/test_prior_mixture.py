"""The mixture-of-Gaussians pose prior (issue 12): EM, choosing K, the file format, solving one component at a time."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from gsik import Solver, Target, load_skeleton
from gsik.cli import main
from gsik.errors import PriorError
from gsik.kinematics import world_frames
from gsik.prior import read_prior
from gsik.prior_mixture import (PoseMixture, choose_components, fit_mixture, follow_mixture, read_mixture,
                                solve_with_mixture, write_mixture)

REAL_CLIP = Path(__file__).resolve().parents[2] / "shared" / "mocap" / "mocap_bvhtools_test.bvh"


def _two_clusters(n: int = 2000, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Biped poses (inside the limits) from two tight, well separated Gaussians (weights 0.7 / 0.3), and the
    two means (2, n_dofs)."""
    sk = load_skeleton("biped")
    rng = np.random.default_rng(seed)
    centre, half = 0.5 * (sk.lower + sk.upper), 0.5 * (sk.upper - sk.lower)
    means = np.array([centre - 0.3 * half, centre + 0.3 * half])
    label = rng.random(n) < 0.3
    return means[label.astype(int)] + 0.01 * half * rng.normal(size=(n, sk.n_dofs)), means


def test_em_finds_two_separated_clusters_with_their_weights():
    sk = load_skeleton("biped")
    Q, means = _two_clusters()
    mixture = fit_mixture(Q, sk, components=2, shrinkage=0.0)
    order = np.argsort(mixture.means[:, 0])
    np.testing.assert_allclose(mixture.means[order], means, atol=0.01)
    np.testing.assert_allclose(mixture.weights[order], [0.7, 0.3], atol=0.03)
    assert mixture.most_likely(means[1]) == order[1] and mixture.most_likely(means[0]) == order[0]
    assert not mixture.means.flags.writeable and not mixture.weights.flags.writeable


def test_cross_validation_picks_several_components_for_clusters_and_one_for_a_single_gaussian():
    two, _ = _two_clusters(600)
    one = two[:1] + 0.03 * np.random.default_rng(1).normal(size=two.shape)
    assert choose_components(two, 0.0)[0] >= 2
    assert choose_components(one, 0.0)[0] == 1


def test_the_overall_gaussian_has_the_mixtures_mean_and_covariance():
    sk = load_skeleton("biped")
    Q, _ = _two_clusters()
    overall = fit_mixture(Q, sk, components=2, shrinkage=0.0).overall
    np.testing.assert_allclose(overall.mean, Q.mean(axis=0), atol=1e-6)
    np.testing.assert_allclose(overall.covariance, np.cov(Q.T, bias=True) + 4e-4 * np.eye(sk.n_dofs), atol=1e-3)


def test_a_mixture_file_round_trips_and_is_not_read_as_a_gaussian(tmp_path):
    sk = load_skeleton("biped")
    mixture = fit_mixture(_two_clusters(400)[0], sk, components=2, source="synthetic")
    path = tmp_path / "m.npz"
    write_mixture(mixture, path)
    back = read_mixture(path)
    assert back.n_components == 2 and back.source == "synthetic" and back.dof_names == sk.dof_names
    np.testing.assert_array_equal(back.covariances, mixture.covariances)
    with pytest.raises(PriorError, match="not a format-1 pose prior \\(format 2; formats: 1 a Gaussian pose "
                                         "prior, 2 a pose mixture\\)"):
        read_prior(path)


def test_bad_mixtures_are_refused_with_the_valid_choices():
    sk = load_skeleton("biped")
    with pytest.raises(PriorError, match="components must be an integer in \\[1, 32\\].*\\[1, 2, 3, 4, 6, 8\\]"):
        fit_mixture(_two_clusters(400)[0], sk, components=0)
    with pytest.raises(PriorError, match="weights must be positive and sum to 1"):
        PoseMixture("arm", ("a.x",), [0.5, 0.6], [[0.0], [1.0]], [[[1.0]], [[1.0]]], 10, 0.1)
    with pytest.raises(PriorError, match="means \\(K, 1\\)"):
        PoseMixture("arm", ("a.x",), [1.0], [[0.0, 1.0]], [[[1.0]]], 10, 0.1)


def test_following_the_mixture_sets_the_component_most_likely_for_the_pose():
    sk = load_skeleton("biped")
    Q, means = _two_clusters()
    mixture = fit_mixture(Q, sk, components=2, shrinkage=0.0)
    solver = Solver(sk, q0=means[1])
    k = follow_mixture(solver, mixture)
    assert k == mixture.most_likely(means[1])
    np.testing.assert_allclose(solver.posture.reference, mixture.means[k])
    solver.set_q(means[0])
    assert follow_mixture(solver, mixture, current=k) != k


def test_solving_with_the_mixture_meets_the_targets_and_lands_on_the_component_they_come_from():
    sk = load_skeleton("biped")
    Q, means = _two_clusters()
    mixture = fit_mixture(Q, sk, components=2, shrinkage=0.0)
    k = mixture.most_likely(means[1])
    R, p = world_frames(sk, mixture.means[k])
    targets = {n: Target(p[sk.frame_of(n)]) for n in ("left_hand", "right_hand", "left_foot")}
    root = np.block([[R[sk.frame_of(sk.root)], p[sk.frame_of(sk.root)][:, None]], [np.zeros((1, 3)), np.ones((1, 1))]])
    result = solve_with_mixture(Solver(sk, world_from_root=root), mixture, targets, q0=sk.rest)
    assert max(e[0] for e in result.errors().values()) < 1e-3
    np.testing.assert_allclose(result.q, mixture.means[k], atol=2e-3)


@pytest.mark.skipif(not REAL_CLIP.exists(), reason=f"the real clip {REAL_CLIP} is not beside the repository")
def test_learn_prior_with_components_rebuilds_the_mixture_the_library_learns_from_the_clip(tmp_path):
    """``gsik learn-prior --components 2`` on the clip's first frames: the library's mixture of the same
    retargeted frames, to the bit."""
    from gsik.anim.retarget import Retargeter
    from gsik.io.bvh import BvhClip, read_bvh

    out = tmp_path / "mixture.npz"
    text = io.StringIO()
    assert main(["learn-prior", str(REAL_CLIP), "--frames", "60", "--components", "2", "--out", str(out)],
                out=text) == 0, text.getvalue()
    assert "2 components" in text.getvalue()
    full = read_bvh(REAL_CLIP)
    clip = BvhClip(full.joints, full.frame_time, full.motion[:60])
    sk = load_skeleton("biped")
    want = fit_mixture(Retargeter(sk, clip).retarget(clip).motion.q, sk, components=2)
    rebuilt = read_mixture(out)
    assert rebuilt.n_frames == 60 and rebuilt.dof_names == sk.dof_names
    np.testing.assert_array_equal(rebuilt.means, want.means)
    np.testing.assert_array_equal(rebuilt.covariances, want.covariances)


def test_learn_prior_refuses_a_bad_component_count(capsys):
    assert main(["learn-prior", "clip.bvh", "--components", "0", "--out", "m.npz"]) == 2
    assert "must be a count from 1 to 32 or 'auto', got '0'" in capsys.readouterr().err
