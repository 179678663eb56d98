"""The learned pose prior (issue 12): fitting, the file format, solving with it, the bundled prior's rebuild."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from gsik import Solver, Target, load_skeleton
from gsik.cli import main
from gsik.errors import PriorError
from gsik.kinematics import world_frames
from gsik.prior import (PosePrior, bundled_prior, bundled_prior_path, choose_shrinkage, fit_prior, read_prior,
                        use_prior, write_prior)

REAL_CLIP = Path(__file__).resolve().parents[2] / "shared" / "mocap" / "mocap_bvhtools_test.bvh"


def _poses(n: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Correlated biped poses inside the limits, with their true mean and covariance."""
    sk = load_skeleton("biped")
    rng = np.random.default_rng(seed)
    A = 0.05 * rng.normal(size=(sk.n_dofs, sk.n_dofs))
    mean = np.clip(sk.rest + 0.1, sk.lower + 0.3, sk.upper - 0.3)
    return mean + rng.normal(size=(n, sk.n_dofs)) @ A.T, mean, A @ A.T


def test_fit_prior_recovers_mean_and_covariance_of_gaussian_poses():
    sk = load_skeleton("biped")
    Q, mean, cov = _poses(20000)
    prior = fit_prior(Q, sk, shrinkage=0.0)
    np.testing.assert_allclose(prior.mean, mean, atol=0.01)
    np.testing.assert_allclose(prior.covariance - 4e-4 * np.eye(sk.n_dofs), cov, atol=0.003)
    np.testing.assert_allclose(prior.precision @ prior.covariance, np.eye(sk.n_dofs), atol=1e-8)
    assert not prior.mean.flags.writeable and not prior.precision.flags.writeable


def test_cross_validation_shrinks_little_data_more_than_much():
    few, _, _ = _poses(40)
    many, _, _ = _poses(20000)
    assert choose_shrinkage(few) > choose_shrinkage(many)


def test_a_prior_file_round_trips_and_garbage_is_refused(tmp_path):
    sk = load_skeleton("biped")
    prior = fit_prior(_poses()[0], sk, source="synthetic")
    path = tmp_path / "p.npz"
    write_prior(prior, path)
    back = read_prior(path)
    assert back.dof_names == sk.dof_names and back.source == "synthetic" and back.shrinkage == prior.shrinkage
    np.testing.assert_array_equal(back.covariance, prior.covariance)
    np.savez(path, mean=prior.mean)
    with pytest.raises(PriorError, match="missing 'format'"):
        read_prior(path)
    path.write_text("not a zip")
    with pytest.raises(PriorError, match="not a pose prior file"):
        read_prior(path)


def test_a_prior_for_another_skeleton_is_refused():
    sk = load_skeleton("biped")
    prior = fit_prior(_poses()[0], sk)
    other = PosePrior("arm", ("a.x",), [0.0], [[1.0]], 10, 0.1)
    with pytest.raises(PriorError, match="does not fit skeleton 'biped'"):
        use_prior(Solver(sk), other)
    with pytest.raises(PriorError, match="strength must be > 0"):
        use_prior(Solver(sk), prior, strength=0.0)


def test_solving_with_the_prior_meets_the_targets_and_returns_its_mean_when_the_targets_come_from_it():
    sk = load_skeleton("biped")
    prior = fit_prior(_poses()[0], sk)
    R, p = world_frames(sk, prior.mean)
    targets = {n: Target(p[sk.frame_of(n)]) for n in ("left_hand", "right_hand", "left_foot")}
    solver = Solver(sk, world_from_root=np.block([[R[sk.frame_of(sk.root)], p[sk.frame_of(sk.root)][:, None]],
                                                   [np.zeros((1, 3)), np.ones((1, 1))]]))
    use_prior(solver, prior)
    result = solver.solve(targets, q0=sk.rest)
    assert max(e[0] for e in result.errors().values()) < 1e-3
    np.testing.assert_allclose(result.q, prior.mean, atol=1e-3)
    use_prior(solver, None)
    assert solver.posture is None


def test_the_bundled_prior_fits_the_biped_and_says_where_it_came_from():
    prior = bundled_prior("biped")
    prior.check_fits(load_skeleton("biped"))
    assert "bvhtools" in prior.source and "MIT" in prior.source and "CMU" in prior.source
    assert prior.n_frames == 2 * 1791  # every 10th frame of the shared clips, and their mirror images
    with pytest.raises(PriorError, match="no pose prior is bundled for skeleton 'robot'.*'biped'"):
        bundled_prior("robot")


@pytest.mark.skipif(not REAL_CLIP.exists(), reason=f"the real clip {REAL_CLIP} is not beside the repository")
def test_learn_prior_rebuilds_the_prior_the_library_learns_from_the_clip(tmp_path):
    """The bundled prior's command on the clip's first frames (the whole clip takes minutes): the
    prior the library learns from the same retargeted frames, to the bit, in the bundled file's format."""
    from gsik.anim.retarget import Retargeter
    from gsik.io.bvh import BvhClip, read_bvh

    out = tmp_path / "prior.npz"
    text = io.StringIO()
    assert main(["learn-prior", str(REAL_CLIP), "--frames", "60", "--out", str(out), "--source", "test"],
                out=text) == 0, text.getvalue()
    assert "biped frames not mapped: head_top" in text.getvalue()
    full = read_bvh(REAL_CLIP)
    clip = BvhClip(full.joints, full.frame_time, full.motion[:60])
    sk = load_skeleton("biped")
    want = fit_prior(Retargeter(sk, clip).retarget(clip).motion.q, sk)
    rebuilt, bundled = read_prior(out), read_prior(bundled_prior_path("biped"))
    assert rebuilt.n_frames == 60 and rebuilt.dof_names == bundled.dof_names
    np.testing.assert_array_equal(rebuilt.mean, want.mean)
    np.testing.assert_array_equal(rebuilt.covariance, want.covariance)
