"""Saving under fire and on the user's files: a save killed at any instant leaves the old file or the new one, the
next save cleans up after it; links are written through, read-only files refused."""

from __future__ import annotations

import os
import random
import stat
import time

import pytest

from fuzzing import kill_during_saves
from gsik.errors import GsikFileError
from gsik.io.files import atomic_write_text

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="kills a forked writer")

OLD = "old\n" * 100_000  # 400 kB: a save takes long enough to be killed in the middle
NEW = "new\n" * 120_000


def _kill_during_saves(path, rng: random.Random) -> int:
    return kill_during_saves(path, OLD, NEW, rng)


def _temporaries(folder, name: str) -> list[str]:
    return [f for f in os.listdir(folder) if f.startswith(f".{name}.") and f.endswith(".tmp")]


def test_a_save_killed_at_any_instant_leaves_a_whole_file(tmp_path):
    path = tmp_path / "pose.yaml"
    atomic_write_text(path, OLD)
    rng = random.Random(5)
    for _ in range(25):
        _kill_during_saves(path, rng)
        assert path.read_text(encoding="utf-8") in (OLD, NEW)


def test_the_next_save_removes_what_killed_saves_left(tmp_path):
    path = tmp_path / "pose.yaml"
    atomic_write_text(path, OLD)
    rng = random.Random(6)
    dead = [_kill_during_saves(path, rng) for _ in range(25)][-1]
    planted = {
        f".pose.yaml.{dead}.0123456789ab.tmp": None,  # a killed writer's: removed
        f".pose.yaml.{os.getppid()}.0123456789ab.tmp": "kept",  # a running process's save in progress: kept
        ".pose.yaml.0123456789ab.tmp": "kept",  # no process id, fresh: could still be in progress
        ".pose.yaml.ba9876543210.tmp": None,  # no process id, an hour old: removed
        ".other.yaml.123.tmp": "kept",  # another file's
    }
    for name in planted:
        (tmp_path / name).write_text("partial")
    an_hour_ago = time.time() - 3600
    os.utime(tmp_path / ".pose.yaml.ba9876543210.tmp", (an_hour_ago, an_hour_ago))
    atomic_write_text(path, "done\n")
    assert path.read_text(encoding="utf-8") == "done\n"
    kept = {n for n, fate in planted.items() if fate == "kept"}
    assert set(_temporaries(tmp_path, "pose.yaml")) | set(_temporaries(tmp_path, "other.yaml")) == kept


def test_a_symbolic_link_is_written_through(tmp_path):
    real = tmp_path / "real.yaml"
    real.write_text("old\n")
    link = tmp_path / "link.yaml"
    link.symlink_to(real)
    atomic_write_text(link, "new\n")
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert real.read_text() == "new\n"


def test_a_read_only_file_is_refused_and_left_alone(tmp_path):
    path = tmp_path / "locked.yaml"
    path.write_text("old\n")
    path.chmod(stat.S_IRUSR | stat.S_IRGRP)
    try:
        with pytest.raises(GsikFileError, match="is read-only") as info:
            atomic_write_text(path, "new\n")
        assert str(path) in str(info.value)
    finally:
        path.chmod(stat.S_IRUSR | stat.S_IWUSR)
    assert path.read_text() == "old\n"
    assert os.listdir(tmp_path) == ["locked.yaml"]
