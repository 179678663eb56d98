"""The humanoid in the real window under Xvfb: File → New on skeleton, its mannequin, a turned hand turns its wrist."""

from __future__ import annotations

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui


def _choose(qtbot, menu, action):
    """Hover ``action`` of an open ``menu`` and click it with the mouse (Qt events, as a person's)."""
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    wait_for(qtbot, menu.isVisible)
    pos = menu.actionGeometry(action).center()
    QTest.mouseMove(menu, pos)
    QTest.mouseClick(menu, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, pos)


def _new_on(qtbot, window, label):
    """File → New on skeleton → ``label``, with the mouse."""
    from PySide6 import QtCore
    from PySide6.QtTest import QTest

    bar = window.menuBar()
    file_action = next(a for a in bar.actions() if a.text() == "&File")
    QTest.mouseClick(bar, QtCore.Qt.LeftButton, QtCore.Qt.NoModifier, bar.actionGeometry(file_action).center())
    file_menu, new_menu = file_action.menu(), window.files.new_menu
    assert new_menu.menuAction() in file_menu.actions()
    wait_for(qtbot, file_menu.isVisible)
    QTest.mouseMove(file_menu, file_menu.actionGeometry(new_menu.menuAction()).center())  # opens the submenu
    entries = {a.text(): a for a in new_menu.actions()}
    assert set(entries) == {"biped (30 DOF)", "humanoid (43 DOF)"}  # every bundled skeleton
    _choose(qtbot, new_menu, entries[label])


def test_file_new_on_the_humanoid_shows_its_mannequin_and_a_turned_hand_turns_its_wrist(qtbot, window, boxes):
    from PySide6 import QtCore
    from gsik.rotations import angle_between

    window.doc.move_target("left_hand", window.doc.targets["left_hand"].position + (0.0, 0.1, 0.0))  # unsaved:
    _new_on(qtbot, window, "humanoid (43 DOF)")
    wait_for(qtbot, lambda: window.doc.skeleton.name == "humanoid")
    assert [title for title, _ in boxes["question"]] == ["Unsaved changes"]  # asked, answered "Discard"
    doc, sk = window.doc, window.doc.skeleton
    # Its mannequin has hands: a solid carried by each wrist.
    carriers = {sk.frame_names[c] for m in window.body.mannequin.meshes for c in m.carriers}
    assert {"left_wrist.x", "right_wrist.x", "chest.z", "left_clavicle.z"} <= carriers
    assert doc.controls.natural and doc.solver.posture is not None  # its own bundled prior: natural
    wait_for(qtbot, lambda: not doc.needs_solving)
    chest, hips = sk.frame_of("chest.z"), sk.frame_of("hips")
    R0 = doc.world_rotations()
    pelvis = doc.effector_poses()["pelvis"][:3, 3].copy()
    # The hand target, with its orientation: untick "pos only", turn it 3 x 15 degrees about y.
    window.viewport.select("left_hand")
    row = window.rows["left_hand"]
    qtbot.mouseClick(row.position_only, QtCore.Qt.LeftButton, pos=row.position_only.rect().center())
    assert not doc.targets["left_hand"].position_only
    for _ in range(3):
        qtbot.mouseClick(window.rotate_buttons[("y", 1)], QtCore.Qt.LeftButton)
    wait_for(qtbot, lambda: not doc.needs_solving)
    position_error, orientation_error = doc.effector_errors()["left_hand"]
    assert orientation_error < np.radians(0.5) and position_error < 1e-3
    R = doc.world_rotations()
    assert angle_between(R[chest], R0[chest]) < np.radians(3.0)  # the hand turned, not the body
    assert angle_between(R[hips], R0[hips]) < np.radians(0.5)
    assert np.linalg.norm(doc.effector_poses()["pelvis"][:3, 3] - pelvis) < 1e-3
    wrist = [sk.dof_index(f"left_wrist.{a}") for a in "zyx"]
    assert np.degrees(np.abs(doc.q[wrist] - sk.rest[wrist]).sum()) > 30.0

