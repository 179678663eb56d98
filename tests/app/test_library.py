"""The pose library model without any display: add, rename, duplicate, delete, apply, each undoable; saved with the pose."""

from __future__ import annotations

import numpy as np
import pytest

import gsik
from gsik_studio.model import Document


@pytest.fixture()
def doc():
    return Document()


def test_add_rename_duplicate_delete_are_each_one_undo_step(doc):
    lib = doc.library
    assert lib.add() == "pose 1"
    doc.random_pose(seed=3)
    assert lib.add("reach") == "reach"
    lib.rename("pose 1", "stand")
    assert lib.duplicate("stand") == "stand copy"
    assert lib.names == ("stand", "stand copy", "reach")
    lib.delete("reach")
    assert lib.names == ("stand", "stand copy")
    texts = [c.text for c in doc.history.commands]
    assert texts == ["Add pose pose 1", "Random pose", "Add pose reach", "Rename pose pose 1 to stand",
                     "Duplicate pose stand", "Delete pose reach"]
    doc.undo()
    assert lib.names == ("stand", "stand copy", "reach")
    doc.undo()
    doc.undo()
    assert lib.names == ("pose 1", "reach")
    doc.redo()
    assert lib.names == ("stand", "reach")


def test_apply_shows_the_pose_and_undo_takes_it_back(doc):
    lib = doc.library
    doc.random_pose(seed=5)
    lib.add("random")
    wanted = doc.pose()
    doc.reset()
    before = doc.pose()
    lib.apply("random")
    assert doc.pose() == wanted and doc.history.undo_text == "Apply pose random"
    doc.undo()
    assert doc.pose() == before


def test_bad_names_are_refused_naming_the_choices(doc):
    doc.library.add("a")
    with pytest.raises(gsik.PoseError, match="already has a pose named 'a'"):
        doc.library.add("a")
    with pytest.raises(gsik.PoseError, match="no pose named 'b'.*poses: 'a'"):
        doc.library.delete("b")
    with pytest.raises(gsik.PoseError, match="must not be empty"):
        doc.library.rename("a", "  ")


def test_the_library_is_saved_and_opened_with_the_pose(doc, tmp_path):
    doc.library.add("one")
    doc.random_pose(seed=1)
    doc.library.add("two")
    path = tmp_path / "lib.yaml"
    doc.save(str(path))
    other = Document()
    other.open(str(path))
    assert other.library.snapshot() == doc.library.snapshot() and other.pose() == doc.pose()
    assert not other.history.can_undo
    np.testing.assert_array_equal(other.q, doc.q)
    other.new()
    assert other.library.names == ()
