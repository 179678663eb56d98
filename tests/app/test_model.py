"""The studio's document model, driven without any display (no Qt, no PyVista)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import gsik
from gsik_studio.model import Document, History, Command, mirror_map
from gsik.io.pose import pose_to_yaml


def settle(doc: Document, max_frames: int = 500) -> gsik.SolveResult:
    for _ in range(max_frames):
        result = doc.step()
        if not doc.needs_solving:
            return result
    return result


@pytest.fixture()
def doc():
    d = Document()
    # The plain solver: these tests check exact poses. The natural posture (on by default for the biped) goes on
    # turning what the targets leave free whenever the solver steps; tests/app/test_posture.py tests it.
    d.controls.set_posture_strength(0.0)
    settle(d)
    return d


def test_model_imports_neither_qt_nor_pyvista():
    code = "import sys, gsik_studio.model, gsik.io.pose; bad = [m for m in sys.modules if m.split('.')[0] in " \
           "('PySide6', 'pyvista', 'pyvistaqt', 'vtk', 'vtkmodules', 'PyQt5', 'PyQt6')]; print(bad); " \
           "sys.exit(1 if bad else 0)"
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    r = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr


def test_new_document_stands_on_the_right_foot_with_targets_on_the_effectors(doc):
    assert doc.root == "right_foot"
    assert set(doc.targets) == {"head", "pelvis", "left_hand", "right_hand", "left_foot"}
    np.testing.assert_array_equal(doc.q, doc.skeleton.rest)
    for name, T in doc.effector_poses().items():
        np.testing.assert_allclose(doc.targets[name].position, T[:3, 3], atol=1e-12)
    assert doc.targets["left_hand"].position_only and not doc.targets["pelvis"].position_only
    assert not doc.dirty and not doc.history.can_undo
    assert doc.last_result.status is gsik.Status.CONVERGED


def test_drag_moves_the_target_and_the_solver_follows(doc):
    name = "left_hand"
    start = np.array(doc.effector_poses()[name][:3, 3])
    goal = start + [0.05, 0.25, 0.30]
    for k in range(1, 11):  # one drag: ten mouse moves
        doc.move_target(name, start + k / 10 * (goal - start), drag=1)
    doc.end_drag()
    np.testing.assert_array_equal(doc.targets[name].position, goal)
    assert len(doc.history.commands) == 1 and doc.history.undo_text == "Move left hand"
    assert doc.dirty and doc.needs_solving
    settle(doc)
    reached = doc.effector_poses()[name][:3, 3]
    assert np.linalg.norm(reached - goal) < 0.1 * np.linalg.norm(start - goal)


def test_separate_drags_are_separate_undo_steps(doc):
    p = np.array(doc.targets["head"].position)
    doc.move_target("head", p + [0, 0.05, 0], drag=1)
    doc.end_drag()
    doc.move_target("head", p + [0, 0.10, 0], drag=2)
    assert len(doc.history.commands) == 2


def test_undo_and_redo_restore_angles_and_targets_exactly(doc):
    before = doc.pose()
    doc.move_target("right_hand", np.array(doc.targets["right_hand"].position) + [0.1, 0.2, 0.3])
    settle(doc)
    doc.rotate_target("head", "z", 0.3)
    settle(doc)
    doc.set_target_options("pelvis", weight=2.5, position_only=True)
    settle(doc)
    after = doc.pose()
    q_after = doc.q
    assert after != before
    assert doc.undo() and doc.undo() and doc.undo()
    assert doc.pose() == before
    np.testing.assert_array_equal(doc.q, before.q(doc.skeleton))
    assert not doc.dirty
    assert doc.redo() and doc.redo() and doc.redo()
    assert doc.pose() == after
    np.testing.assert_array_equal(doc.q, q_after)
    assert not doc.redo()


def test_a_new_edit_drops_the_redo_steps(doc):
    doc.random_pose(seed=3)
    doc.undo()
    assert doc.history.can_redo
    doc.rotate_target("pelvis", "x", 0.1)
    assert not doc.history.can_redo


def test_root_switch_keeps_every_joint_in_place(doc):
    doc.random_pose(seed=7)
    settle(doc)
    P = doc.solver.world_positions()
    q = doc.q
    doc.set_root("left_foot")
    assert doc.root == "left_foot"
    np.testing.assert_allclose(doc.solver.world_positions(), P, atol=1e-12)
    np.testing.assert_array_equal(doc.q, q)
    assert "left_foot" not in doc.targets and "right_foot" in doc.targets
    np.testing.assert_allclose(doc.targets["right_foot"].position, P[doc.skeleton.frame_of("right_foot")], atol=1e-12)
    # The solver agrees with the pose: nothing moves on the next frames.
    settle(doc)
    np.testing.assert_allclose(doc.solver.world_positions(), P, atol=1e-6)
    doc.undo()
    assert doc.root == "right_foot"
    np.testing.assert_allclose(doc.solver.world_positions(), P, atol=1e-12)


def test_reset_returns_to_the_standing_pose(doc):
    doc.random_pose(seed=1)
    doc.set_root("left_foot")
    doc.set_target_options("head", enabled=False)
    doc.reset()
    assert doc.root == "right_foot"
    np.testing.assert_array_equal(doc.q, doc.skeleton.rest)
    assert doc.targets["head"].enabled is False  # flags survive a reset


def test_random_pose_is_within_limits_and_targets_follow(doc):
    doc.random_pose(seed=11)
    q = doc.q
    sk = doc.skeleton
    assert np.all(q >= sk.lower) and np.all(q <= sk.upper)
    assert np.abs(q - sk.rest).max() > 0.05
    for name, T in doc.effector_poses().items():
        np.testing.assert_allclose(doc.targets[name].position, T[:3, 3], atol=1e-12)


def test_mirror_copies_one_side_onto_the_other(doc):
    sk = doc.skeleton
    q = sk.rest.copy()
    q[sk.dof_index("left_shoulder.x")] = 1.2
    q[sk.dof_index("left_shoulder.y")] = 0.6
    q[sk.dof_index("left_shoulder.z")] = -0.4
    q[sk.dof_index("left_elbow.x")] = 1.0
    doc.set_angles(q)
    doc.mirror("left")
    got = doc.q
    assert got[sk.dof_index("right_shoulder.x")] == 1.2
    assert got[sk.dof_index("right_shoulder.y")] == -0.6
    assert got[sk.dof_index("right_shoulder.z")] == 0.4
    assert got[sk.dof_index("right_elbow.x")] == 1.0
    # The arms are mirror images in the plane x = 0 (relative to the pelvis).
    P = doc.solver.world_positions()
    pelvis = P[sk.frame_of("pelvis")]
    lh, rh = P[sk.frame_of("left_hand")] - pelvis, P[sk.frame_of("right_hand")] - pelvis
    np.testing.assert_allclose(lh * [-1, 1, 1], rh, atol=1e-9)
    doc.mirror("right")  # now symmetric: right to left changes nothing
    np.testing.assert_array_equal(doc.q, got)


def test_mirror_map_pairs_every_limb_dof(doc):
    pairs = mirror_map(doc.skeleton, "left")
    assert len(pairs) == 11  # shoulder 3 + elbow 1 + hip 3 + knee 1 + ankle 3
    with pytest.raises(ValueError):
        mirror_map(doc.skeleton, "up")


def test_save_and_open_round_trip_exactly(doc, tmp_path):
    doc.random_pose(seed=5)
    doc.set_root("left_foot")
    doc.move_target("right_hand", np.array(doc.targets["right_hand"].position) + [0.0, 0.1, 0.1])
    doc.set_target_options("head", enabled=False)
    for _ in range(3):
        doc.step()
    path = tmp_path / "pose.yaml"
    doc.save(str(path))
    assert not doc.dirty and doc.path == str(path)
    saved = doc.pose()
    other = Document()
    warnings = other.open(str(path))
    assert warnings == ()
    assert other.pose() == saved
    np.testing.assert_array_equal(other.q, doc.q)
    np.testing.assert_array_equal(other.solver.world_from_root, doc.solver.world_from_root)
    np.testing.assert_array_equal(other.solver.world_positions(), doc.solver.world_positions())
    assert other.root == "left_foot" and not other.dirty and not other.history.can_undo
    path2 = tmp_path / "again.yaml"
    other.save(str(path2))
    assert path2.read_bytes() == path.read_bytes()


def test_open_with_clamped_angles_reports_and_marks_dirty(doc, tmp_path):
    pose = doc.pose()
    pose = pose.replace(joints={**pose.joints, "right_elbow.x": 3.5})
    path = tmp_path / "clamped.yaml"
    path.write_text(pose_to_yaml(pose))
    warnings = doc.open(str(path))
    assert len(warnings) == 1 and "right_elbow.x" in warnings[0]
    assert doc.q[doc.skeleton.dof_index("right_elbow.x")] == doc.skeleton.upper[doc.skeleton.dof_index("right_elbow.x")]
    assert doc.dirty


@pytest.mark.parametrize("content", [
    "format: 1\nskeleton: biped\n  bad: [\n",
    "not: a pose\n",
    None,  # the valid pose for another skeleton
    "",
])
def test_bad_file_leaves_the_document_untouched(doc, tmp_path, content):
    doc.random_pose(seed=2)
    doc.move_target("head", np.array(doc.targets["head"].position) + [0.0, 0.05, 0.0])
    for _ in range(2):
        doc.step()
    if content is None:
        content = pose_to_yaml(doc.pose()).replace("skeleton: biped", "skeleton: robot")
    path = tmp_path / "bad.yaml"
    path.write_text(content)
    before, q, n_commands, dirty = doc.pose(), doc.q, len(doc.history.commands), doc.dirty
    with pytest.raises(gsik.PoseError):
        doc.open(str(path))
    assert doc.pose() == before
    np.testing.assert_array_equal(doc.q, q)
    assert len(doc.history.commands) == n_commands and doc.dirty == dirty and doc.path is None


def test_missing_file_leaves_the_document_untouched(doc, tmp_path):
    before = doc.pose()
    with pytest.raises(gsik.GsikFileError):
        doc.open(str(tmp_path / "missing.yaml"))
    assert doc.pose() == before


def test_failed_save_keeps_path_dirty_flag_and_old_file(doc, tmp_path, monkeypatch):
    path = tmp_path / "pose.yaml"
    doc.save(str(path))
    old = path.read_bytes()
    doc.random_pose(seed=9)
    assert doc.dirty

    def full_disk(*_a, **_k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", full_disk)
    with pytest.raises(gsik.GsikFileError):
        doc.save()
    assert doc.dirty and doc.path == str(path)
    assert path.read_bytes() == old


def test_save_without_a_path_is_an_error(doc):
    with pytest.raises(gsik.GsikFileError):
        doc.save()


def test_disabled_effector_is_free(doc):
    doc.set_target_options("left_hand", enabled=False)
    assert "left_hand" not in doc.solver.targets
    doc.move_target("left_hand", (0.0, 1.0, 1.0))
    settle(doc)
    hand = doc.effector_poses()["left_hand"][:3, 3]
    assert np.linalg.norm(hand - [0.0, 1.0, 1.0]) > 0.5


def test_settings_reach_the_solver(doc):
    doc.configure(sweeps=3, damping=0.01)
    assert doc.solver.settings.sweeps == 3 and doc.solver.settings.damping == 0.01
    with pytest.raises(gsik.SolverError):
        doc.configure(sweeps=0)


def test_unknown_effector_is_an_error_naming_the_valid_ones(doc):
    with pytest.raises(gsik.TargetError) as info:
        doc.move_target("right_foot", (0, 0, 0))
    assert "IK root" in str(info.value) and "'left_foot'" in str(info.value)


def test_history_merges_one_drag_and_keeps_the_clean_mark():
    h = History()
    from gsik.io.pose import Pose
    p = Pose("s", "r", (0, 0, 0), (1, 0, 0, 0), {}, {})
    assert h.push(Command("a", p, merge_key=("move", 1)))
    assert not h.push(Command("a", p, merge_key=("move", 1)))
    h.set_clean()
    assert h.is_clean
    h.end_merge()
    assert h.push(Command("a", p, merge_key=("move", 1)))
    assert not h.is_clean and len(h.commands) == 2


def test_playback_of_a_motion_is_one_undo_step(doc):
    from gsik.anim.motion import Motion

    sk = doc.skeleton
    n = 5
    q = np.tile(sk.rest, (n, 1))
    q[:, sk.dof_index("left_elbow.x")] = np.linspace(0.2, 1.5, n)
    W = np.tile(doc.solver.world_from_root, (n, 1, 1))
    W[:, 1, 3] += np.linspace(0.0, 0.4, n)
    motion = Motion(sk, q, ("right_foot",) * n, W, 1 / 30)
    before = doc.pose()
    pb = doc.playback(motion, "Play test")
    frames = 0
    while pb.advance():
        frames += 1
    assert frames == n and pb.finished
    np.testing.assert_array_equal(doc.q, q[-1])
    np.testing.assert_allclose(doc.solver.world_from_root, W[-1], atol=1e-12)
    assert doc.history.undo_text == "Play test"
    doc.undo()
    assert doc.pose() == before


def test_playback_of_target_frames_steps_the_solver(doc):
    start = np.array(doc.targets["left_hand"].position)
    frames = [{"left_hand": gsik.Target(start + [0.0, 0.02 * k, 0.02 * k])} for k in range(1, 21)]
    pb = doc.playback(frames, "Reach")
    while pb.advance():
        pass
    hand = doc.effector_poses()["left_hand"][:3, 3]
    assert np.linalg.norm(hand - (start + [0.0, 0.4, 0.4])) < np.linalg.norm(start - (start + [0.0, 0.4, 0.4]))
    assert doc.history.undo_text == "Reach"


def test_an_edit_during_playback_stops_it_and_both_are_undoable(doc):
    start = np.array(doc.targets["left_foot"].position)
    frames = [{"left_foot": gsik.Target(start + [0.0, 0.0, 0.01 * k])} for k in range(1, 30)]
    before = doc.pose()
    pb = doc.playback(frames, "Lift")
    for _ in range(5):
        assert pb.advance()
    doc.set_root("left_foot")  # the played effector becomes the root
    assert pb.finished and not pb.advance()
    assert [c.text for c in doc.history.commands] == ["Lift", "Root on left foot"]
    # A playback whose effector is now the root skips it instead of failing.
    pb2 = doc.playback(frames, "Lift again")
    while pb2.advance():
        pass
    assert doc.history.undo_text == "Lift again"
    doc.undo()
    doc.undo()
    doc.undo()
    assert doc.pose() == before
