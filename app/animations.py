"""Animations the studio plays: a solved walk and the built-in test scenarios of :mod:`gsik.anim.scenarios`."""

from __future__ import annotations

from collections.abc import Callable

from PySide6 import QtGui, QtWidgets

import gsik
from gsik.anim import scenarios
from gsik.io.pose import Pose
from gsik_studio.widgets import nice


def fill_scenario_menu(menu: QtWidgets.QMenu, skeleton: gsik.Skeleton, play: Callable[[str], None]) -> None:
    """Make ``menu`` hold one entry per built-in scenario (disabled, saying why, where one does not fit ``skeleton``)."""
    menu.clear()
    menu.setToolTipsVisible(True)
    for name in scenarios.SCENARIO_NAMES:
        a = menu.addAction(nice(name))
        try:
            a.setToolTip(scenarios.builtin_scenario(skeleton, name).description)
        except gsik.GsikError as exc:  # a skeleton the built-in scenarios do not fit
            a.setEnabled(False)
            a.setToolTip(str(exc))
        a.triggered.connect(lambda _c=False, n=name: play(n))


def scenarios_action(menu: QtWidgets.QMenu) -> QtGui.QAction:
    """The toolbar's action of the "Scenarios" menu, with its icon and tooltip."""
    a = menu.menuAction()
    a.setIcon(menu.style().standardIcon(QtWidgets.QStyle.SP_FileDialogDetailedView))
    a.setToolTip("Load a test scenario (targets from the paper's poses) and watch it solve")
    return a


def scenario_start(skeleton: gsik.Skeleton, name: str) -> tuple[scenarios.Scenario, Pose]:
    """The scenario and the pose it starts from: the rest pose with the scenario's (first frame's) targets.

    Raises:
        GsikError: the scenario does not fit ``skeleton``.
    """
    sc = scenarios.builtin_scenario(skeleton, name)
    first = scenarios.scenario_pose(sc)
    if sc.n_frames > 1:  # an animated scenario starts at its first frame's targets
        t0 = sc.targets_at(0)
        first = first.replace(targets={n: t0.get(n, t) for n, t in first.targets.items()})
    return sc, first


def scenario_frames(sc: scenarios.Scenario) -> list:
    """The target frames an animated scenario plays after its first."""
    return [sc.targets_at(i) for i in range(1, sc.n_frames)]

