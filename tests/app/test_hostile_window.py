"""Hostile files through the real File menu: one dialog each, and the document is left exactly as it was."""

from __future__ import annotations

import os

import pytest

pytestmark = pytest.mark.gui

DATA = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")


def _walk_with(motion: str) -> str:
    """tests/data/walk_zxy.bvh (12 joints, 39 channels) with its MOTION section replaced by ``motion``."""
    with open(os.path.join(DATA, "walk_zxy.bvh"), encoding="utf-8") as f:
        return f.read().split("MOTION")[0] + "MOTION\n" + motion


_STILL = """name: still
joints:
  - {name: base, offset: [0, 0, 0], rotations: []}
sites:
  - {name: tip, parent: base, offset: [0, 0, 1]}
effectors: [tip]
"""

_FAR = """name: far
joints:
  - {name: base, offset: [0, 0, 0], rotations: [{axis: z, limits: [-1, 1]}]}
sites:
  - {name: tip, parent: base, offset: [1.0e+300, 0, 0]}
effectors: [tip]
"""


def _long_keys(pose) -> str:
    """A biped pose file keyed at frames 0 and 99,999 (31 KB; 100,000 frames to solve on Play)."""
    from gsik.io.pose import KeySequence, pose_to_yaml

    text = pose_to_yaml(pose, keys=KeySequence(((0, pose), (1, pose)), 30.0, 2))
    assert "    - frame: 1\n" in text and "  length: 2\n" in text
    return text.replace("    - frame: 1\n", "    - frame: 99999\n").replace("  length: 2\n", "  length: 100000\n")


def _hostile_files(tmp_path, pose) -> dict[str, tuple[str, str, str]]:
    """name -> (the File menu action, its path, what the refusal says)."""
    files = {
        "frames0.bvh": ("import_clip", _walk_with("Frames: 0\nFrame Time: 0.0333\n"), "no frames"),
        "frame_time.bvh": ("import_clip", _walk_with("Frames: 1\nFrame Time: 5e-324\n" + "0 " * 39 + "\n"),
                           "Frame Time 5e-324: must be from 0.0001 to 1000 seconds"),
        "still.yaml": ("import_skeleton", _STILL, "no degrees of freedom"),
        "far.yaml": ("import_skeleton", _FAR, "a skeleton may reach at most 100000 m"),
        "long_keys.yaml": ("open", _long_keys(pose), "keys.poses.1.frame: must be a whole number from 0 to 9999"),
    }
    out = {}
    for name, (action, text, reason) in files.items():
        (tmp_path / name).write_text(text)
        out[name] = (action, str(tmp_path / name), reason)
    fifo = tmp_path / "fifo.bvh"
    os.mkfifo(fifo)
    out["fifo.bvh"] = ("import_clip", str(fifo), "not a regular file (a FIFO)")
    out["/dev/zero"] = ("open", "/dev/zero", "not a regular file (a character device)")
    return out


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs (POSIX)")
def test_each_hostile_file_gets_one_dialog_and_leaves_the_document_unchanged(window, boxes, monkeypatch, tmp_path):
    from PySide6.QtWidgets import QFileDialog

    for name, (action, path, reason) in _hostile_files(tmp_path, window.doc.pose()).items():
        monkeypatch.setattr(QFileDialog, "getOpenFileName", staticmethod(lambda *a, p=path, **k: (p, "")))
        doc = window.doc
        before, history, shown = doc.pose(), list(doc.history.commands), boxes["critical"][:]
        getattr(window, f"act_{action}").trigger()
        assert len(boxes["critical"]) == len(shown) + 1, name
        text = boxes["critical"][-1][1]
        assert reason in text and os.path.basename(path) in text + window.statusBar().currentMessage(), (name, text)
        assert window.doc is doc and doc.pose() == before and doc.history.commands == history, name
        assert doc.timeline.clip is None and not window.others, name
