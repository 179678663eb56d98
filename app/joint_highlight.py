"""The joint selected for direct rotation, highlighted in the 3D view: a larger, bright ball on it, over the body.

Drawn on the body's overlay renderer (so the mannequin never hides it) and
moved in place each frame as a layer of the :class:`gsik_studio.viewport.Viewport`;
it follows :attr:`gsik_studio.model.joints.JointEditor.selection_changed`.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from gsik_studio.model.joints import JointEditor
from gsik_studio.scene import glyph_actor, points_view, touch

HIGHLIGHT_COLOR = (0.30, 0.95, 1.00)  # cyan: no target, effector, axis or limit uses it
HIGHLIGHT_RADIUS = 0.032  # [m], larger than a joint's ball (viewport.JOINT_RADIUS)


class JointHighlight:
    """A ball on the selected joint (hidden while none is selected).

    Args:
        viewport: The viewport (its document; this joins its layers).
        editor: The joint editor whose selection is shown.
        overlay: The renderer drawn over the body.
    """

    def __init__(self, viewport, editor: JointEditor, overlay):
        self.doc = viewport.doc
        self.editor = editor
        self._point = pv.PolyData(np.zeros((1, 3)))
        self._xyz = points_view(self._point)
        self.actor = glyph_actor(self._point, HIGHLIGHT_RADIUS, None, HIGHLIGHT_COLOR)
        self.actor.GetProperty().SetLighting(False)  # flat and bright, whatever the light
        self.actor.VisibilityOff()
        overlay.AddActor(self.actor)
        viewport.layers.append(self)
        editor.selection_changed.connect(lambda _name: self.refresh(self.doc.world_positions()))

    @property
    def position(self) -> np.ndarray | None:
        """Where the ball is drawn (3,) [m]; None while hidden."""
        return self._xyz[0].copy() if self.actor.GetVisibility() else None

    def refresh(self, P: np.ndarray, R: np.ndarray | None = None) -> None:
        """Put the ball on the selected joint at world positions P (n_frames, 3) [m], or hide it."""
        name = self.editor.selected
        if name is None:
            self.actor.VisibilityOff()
            return
        sk = self.doc.skeleton
        self._xyz[0] = P[sk.joint_frame[sk.joint_names.index(name)]]
        touch(self._point)
        self.actor.VisibilityOn()
