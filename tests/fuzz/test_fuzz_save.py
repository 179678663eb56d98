"""Saving under fire: a save killed at any instant leaves the old file or the new one, never a torn one."""

from __future__ import annotations

import os
import random
import signal
import time

import pytest

from gsik.io.files import atomic_write_text

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="kills a forked writer")

OLD = "old\n" * 100_000  # 400 kB: a save takes long enough to be killed in the middle
NEW = "new\n" * 120_000


def _kill_during_saves(path, rng: random.Random) -> None:
    """Fork a process that saves OLD and NEW in turn, and SIGKILL it after a random few milliseconds."""
    pid = os.fork()
    if pid == 0:  # the writer: never returns into pytest
        try:
            while True:
                atomic_write_text(path, NEW)
                atomic_write_text(path, OLD)
        finally:
            os._exit(0)
    time.sleep(rng.uniform(0.001, 0.03))
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)


def _temporaries(folder, name: str) -> list[str]:
    return [f for f in os.listdir(folder) if f.startswith(f".{name}.") and f.endswith(".tmp")]


def test_a_save_killed_at_any_instant_leaves_a_whole_file(tmp_path):
    path = tmp_path / "pose.yaml"
    atomic_write_text(path, OLD)
    rng = random.Random(5)
    for _ in range(25):
        _kill_during_saves(path, rng)
        assert path.read_text(encoding="utf-8") in (OLD, NEW)
