"""The studio's document under hostile edits and files: every failure a GsikError that changes nothing, and the
document never left where undo, save or reset fail (plain Python: no display)."""

from __future__ import annotations

import os
import random
import stat

import numpy as np
import pytest

import gsik
from fuzzing import HOSTILE
from gsik_studio.model import Document

HOSTILE_VALUES = [[1e300, -1e300, 1e300], [float("nan")] * 3, [1e6 + 1, 0, 0], [10**400, 0, 0], "left", None,
                  [0.1, 0.2], [[1, 2, 3]], [0.3, 0.2, 1.0]]
WEIGHTS = [1e9, -1.0, float("nan"), float("inf"), 10**400, "heavy", 2.0]
ORIENTATIONS = [(2.0, 0.0, 0.0, 0.0), np.full((3, 3), 1e300), (float("nan"),) * 4, (1.0, 0.0, 0.0, 0.0), "up"]
SETTINGS = [dict(sweeps=2**62), dict(max_iterations=10**20), dict(damping=float("nan")), dict(damping=np.float32(0.01)),
            dict(orientation_weight=1e300), dict(sweeps=12)]


def _edit(doc: Document, rng: random.Random) -> None:
    name = rng.choice(doc.effector_names)
    action = rng.randrange(5)
    if action == 0:
        doc.move_target(name, rng.choice(HOSTILE_VALUES))
    elif action == 1:
        doc.set_target_options(name, weight=rng.choice(WEIGHTS))
    elif action == 2:
        doc.orient_target(name, rng.choice(ORIENTATIONS))
    elif action == 3:
        doc.configure(**rng.choice(SETTINGS))
    else:
        doc.set_root(rng.choice(["nope", "left_foot", "right_foot", "pelvis", ""]))


def test_hostile_edits_fail_cleanly_and_leave_the_document_working(tmp_path):
    doc = Document()
    rng = random.Random(3)
    refused = 0
    for _ in range(300):
        before = doc.pose
        try:
            _edit(doc, rng)
        except gsik.GsikError:
            refused += 1
            assert doc.pose == before  # a refused edit changes nothing
        result = doc.step()
        assert np.isfinite(result.q).all() and np.isfinite(doc.q).all()
        assert result.status is not gsik.Status.CONVERGED or np.isfinite(result.position_errors).all()
    assert refused > 50
    while doc.undo():  # every edit undoes
        assert np.isfinite(doc.q).all()
    doc.save(tmp_path / "after.yaml")
    doc.reset()
    assert np.isfinite(doc.q).all()
    doc.open(tmp_path / "after.yaml")


@pytest.mark.parametrize("name", sorted(p.name for p in HOSTILE.glob("*.yaml")))
def test_opening_a_hostile_file_changes_nothing(name):
    doc = Document()
    doc.move_target("left_hand", [0.3, 0.2, 1.0])
    pose, path = doc.pose, doc.path
    with pytest.raises(gsik.GsikError):
        doc.open(str(HOSTILE / name))
    assert doc.pose == pose and doc.path == path
    assert doc.undo()


def test_a_failed_save_keeps_the_document_and_its_dirty_flag(tmp_path):
    doc = Document()
    doc.move_target("left_hand", [0.3, 0.2, 1.0])
    locked = tmp_path / "locked.yaml"
    locked.write_text("old\n")
    locked.chmod(stat.S_IRUSR)
    try:
        for bad in (locked, tmp_path / "bad\x00name.yaml", tmp_path / "missing" / "x.yaml"):
            with pytest.raises(gsik.GsikFileError):
                doc.save(bad)
            assert doc.dirty and doc.path is None
    finally:
        locked.chmod(stat.S_IRUSR | stat.S_IWUSR)
    assert locked.read_text() == "old\n"
    doc.save(tmp_path / "good.yaml")
    assert not doc.dirty and os.path.exists(tmp_path / "good.yaml")
