"""File → Import BVH clip, Import skeleton and Export BVH in the real window (dialogs bypassed by the path entry points)."""

from __future__ import annotations

import os

import numpy as np
import pytest

import gsik
from gsik.io.bvh import read_bvh
from waiting import wait_for

pytestmark = pytest.mark.gui


DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")


def _menu_actions(window, title):
    menu = next(a.menu() for a in window.menuBar().actions() if a.text() == title)
    return {a.text(): a for a in menu.actions()}


def test_file_menu_has_import_and_export(window):
    names = _menu_actions(window, "&File")
    assert {"Import BVH &clip…", "Import s&keleton…", "&Export BVH…"} <= set(names)


def test_export_pose_then_walk_clip_then_reimport_it_onto_the_timeline(qtbot, window, tmp_path):
    doc = window.doc
    pose_path = str(tmp_path / "pose.bvh")
    assert window.files.export_bvh_path(pose_path)
    assert read_bvh(pose_path).n_frames == 1
    pb = window.play_walk(n_steps=1)
    n = pb.n_frames
    window.stop_playback()
    clip_path = str(tmp_path / "walk.bvh")
    assert window.files.export_bvh_path(clip_path)
    assert read_bvh(clip_path).n_frames == n
    window.doc.timeline.discard()
    assert window.files.import_clip_path(clip_path) is True  # the biped's own clip: on this document
    tl = doc.timeline
    assert tl.clip is not None and tl.clip.n_frames == n and tl.name == "walk.bvh" and tl.playing
    wait_for(qtbot, lambda: not tl.playing)
    pelvis = doc.world_positions()[doc.skeleton.frame_of("pelvis")]
    assert pelvis[1] > 0.15  # the re-imported walk walked forward


def test_keyed_sequence_exports_every_frame(qtbot, window, tmp_path):
    from PySide6.QtCore import Qt

    bar, doc = window.timeline_bar, window.doc
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)
    doc.timeline.frame = 12
    doc.move_target("left_hand", np.array(doc.targets["left_hand"].position) + [0, 0.2, 0.2])
    window.settle()
    qtbot.mouseClick(bar.buttons["key"], Qt.LeftButton)
    path = str(tmp_path / "keys.bvh")
    assert window.files.export_bvh_path(path)
    assert read_bvh(path).n_frames == doc.timeline.n_frames == 90  # the keys' whole timeline


def _dialog_returns(monkeypatch, path):
    from PySide6.QtWidgets import QFileDialog

    monkeypatch.setattr(QFileDialog, "getOpenFileName", staticmethod(lambda *a, **k: (path, "")))


def _shows_skeleton(window, skeleton):
    """True when the window's scene, panels, timeline and read-outs are those of a document on ``skeleton``."""
    doc = window.doc
    return (doc.skeleton is skeleton and window.loop.doc is doc and window.files.doc is doc
            and window.viewport.doc is doc and window.joints.doc is doc and window.timeline_bar.timeline is doc.timeline
            and set(window.rows) == set(skeleton.effector_sites)
            and window.viewport._joints.n_points == len(skeleton.joint_frame)
            and window.centralWidget() is window.plotter and window.status.doc is doc)


