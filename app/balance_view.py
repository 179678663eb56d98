"""The centre of mass, its ground projection and the support polygon, drawn over the body.

Built once on the body's overlay renderer (so the solids never hide them) and
moved in place each frame: a ball at the centre of mass, a plumb line down to
a cross on the ground, and the support polygon as a closed line on the floor
(green while the projection is inside it, orange when it leaves).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from gsik_studio.scene import glyph_actor, line_cells, points_view, touch

COM_COLOR = (1.0, 0.95, 0.35)
INSIDE_COLOR = (0.35, 0.95, 0.45)
OUTSIDE_COLOR = (1.0, 0.55, 0.0)
COM_RADIUS = 0.03  # [m]
CROSS = 0.05  # half length of the ground cross's arms [m]
MAX_CORNERS = 24  # the support polygon's points (a hull of two soles has at most 8)
LIFT = 0.004  # drawn this far above the ground [m], over the floor


class BalanceView:
    """Draws a document's centre of mass and support polygon on an overlay renderer.

    Args:
        doc: The document (its ``controls`` give the read-outs).
        overlay: The renderer drawn over the scene.
    """

    def __init__(self, doc, overlay):
        self.doc = doc
        self.visible = doc.controls.has_masses
        self._com = pv.PolyData(np.zeros((1, 3)))
        self.com_actor = glyph_actor(self._com, COM_RADIUS, None, COM_COLOR)
        # Plumb line (2 points) and ground cross (4 points).
        self._marks = pv.PolyData(np.zeros((6, 3)), lines=line_cells([(0, 1), (2, 3), (4, 5)]))
        self.marks_actor = pv.Actor(mapper=pv.DataSetMapper(self._marks))
        self.marks_actor.prop.color = COM_COLOR
        self.marks_actor.prop.line_width = 2
        self.marks_actor.prop.lighting = False
        ring = np.r_[np.arange(MAX_CORNERS), 0]
        self._polygon = pv.PolyData(np.zeros((MAX_CORNERS, 3)), lines=np.r_[len(ring), ring])
        self.polygon_actor = pv.Actor(mapper=pv.DataSetMapper(self._polygon))
        self.polygon_actor.prop.line_width = 3
        self.polygon_actor.prop.lighting = False
        self.inside: bool | None = None
        self._xyz = [points_view(pd) for pd in (self._com, self._marks, self._polygon)]
        self.actors = (self.com_actor, self.marks_actor, self.polygon_actor)
        for a in self.actors:
            overlay.AddActor(a)
        self.set_visible(self.visible)

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible) and self.doc.controls.has_masses
        for a in self.actors:
            a.SetVisibility(self.visible)
        if self.visible:
            self.refresh()

    def refresh(self, P=None, R=None) -> None:
        """Move the marks to the centre of mass and support polygon now (arguments unused: a viewport layer)."""
        if not self.visible:
            return
        s = self.doc.controls.support()
        com_xyz, marks, polygon = self._xyz
        com_xyz[0] = s.com
        z = s.ground + LIFT
        g = np.array([s.com[0], s.com[1], z])
        marks[:] = [s.com, g, g - (CROSS, 0, 0), g + (CROSS, 0, 0), g - (0, CROSS, 0), g + (0, CROSS, 0)]
        k = min(len(s.polygon), MAX_CORNERS)
        polygon[:k, :2] = s.polygon[:k]
        polygon[k:, :2] = s.polygon[0] if k else g[:2]  # unused corners sit on the first one
        polygon[:, 2] = z
        for pd in (self._com, self._marks, self._polygon):
            touch(pd)
        if s.inside != self.inside:
            self.inside = s.inside
            self.polygon_actor.prop.color = INSIDE_COLOR if s.inside else OUTSIDE_COLOR
