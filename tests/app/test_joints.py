"""Direct joint rotation (FK) in the model, and the mannequin's geometry: no window."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik_studio.model import Document
from gsik_studio.model.joints import JointEditor, joint_dofs


def settle(doc, frames=400):
    for _ in range(frames):
        doc.step()
        if not doc.needs_solving:
            break


@pytest.fixture()
def doc():
    d = Document()
    # The plain solver: these tests check exact poses. The natural posture (on by default for the biped) goes on
    # turning what the targets leave free whenever the solver steps; tests/app/test_posture.py tests it.
    d.controls.set_posture_strength(0.0)
    settle(d)
    return d


def test_joint_dofs_name_each_rotation_with_its_axis_and_limits(doc):
    dofs = joint_dofs(doc, "left_shoulder")
    assert [d.axis for d in dofs] == ["x", "y", "z"]
    assert [d.name for d in dofs] == ["left_shoulder.x", "left_shoulder.y", "left_shoulder.z"]
    sk = doc.skeleton
    assert all(d.lower == sk.lower[d.index] and d.upper == sk.upper[d.index] for d in dofs)
    with pytest.raises(ValueError, match="joints: "):
        joint_dofs(doc, "left_wing")


def test_turning_a_joint_with_targets_following_holds_the_new_pose(doc):
    ed = JointEditor(doc)
    ed.select("left_elbow")
    (elbow,) = ed.dofs()
    before = doc.effector_poses()["left_hand"][:3, 3].copy()
    q_others = np.delete(doc.q, elbow.index)
    angle = ed.set_angle(elbow.index, elbow.lower + 0.5 * (elbow.upper - elbow.lower))
    settle(doc)
    assert doc.q[elbow.index] == pytest.approx(angle, abs=1e-6)
    np.testing.assert_allclose(np.delete(doc.q, elbow.index), q_others, atol=1e-6)
    hand = doc.effector_poses()["left_hand"][:3, 3]
    assert np.linalg.norm(hand - before) > 0.05  # the hand moved with the forearm
    np.testing.assert_allclose(doc.targets["left_hand"].position, hand, atol=1e-4)  # and its target with it


def test_turning_a_joint_with_targets_staying_gives_the_hand_back_to_its_target(doc):
    ed = JointEditor(doc)
    ed.targets_follow = False
    ed.select("waist")
    waist_x = ed.dofs()[0]
    target = doc.targets["left_hand"].position.copy()
    ed.set_angle(waist_x.index, 0.3)
    assert doc.targets["left_hand"].position.tolist() == target.tolist()
    settle(doc)
    np.testing.assert_allclose(doc.effector_poses()["left_hand"][:3, 3], target, atol=1e-3)


def test_an_angle_is_clamped_into_the_limits(doc):
    ed = JointEditor(doc)
    ed.select("left_knee")
    (knee,) = ed.dofs()
    assert ed.set_angle(knee.index, knee.upper + 2.0) == knee.upper
    assert doc.q[knee.index] == knee.upper


def test_one_ring_drag_is_one_undo_step_and_undo_restores_the_angles(doc):
    ed = JointEditor(doc)
    ed.select("right_shoulder")
    d = ed.dofs()[0]
    q0 = doc.q.copy()
    n = len(doc.history.commands)
    for k in range(1, 6):
        ed.set_angle(d.index, q0[d.index] + 0.1 * k, drag=7)
    doc.end_drag()
    assert len(doc.history.commands) == n + 1
    assert doc.undo()
    np.testing.assert_array_equal(doc.q, q0)


def test_only_joints_that_turn_can_be_selected(doc):
    ed = JointEditor(doc)
    seen = []
    ed.selection_changed.connect(seen.append)
    ed.select("left_knee")
    ed.select(None)
    assert seen == ["left_knee", None]
    with pytest.raises(ValueError, match="no joint 'hips' to turn"):
        ed.select("hips")


@pytest.mark.parametrize("root", ["right_foot", "left_foot", "pelvis"])
def test_every_mannequin_solid_stays_on_its_bone_in_any_pose_from_any_root(root):
    from gsik.mannequin import segment_shapes

    sk = gsik.load_skeleton("biped")
    shapes = segment_shapes(sk)
    assert len(shapes) == len(sk.bone_frames)
    solver = gsik.Solver(sk)
    solver.set_root(root)
    solver.set_q(np.random.default_rng(3).uniform(sk.lower, sk.upper))
    P, R = solver.world_positions(), solver.world_rotations()
    for (a, b), s in zip(sk.bone_frames, shapes):
        np.testing.assert_allclose(P[s.carrier] + R[s.carrier] @ s.start, P[a], atol=1e-12)
        np.testing.assert_allclose(P[s.carrier] + R[s.carrier] @ s.end, P[b], atol=1e-12)


def test_undo_texts_name_joints_and_targets_in_words(doc):
    ed = JointEditor(doc)
    ed.select("right_shoulder")
    ed.set_angle(next(d.index for d in ed.dofs() if d.axis == "y"), 0.2)
    assert doc.history.undo_text == "Turn right shoulder (y)"
    doc.rotate_target("left_hand", "z", 0.1)
    assert doc.history.undo_text == "Rotate left hand about z"
    doc.move_targets({"left_hand": [0.3, 0.2, 1.0], "head": [0.0, 0.0, 1.7]})
    assert doc.history.undo_text == "Move left hand, head"
    assert "_" not in " ".join(c.text for c in doc.history.commands)