def test_import_skeleton_rebuilds_this_window_asking_first_about_unsaved_changes(qtbot, window, boxes, monkeypatch):
    from PySide6.QtWidgets import QMessageBox

    _dialog_returns(monkeypatch, os.path.join(DATA, "humanoid.urdf"))
    biped = window.doc
    biped.random_pose(seed=5)
    window.act_sticks.trigger()  # a view option: it stays for the new document
    boxes["answer"] = QMessageBox.Cancel
    window.act_import_skeleton.trigger()  # File -> Import skeleton..., unsaved changes: Cancel
    assert len(boxes["question"]) == 1 and "import another skeleton" in boxes["question"][0][1]
    assert window.doc is biped and biped.dirty
    boxes["answer"] = QMessageBox.Discard
    window.act_import_skeleton.trigger()
    assert len(boxes["question"]) == 2 and not window.others
    doc = window.doc
    assert doc is not biped and doc.skeleton.name == "mini_humanoid" and doc.root == doc.skeleton.root
    assert _shows_skeleton(window, doc.skeleton)
    assert window.body.mode == "sticks" and window.act_sticks.isChecked()
    assert set(doc.targets) == set(doc.skeleton.effector_sites) - {doc.root}
    assert not window.act_root_left.isEnabled()  # no feet to pin
    assert window.windowTitle().startswith("Untitled") and not doc.dirty and not window.act_undo.isEnabled()
    assert "mini_humanoid" in window.statusBar().currentMessage()
    name = sorted(doc.targets)[0]
    doc.move_target(name, np.array(doc.targets[name].position) + [0.0, 0.0, -0.05])
    assert window.timer.isActive()  # the new document's frame loop drives this window's timer
    wait_for(qtbot, lambda: not window.timer.isActive())
    assert doc.last_result is not None
    widget = window.viewport.target_widgets[window.viewport._sites.index(name)]
    np.testing.assert_allclose(widget.GetCenter(), doc.targets[name].position, atol=1e-9)
    window.act_undo.trigger()
    assert not doc.dirty and window.doc is doc


def test_import_skeleton_in_a_new_window_keeps_this_one(qtbot, window, monkeypatch):
    _dialog_returns(monkeypatch, os.path.join(DATA, "humanoid.urdf"))
    window.act_import_skeleton_window.trigger()  # File -> Import skeleton in new window...
    assert len(window.others) == 1
    other = window.others[0]
    try:
        qtbot.waitExposed(other)
        doc = other.doc
        assert doc.skeleton.name == "mini_humanoid" and doc.root == doc.skeleton.root
        assert set(doc.targets) == set(doc.skeleton.effector_sites) - {doc.root}
        assert not other.act_root_left.isEnabled() and window.act_root_left.isEnabled()  # no feet to pin
        name = sorted(doc.targets)[0]
        doc.move_target(name, np.array(doc.targets[name].position) + [0.0, 0.0, -0.05])
        wait_for(qtbot, lambda: not other.timer.isActive())
        assert doc.last_result is not None
        assert window.doc.skeleton.name == "biped"  # this window's document is untouched
    finally:
        other.doc.history.set_clean()
        other.close()


def test_import_a_clip_of_another_skeleton_plays_in_this_window_on_its_own_document(qtbot, window, monkeypatch):
    _dialog_returns(monkeypatch, os.path.join(DATA, "walk_zxy.bvh"))
    window.act_import_clip.trigger()  # File -> Import BVH clip... (the document is clean: no question)
    doc = window.doc
    tl = doc.timeline
    assert doc.skeleton.name == "walk_zxy" and tl.clip is not None and tl.n_frames == 4 and not window.others
    assert _shows_skeleton(window, doc.skeleton)
    wait_for(qtbot, lambda: not tl.playing)
    assert tl.frame == tl.n_frames - 1


@pytest.mark.parametrize("kind", ["clip", "skeleton"])
def test_a_bad_file_gets_one_dialog_and_changes_nothing(qtbot, window, boxes, tmp_path, kind):
    bad = tmp_path / ("bad.bvh" if kind == "clip" else "bad.urdf")
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n" if kind == "clip" else "<robot><link/></robot>")
    before, history = window.doc.pose(), list(window.doc.history.commands)
    importer = window.files.import_clip_path if kind == "clip" else window.files.import_skeleton_path
    assert importer(str(bad)) is False
    assert len(boxes["critical"]) == 1 and str(bad.name) in window.statusBar().currentMessage()
    assert window.doc.pose() == before and window.doc.history.commands == history and not window.others


def test_export_to_an_unwritable_place_reports_and_writes_nothing(qtbot, window, boxes, tmp_path):
    path = tmp_path / "missing" / "x.bvh"
    assert window.files.export_bvh_path(str(path)) is False
    assert len(boxes["critical"]) == 1 and not path.exists()


def test_bad_skeleton_error_is_a_gsik_error():
    from gsik_studio.model import transfer

    with pytest.raises(gsik.GsikError):
        transfer.read_skeleton(os.path.join(DATA, "walk_zxy.bvh"))  # not YAML


