"""Pins (strict priority levels), posture strength, balance and the centre of mass in the model: no window."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik.io.pose import read_pose
from gsik_studio.model import Document
from gsik_studio.model.pins import FREE, PINNED, is_pinned


def settle(doc, frames=600):
    for _ in range(frames):
        doc.step()
        if not doc.needs_solving:
            break


def pull(doc, name, offset, frames=400):
    """Drag a target by ``offset`` [m] in 10 mouse moves, solving between them, then let it settle."""
    start = doc.targets[name].position.copy()
    for k in range(1, 11):
        doc.move_target(name, start + np.asarray(offset) * k / 10, drag=1)
        for _ in range(5):
            doc.step()
    doc.end_drag()
    settle(doc, frames)


@pytest.fixture()
def doc():
    d = Document()
    settle(d)
    return d


def test_feet_and_pelvis_are_pinned_by_default_hands_and_head_are_not(doc):
    t = doc.targets
    assert is_pinned(t["pelvis"]) and is_pinned(t["left_foot"])
    assert not is_pinned(t["left_hand"]) and not is_pinned(t["head"])
    assert t["left_hand"].priority == FREE


def test_pulling_a_hand_out_of_reach_never_moves_the_pinned_pelvis_and_foot(doc):
    pelvis = doc.effector_poses()["pelvis"][:3, 3].copy()
    foot = doc.effector_poses()["left_foot"][:3, 3].copy()
    pull(doc, "left_hand", (-1.5, 1.0, 0.3))
    poses = doc.effector_poses()
    assert np.linalg.norm(poses["pelvis"][:3, 3] - pelvis) < 1e-4
    assert np.linalg.norm(poses["left_foot"][:3, 3] - foot) < 1e-4
    assert np.linalg.norm(poses["left_hand"][:3, 3] - doc.targets["left_hand"].position) > 0.5  # out of reach


def test_an_unpinned_pelvis_follows_a_hand_pulled_out_of_reach(doc):
    pelvis = doc.effector_poses()["pelvis"][:3, 3].copy()
    doc.set_target_options("pelvis", priority=FREE)
    assert doc.history.undo_text == "Set pelvis priority 1"
    pull(doc, "left_hand", (-1.5, 1.0, 0.3))
    assert np.linalg.norm(doc.effector_poses()["pelvis"][:3, 3] - pelvis) > 0.01


def test_a_pin_is_undone_redone_and_saved_with_its_target(doc, tmp_path):
    doc.set_target_options("left_hand", priority=PINNED)
    assert is_pinned(doc.targets["left_hand"])
    doc.undo()
    assert not is_pinned(doc.targets["left_hand"])
    doc.redo()
    assert is_pinned(doc.targets["left_hand"])
    doc.save(tmp_path / "p.yaml")
    pose = read_pose(tmp_path / "p.yaml", doc.skeleton).pose
    assert pose.targets["left_hand"].priority == PINNED and pose.targets["right_hand"].priority == FREE


def test_pins_survive_reset_random_pose_and_a_root_switch(doc):
    doc.set_target_options("head", priority=PINNED)
    doc.random_pose(seed=2)
    doc.reset()
    doc.set_root("left_foot")
    t = doc.targets
    assert is_pinned(t["head"]) and is_pinned(t["right_foot"]) and not is_pinned(t["left_hand"])


def test_posture_strength_and_balance_reach_the_solver_and_refuse_bad_values(doc):
    seen = []
    doc.controls.changed.connect(lambda: seen.append(1))
    doc.controls.set_posture_strength(0.5)
    assert doc.solver.posture is not None and doc.controls.posture_strength == 0.5
    doc.controls.set_posture_strength(0.0)
    assert doc.solver.posture is None
    with pytest.raises(gsik.SolverError, match="posture strength"):
        doc.controls.set_posture_strength(-1.0)
    doc.controls.set_balance(True)
    assert doc.solver.balance and doc.controls.balance
    assert len(seen) == 3


def test_the_support_polygon_is_under_the_feet_and_holds_the_centre_of_mass_standing(doc):
    s = doc.controls.support()
    P = doc.world_positions()
    sk = doc.skeleton
    feet = P[[sk.frame_of("left_foot"), sk.frame_of("right_foot")]]
    assert s.polygon.shape[1] == 2 and len(s.polygon) >= 4
    lo, hi = s.polygon.min(axis=0), s.polygon.max(axis=0)
    assert np.all(lo <= feet[:, :2].min(axis=0)) and np.all(hi >= feet[:, :2].max(axis=0))
    assert s.inside
    np.testing.assert_allclose(s.com, doc.solver.center_of_mass())


def test_with_balance_a_hand_pulled_forward_keeps_the_centre_of_mass_over_the_feet(doc):
    doc.set_target_options("left_foot", enabled=False)  # stand on the right foot only
    settle(doc)
    doc.controls.set_balance(True)
    settle(doc)
    pull(doc, "left_hand", (0.0, 0.8, 0.0))
    assert doc.controls.support().inside


def test_a_pole_target_swings_the_knee_without_moving_the_feet_or_pelvis(doc):
    doc.move_target("pelvis", doc.targets["pelvis"].position + (0.0, 0.0, -0.08))  # crouch: the knees bend
    settle(doc)
    doc.controls.set_poles(True)
    assert set(doc.controls.poles) == {"left_knee", "right_knee", "left_elbow", "right_elbow"}
    settle(doc)
    knee0 = doc.controls.joint_position("left_knee").copy()
    poses0 = {n: T[:3, 3].copy() for n, T in doc.effector_poses().items()}
    doc.controls.move_pole("left_knee", knee0 + (-0.3, 0.0, 0.0))  # swing the knee outwards
    settle(doc)
    knee = doc.controls.joint_position("left_knee")
    assert knee[0] - knee0[0] < -0.03
    for name in ("pelvis", "left_foot"):
        assert np.linalg.norm(doc.effector_poses()[name][:3, 3] - poses0[name]) < 1e-4
    doc.controls.set_poles(False)
    assert doc.controls.poles == {} and "left_knee" not in doc.solver.targets
    with pytest.raises(gsik.TargetError, match="no pole target"):
        doc.controls.move_pole("left_knee", knee0)
