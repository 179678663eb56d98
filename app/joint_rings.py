"""Mouse input on the joint rings: click a joint to select it, drag one of its rings to turn it.

A Qt event filter on the 3D view sees a press before VTK does. A press on a
ring (within :data:`PICK_PX` of one of its drawn points) selects that joint
and starts turning that one-DOF rotation; a press on a joint's centre selects
it. Either press is kept from VTK (no orbit starts). A press near a target
or pole sphere goes on to VTK, whose sphere widget takes it. While turning, the
mouse ray meets the ring's plane and the angle swept about the axis is the
turn, so the grabbed point of the ring follows the pointer; a ring seen edge
on turns by the pointer's travel along the ring's screen tangent instead.
Everything goes through :class:`gsik_studio.model.joints.JointEditor`.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np
import pyvista as pv
from PySide6 import QtCore

from gsik_studio.model.joints import JointEditor
from gsik_studio.viewport import RING_POINTS, ring_and_stick

PICK_PX = 7.0  # how near a ring's drawn point a press must be [px]
JOINT_PICK_PX = 10.0  # how near a joint's centre [px]
TARGET_GUARD_PX = 16.0  # presses this near a target sphere belong to its widget [px]
EDGE_ON = 0.2  # |cos| between the view ray and the axis below which the ring is seen edge on


class _Turn(NamedTuple):
    """One ring drag.

    Attributes:
        dof: The DOF turned.
        axis, centre: Its world axis (3,) and the ring's centre (3,) [m] at the press.
        angle0: Its angle at the press [rad].
        grab: (3,) from the centre to the grabbed point, in the ring's plane (None: edge on).
        press_px: Display point of the press (2,).
        px_per_rad: (2,) how the grabbed point moves on screen per radian of turn.
        token: The drag's undo-merge token.
    """

    dof: int
    axis: np.ndarray
    centre: np.ndarray
    angle0: float
    grab: np.ndarray | None
    press_px: np.ndarray
    px_per_rad: np.ndarray
    token: int


class JointRings(QtCore.QObject):
    """Turns joints by their rings in a viewport.

    Args:
        viewport: The :class:`gsik_studio.viewport.Viewport` (its plotter and document).
        editor: The joint editor the turns go through.
    """

    def __init__(self, viewport, editor: JointEditor):
        super().__init__()
        self.viewport = viewport
        self.editor = editor
        self.turn: _Turn | None = None
        self._tokens = itertools.count(1)
        sk = viewport.doc.skeleton
        self._dof_frame = np.asarray(sk.dof_frame)
        self._axes_local = np.asarray(sk.frame_axis)[self._dof_frame]  # (n_dofs, 3)
        self._rings_local = np.stack([ring_and_stick(a)[:RING_POINTS] for a in self._axes_local])
        self._joint_of_dof = [""] * sk.n_dofs
        for name, dofs in zip(sk.joint_names, sk.joint_dofs):
            for d in dofs:
                self._joint_of_dof[d] = name
        viewport.plotter.installEventFilter(self)

    # -- geometry ---------------------------------------------------------------
    def _display(self, event) -> np.ndarray:
        """VTK display coordinates (pixels, origin bottom-left) of a Qt mouse event."""
        w = self.viewport.plotter
        r = w.devicePixelRatioF()
        p = event.position()
        return np.array([p.x() * r, (w.height() - p.y() - 1) * r])

    def project(self, points: np.ndarray) -> np.ndarray:
        """Display coordinates (m, 2) of world points (m, 3)."""
        ren = self.viewport.plotter.renderer
        w, h = ren.GetSize()
        aspect = w / max(h, 1)
        M = pv.array_from_vtkmatrix(ren.GetActiveCamera().GetCompositeProjectionTransformMatrix(aspect, -1, 1))
        X = np.c_[points, np.ones(len(points))] @ M.T
        ndc = X[:, :2] / X[:, 3:4]
        x0, y0 = ren.GetOrigin()
        return np.c_[x0 + (ndc[:, 0] + 1) * w / 2, y0 + (ndc[:, 1] + 1) * h / 2]

    def _ray(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World point and unit direction of the view ray through display point ``xy``."""
        ren = self.viewport.plotter.renderer
        ends = []
        for z in (0.0, 1.0):
            ren.SetDisplayPoint(xy[0], xy[1], z)
            ren.DisplayToWorld()
            w = np.array(ren.GetWorldPoint())
            ends.append(w[:3] / w[3])
        d = ends[1] - ends[0]
        return ends[0], d / np.linalg.norm(d)

    def ring_world(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every DOF's world axis (n_dofs, 3), ring centre (n_dofs, 3) [m] and ring points (n_dofs, K, 3) [m]."""
        doc = self.viewport.doc
        P, R = doc.world_positions(), doc.world_rotations()
        Rd, c = R[self._dof_frame], P[self._dof_frame]
        return (np.einsum("dij,dj->di", Rd, self._axes_local), c,
                np.einsum("dij,dkj->dki", Rd, self._rings_local) + c[:, None, :])

    def pick(self, xy: np.ndarray) -> tuple[str, int | str] | None:
        """What a press at display point ``xy`` grabs: ``("ring", dof)``, ``("joint", name)`` or None."""
        doc = self.viewport.doc
        targets = [t.position for t in doc.targets.values() if t.enabled]
        targets += [t.position for t in doc.controls.poles.values()]  # a press on a pole is the pole's
        if targets and np.min(np.linalg.norm(self.project(np.array(targets)) - xy, axis=1)) <= TARGET_GUARD_PX:
            return None
        _, _, rings = self.ring_world()
        d = np.linalg.norm(self.project(rings.reshape(-1, 3)).reshape(rings.shape[:2] + (2,)) - xy, axis=-1)
        dof, k = np.unravel_index(np.argmin(d), d.shape)
        if d[dof, k] <= PICK_PX:
            return "ring", int(dof)
        sk = doc.skeleton
        turnable = self.editor.joint_names
        frames = [sk.joint_frame[sk.joint_names.index(n)] for n in turnable]
        dj = np.linalg.norm(self.project(doc.world_positions()[frames]) - xy, axis=-1)
        j = int(np.argmin(dj))
        return ("joint", turnable[j]) if dj[j] <= JOINT_PICK_PX else None

    # -- the drag ------------------------------------------------------------------
    def _start(self, dof: int, xy: np.ndarray) -> None:
        axes, centres, _ = self.ring_world()
        axis, centre = axes[dof], centres[dof]
        origin, ray = self._ray(xy)
        grabbed = on_plane(origin, ray, centre, axis)
        grab = grabbed - centre if abs(ray @ axis) > EDGE_ON else None
        # How the grabbed point moves on screen per radian: the fallback when the ring is seen edge on.
        g = grabbed - centre
        eps = 0.05
        moved = centre + np.cos(eps) * g + np.sin(eps) * np.cross(axis, g)
        px = self.project(np.array([grabbed, moved]))
        px_per_rad = (px[1] - px[0]) / eps
        if np.linalg.norm(px_per_rad) < 1.0:
            px_per_rad = np.array([20.0, 0.0])
        self.turn = _Turn(dof, axis, centre, self.editor.angle(dof), grab, xy, px_per_rad, next(self._tokens))

    def swept_angle(self, xy: np.ndarray) -> float:
        """The turn [rad] from the press to display point ``xy``."""
        t = self.turn
        if t.grab is not None:
            origin, ray = self._ray(xy)
            if abs(ray @ t.axis) > 1e-6:
                hit = origin + ray * ((t.centre - origin) @ t.axis) / (ray @ t.axis)
                v = hit - t.centre
                v = v - (v @ t.axis) * t.axis
                return float(np.arctan2(t.axis @ np.cross(t.grab, v), t.grab @ v))
        return float((xy - t.press_px) @ t.px_per_rad) / float(t.px_per_rad @ t.px_per_rad)

    def _move(self, xy: np.ndarray) -> None:
        t = self.turn
        self.editor.set_angle(t.dof, t.angle0 + self.swept_angle(xy), drag=t.token)

    def _end(self) -> None:
        self.turn = None
        self.editor.doc.end_drag()

    # -- Qt ------------------------------------------------------------------------------
    def eventFilter(self, obj, event):  # noqa: N802 (Qt's name)
        kind = event.type()
        if kind == QtCore.QEvent.MouseButtonPress and event.button() == QtCore.Qt.LeftButton:
            xy = self._display(event)
            hit = self.pick(xy)
            if hit is None:
                return False
            what, index = hit
            if what == "ring":
                self.editor.select(self._joint_of_dof[index])
                self._start(index, xy)
            else:
                self.editor.select(index)
            return True
        if self.turn is not None and kind == QtCore.QEvent.MouseMove:
            self._move(self._display(event))
            return True
        if self.turn is not None and kind == QtCore.QEvent.MouseButtonRelease:
            self._end()
            return True
        return False


def on_plane(origin: np.ndarray, ray: np.ndarray, centre: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Where the view ray meets the ring's plane; edge on, the ray's point nearest the centre put onto the plane."""
    if abs(ray @ axis) > EDGE_ON:
        return origin + ray * ((centre - origin) @ axis) / (ray @ axis)
    p = origin + ray * ((centre - origin) @ ray)
    return p - ((p - centre) @ axis) * axis