def test_open_after_import_skeleton_opens_the_pose_on_its_own_skeleton_and_a_bad_file_changes_nothing(
        qtbot, window, boxes, monkeypatch, tmp_path):
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QMessageBox

    biped_pose = tmp_path / "biped pose.yaml"
    window.doc.random_pose(seed=3)
    assert window.save_to(str(biped_pose))
    want = window.doc.pose()
    assert window.windowTitle().startswith("biped pose.yaml") and "biped" in window.windowTitle()
    _dialog_returns(monkeypatch, os.path.join(DATA, "humanoid.urdf"))
    window.act_import_skeleton.trigger()
    mini = window.doc
    assert mini.skeleton.name == "mini_humanoid" and "mini_humanoid" in window.windowTitle()
    name = sorted(mini.targets)[0]
    mini.move_target(name, np.array(mini.targets[name].position) + [0.0, 0.0, -0.05])  # unsaved
    before = mini.pose()
    text = biped_pose.read_text()
    assert "root: right_foot" in text
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("root: right_foot", "root: tail", 1))  # a biped pose with an unknown root
    boxes["answer"] = QMessageBox.Discard
    _dialog_returns(monkeypatch, str(bad))
    qtbot.keyClick(window, Qt.Key_O, Qt.ControlModifier)  # File → Open
    assert len(boxes["question"]) == 1 and "open another pose" in boxes["question"][0][1]
    assert len(boxes["critical"]) == 1 and "tail" in boxes["critical"][0][1]
    assert window.doc is mini and mini.pose() == before and mini.dirty and _shows_skeleton(window, mini.skeleton)
    _dialog_returns(monkeypatch, str(biped_pose))
    qtbot.keyClick(window, Qt.Key_O, Qt.ControlModifier)
    assert len(boxes["question"]) == 2 and len(boxes["critical"]) == 1
    doc = window.doc
    assert doc is not mini and doc.skeleton.name == "biped" and _shows_skeleton(window, doc.skeleton)
    assert (doc.targets, doc.root) == (want.targets, want.root) and doc.path == str(biped_pose)  # the file's pose
    assert window.windowTitle() == "biped pose.yaml[*] — biped — gsik studio"
    window.save_screenshot(str(tmp_path / "opened.png"))


def test_a_pose_of_a_skeleton_that_is_neither_shown_nor_bundled_says_to_import_it(window, boxes, tmp_path):
    from gsik_studio.model import transfer

    path = tmp_path / "mini.yaml"
    mini = transfer.document_for(transfer.read_skeleton(os.path.join(DATA, "humanoid.urdf")))
    mini.save(str(path))
    biped = window.doc
    assert not window.open_path(str(path))
    assert len(boxes["critical"]) == 1 and "import that skeleton first" in boxes["critical"][0][1]
    assert window.doc is biped


def test_export_bvh_asks_the_up_axis_and_units_defaulting_to_what_blender_expects(qtbot, window, monkeypatch,
                                                                                   tmp_path):
    from PySide6 import QtCore, QtWidgets
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    from gsik_studio.widgets.export_options import ExportOptionsDialog

    monkeypatch.setattr(QtWidgets.QFileDialog, "getSaveFileName",
                        staticmethod(lambda *a, **k: (str(tmp_path / "out.bvh"), "")))
    seen = []

    def choose_z_up():
        dialog = QtWidgets.QApplication.activeModalWidget()
        if not isinstance(dialog, ExportOptionsDialog):
            return  # not shown yet: the poll comes back
        poll.stop()
        seen.append(dialog.options())
        dialog.up.setFocus()
        QTest.keyClick(dialog.up, Qt.Key_Down)  # y up -> z up, by the keyboard
        QTest.keyClick(dialog, Qt.Key_Return)  # OK

    poll = QtCore.QTimer(window)
    poll.timeout.connect(choose_z_up)
    poll.start(50)
    window.act_export_bvh.trigger()  # the dialog runs its own event loop until the poll answers it
    assert seen == [("y", "cm")]  # Blender's default import: y up, centimetres
    assert (tmp_path / "out.bvh").is_file() and "(z up, cm)" in window.statusBar().currentMessage()
    assert window.settings.value("export/up") == "z"  # remembered for the next export
