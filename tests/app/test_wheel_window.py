"""The mouse wheel over the side panel, as real X events (xdotool) in the real window under Xvfb.

The wheel scrolls the panel; it changes a field only when that field has the keyboard focus (clicked or tabbed
into), so scrolling past the joint's angle editors never turns a joint.
"""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from waiting import wait_for

pytestmark = pytest.mark.gui

WHEEL_UP, WHEEL_DOWN = "4", "5"  # X pointer buttons of the wheel


def _x(qtbot, *args: str) -> None:
    """Run one xdotool command line (real X pointer events), the Qt event loop running meanwhile."""
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool is not installed (Debian: apt-get install xdotool)")
    proc = subprocess.Popen(["xdotool", *args])
    wait_for(qtbot, lambda: proc.poll() is not None)
    assert proc.returncode == 0
    qtbot.wait(100)  # the X events that xdotool sent reach Qt


def _wheel_over(qtbot, widget, button: str, clicks: int = 3, click_first: bool = False) -> None:
    centre = widget.mapToGlobal(widget.rect().center())
    args = ["mousemove", str(centre.x()), str(centre.y()), "sleep", "0.2"]
    if click_first:
        args += ["click", "1", "sleep", "0.2"]
    _x(qtbot, *args, "click", "--repeat", str(clicks), "--delay", "80", button)


def test_the_wheel_scrolls_the_panel_and_turns_a_joint_only_from_its_focused_field(qtbot, window):
    doc, side = window.doc, window.pose_dock.widget()
    wait_for(qtbot, lambda: not doc.needs_solving)
    window.joints.select("right_shoulder")
    spin = window.joint_panel.angles[1]  # right shoulder (y)
    bar = side.verticalScrollBar()
    assert bar.maximum() > 0, "the side panel should be taller than the window here"
    side.ensureWidgetVisible(spin, 0, 150)
    qtbot.wait(50)
    direction = WHEEL_DOWN if bar.value() < bar.maximum() else WHEEL_UP
    q0, steps0, scroll0 = doc.q.copy(), len(doc.history.commands), bar.value()
    window.activateWindow()
    _wheel_over(qtbot, spin, direction)
    wait_for(qtbot, lambda: bar.value() != scroll0)  # the panel scrolled under the pointer
    np.testing.assert_array_equal(doc.q, q0)
    assert len(doc.history.commands) == steps0 and not spin.hasFocus()
    # Clicked into, the field has the focus: now the wheel turns the joint, one step per notch.
    side.ensureWidgetVisible(spin, 0, 150)
    qtbot.wait(50)
    angle0, scroll1 = spin.value(), bar.value()
    _wheel_over(qtbot, spin, WHEEL_UP, clicks=2, click_first=True)
    assert spin.hasFocus()
    wait_for(qtbot, lambda: doc.history.undo_text == "Turn right shoulder (y)")
    assert spin.value() != angle0 and bar.value() == scroll1
    dof = doc.skeleton.dof_names.index("right_shoulder.y")
    assert doc.q[dof] != q0[dof]


def test_every_wheel_driven_editor_of_the_panels_takes_focus_by_click_or_tab_only(window):
    from PySide6 import QtCore

    from gsik_studio.widgets.fields import WHEEL_EDITORS

    editors = [w for kind in WHEEL_EDITORS for w in window.pose_dock.widget().widget().findChildren(kind)]
    assert len(editors) > 10  # the angle, weight, solver and posture fields
    assert all(w.focusPolicy() == QtCore.Qt.StrongFocus for w in editors)
