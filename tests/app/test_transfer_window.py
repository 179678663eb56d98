"""File → Import BVH clip, Import skeleton and Export BVH in the real window (dialogs bypassed by the path entry points)."""

from __future__ import annotations

import os

import numpy as np
import pytest

import gsik
from gsik.io.bvh import read_bvh

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
    qtbot.waitUntil(lambda: not tl.playing, timeout=20000)
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
    assert read_bvh(path).n_frames == 13


def test_import_skeleton_from_urdf_opens_a_document_on_it(qtbot, window):
    other = window.files.import_skeleton_path(os.path.join(DATA, "humanoid.urdf"))
    try:
        qtbot.waitExposed(other)
        doc = other.doc
        assert doc.skeleton.name == "mini_humanoid" and doc.root == doc.skeleton.root
        assert set(doc.targets) == set(doc.skeleton.effector_sites) - {doc.root}
        assert not other.act_root_left.isEnabled() and window.act_root_left.isEnabled()  # no feet to pin
        name = sorted(doc.targets)[0]
        doc.move_target(name, np.array(doc.targets[name].position) + [0.0, 0.0, -0.05])
        qtbot.waitUntil(lambda: not other.timer.isActive(), timeout=20000)
        assert doc.last_result is not None
        assert window.doc.skeleton.name == "biped"  # this window's document is untouched
    finally:
        other.doc.history.set_clean()
        other.close()


def test_import_a_clip_of_another_skeleton_plays_in_its_own_document(qtbot, window):
    other = window.files.import_clip_path(os.path.join(DATA, "walk_zxy.bvh"))
    try:
        assert other is not None and other is not True and other is not False
        tl = other.doc.timeline
        assert other.doc.skeleton.name == "walk_zxy" and tl.clip is not None and tl.n_frames == 4
    finally:
        other.doc.history.set_clean()
        other.close()


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
