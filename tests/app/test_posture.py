"""The natural posture (the learned pose prior) and its fall-back to the rest pose, in the model: no window."""

from __future__ import annotations

import os

import numpy as np
import pytest

import gsik
from gsik.io.urdf_skeleton import skeleton_from_urdf
from gsik.prior import bundled_prior
from gsik_studio.model import Document
from gsik_studio.model.posture import NATURAL_STRENGTH, prior_for

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")


def _settle(doc: Document, max_steps: int = 400) -> None:
    for _ in range(max_steps):
        if not doc.needs_solving:
            return
        doc.step()


def _reach(doc: Document) -> np.ndarray:
    """Pull the left hand up and out, settle; the angles (n_dofs,) [rad]."""
    hand = np.array(doc.targets["left_hand"].position)
    doc.move_target("left_hand", hand + [0.15, 0.10, 0.25])
    _settle(doc)
    return doc.q


@pytest.mark.parametrize("name", ["biped", "humanoid"])
def test_a_bundled_skeleton_starts_natural_with_its_bundled_prior_as_the_posture(name):
    doc = Document(gsik.load_skeleton(name))
    prior = bundled_prior(name)
    assert prior.dof_names == doc.skeleton.dof_names
    c = doc.controls
    assert c.natural and c.posture.can_be_natural and c.posture_strength == NATURAL_STRENGTH
    posture = doc.solver.posture
    np.testing.assert_allclose(posture.reference, np.clip(prior.mean, doc.skeleton.lower, doc.skeleton.upper))
    np.testing.assert_allclose(posture.precision, NATURAL_STRENGTH * prior.precision)


def test_the_toggle_falls_back_to_the_rest_pose_and_back_and_says_so():
    doc = Document()
    seen = []
    doc.controls.changed.connect(lambda: seen.append(doc.controls.natural))
    doc.controls.set_natural(False)
    posture = doc.solver.posture
    np.testing.assert_allclose(posture.reference, doc.skeleton.rest)
    np.testing.assert_allclose(posture.precision, np.full(doc.skeleton.n_dofs, NATURAL_STRENGTH))
    doc.controls.set_posture_strength(0.0)
    assert doc.solver.posture is None and not doc.controls.natural
    doc.controls.set_natural(True)
    assert doc.solver.posture is None  # strength 0 keeps the posture off, natural or not
    doc.controls.set_posture_strength(2.0)
    np.testing.assert_allclose(doc.solver.posture.precision, 2.0 * bundled_prior("biped").precision)
    assert seen == [False, False, True, True]


def test_natural_reaches_meet_the_target_with_a_likelier_body_than_rest():
    prior = bundled_prior("biped")
    natural, rest = Document(), Document()
    rest.controls.set_natural(False)
    q_natural, q_rest = _reach(natural), _reach(rest)
    for doc in (natural, rest):
        assert doc.effector_errors()["left_hand"][0] < 1e-3
    assert prior.mahalanobis(q_natural) < prior.mahalanobis(q_rest)


def test_a_skeleton_without_a_bundled_prior_keeps_the_plain_solver():
    sk = skeleton_from_urdf(os.path.join(DATA, "humanoid.urdf"))
    assert prior_for(sk) is None
    doc = Document(sk)
    c = doc.controls
    assert not c.natural and not c.posture.can_be_natural and c.posture_strength == 0.0
    assert doc.solver.posture is None
    with pytest.raises(gsik.SolverError, match="no pose prior is bundled for skeleton 'mini_humanoid'"):
        c.set_natural(True)
    c.set_posture_strength(0.5)
    np.testing.assert_allclose(doc.solver.posture.reference, sk.rest)


def test_when_the_rule_picks_the_rest_posture_the_prior_is_one_click_away(monkeypatch):
    """Issue 18's rule may pick the rest posture as the default: then a new biped document prefers the rest
    pose at full strength and the natural toggle switches the bundled prior on."""
    from gsik_studio.model import posture

    monkeypatch.setattr(posture, "NATURAL_BY_DEFAULT", False)
    doc = Document()
    c = doc.controls
    assert not c.natural and c.posture.can_be_natural and c.posture_strength == NATURAL_STRENGTH
    np.testing.assert_allclose(doc.solver.posture.reference, doc.skeleton.rest)
    c.set_natural(True)
    np.testing.assert_allclose(doc.solver.posture.precision, NATURAL_STRENGTH * bundled_prior("biped").precision)
