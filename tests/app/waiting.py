"""Waiting for a state in GUI tests, never for a wall-clock budget.

A GUI test waits until the studio reaches the state it checks (settled, idle, played to the end): however slow the
machine, the state comes. The only clock is a hang guard, far beyond any machine's speed, that turns a test which
would wait forever (a real bug) into a failure: ``GSIK_TEST_HANG_GUARD_S`` seconds, 600 by default.
"""

from __future__ import annotations

import os

HANG_GUARD_MS = int(float(os.environ.get("GSIK_TEST_HANG_GUARD_S", "600")) * 1000)


def wait_for(qtbot, condition) -> None:
    """Run Qt's event loop (the studio's real timers) until ``condition()`` holds."""
    qtbot.waitUntil(condition, timeout=HANG_GUARD_MS)
