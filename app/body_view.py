"""How the body is drawn: the skinned body (the mannequin or a character) or the stick figure, joint rings on top.

The rings (and the achieved effectors, triads and error lines) move to an
overlay renderer (layer 1, same camera, its own depth buffer), so the solids
never hide them: an artist can grab any joint's ring through the body. The
target spheres inside the body (head, pelvis) are drawn there too, as wire
markers over the sphere widgets (the widgets pick only their own sphere, so a
hidden one is still grabbed). Drawn as a layer of the
:class:`gsik_studio.viewport.Viewport`.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkRenderer

from gsik_studio.scene import glyph_actor, points_view, rgb8, set_colors, touch
from gsik_studio.skinned_body import body_of
from gsik_studio.viewport import TARGET_COLOR, TARGET_RADIUS, TARGET_SELECTED_COLOR

#: The ways the body can be drawn.
BODY_MODES = ("mannequin", "sticks")
#: The viewport's actors drawn over the body: the axis rings, the achieved effectors, their triads, error lines.
OVERLAID = ("gizmos", "effectors", "triads", "errors")
_MARKER_RGB8 = rgb8(TARGET_COLOR)  # computed once: the markers are recoloured every frame
_SELECTED_MARKER_RGB8 = rgb8(TARGET_SELECTED_COLOR)


def overlay_renderer(plotter) -> vtkRenderer:
    """A renderer drawn over ``plotter``'s own (layer 1, same camera, depth cleared): what it shows is never hidden."""
    ren = vtkRenderer()
    ren.SetLayer(1)
    ren.SetActiveCamera(plotter.renderer.GetActiveCamera())
    ren.InteractiveOff()
    ren.SetViewport(plotter.renderer.GetViewport())
    rw = plotter.render_window
    rw.SetNumberOfLayers(max(2, rw.GetNumberOfLayers()))
    rw.AddRenderer(ren)
    return ren


class BodyView:
    """The body of a viewport's document, drawn as a mannequin (default) or as sticks.

    Args:
        viewport: The viewport; its bone and joint actors are the stick figure,
            its ``gizmos`` actor (the axis rings) moves to the overlay.
        mode: One of :data:`BODY_MODES`.
    """

    def __init__(self, viewport, mode: str = "mannequin"):
        self.viewport = viewport
        pl = viewport.plotter
        self.mannequin = body_of(pl, viewport.doc.skeleton)
        self.overlay = overlay_renderer(pl)
        for name in OVERLAID:
            pl.renderer.RemoveActor(viewport.actors[name])
            self.overlay.AddActor(viewport.actors[name])
        self._sites = viewport.doc.skeleton.effector_sites
        self._markers = pv.PolyData(np.zeros((len(self._sites), 3)))
        self._marker_xyz = points_view(self._markers)
        self._marker_colors = np.zeros((len(self._sites), 3), dtype=np.uint8)
        # A wire cage the size of the widget's sphere, so the achieved effector shows through it: a
        # translucent overlay costs about a third more per render under software GL.
        self.markers = glyph_actor(self._markers, TARGET_RADIUS, self._marker_colors.copy())
        self.markers.GetProperty().SetRepresentationToWireframe()
        self.markers.GetProperty().SetLighting(False)
        self.markers.GetProperty().SetLineWidth(1.5)
        self.overlay.AddActor(self.markers)
        self.mode = ""
        viewport.layers.append(self)
        self.set_mode(mode)

    def set_mode(self, mode: str) -> None:
        """Draw the body as ``"mannequin"`` or ``"sticks"`` (no render)."""
        if mode not in BODY_MODES:
            raise ValueError(f"body mode must be one of {', '.join(BODY_MODES)}, got {mode!r}")
        if mode == self.mode:
            return
        self.mode = mode
        solid = mode == "mannequin"
        self.mannequin.set_visible(solid)
        self.markers.SetVisibility(solid)
        for name in ("bones", "joints"):
            self.viewport.actors[name].SetVisibility(not solid)
        if solid:
            d = self.viewport.doc
            self.mannequin.update(d.world_positions(), d.world_rotations())

    def refresh(self, P: np.ndarray, R: np.ndarray) -> None:
        """Move the mannequin (when shown) to world positions P (n_frames, 3) [m], rotations R (n_frames, 3, 3)."""
        if self.mode == "mannequin":
            self.mannequin.update(P, R)
            self._show_targets()

    def _show_targets(self) -> None:
        """Markers on the shown targets (a hidden one sinks far below the floor), the selected one lighter.

        A target is shown while its sphere widget is on (an enabled target, targets not hidden for a picture).
        """
        vp = self.viewport
        targets = vp.doc.targets
        colors = np.empty_like(self._marker_colors)
        for i, name in enumerate(self._sites):
            t = targets.get(name)
            on = t is not None and bool(vp.target_widgets[i].GetEnabled())
            self._marker_xyz[i] = t.position if on else (0.0, 0.0, -1e3)
            colors[i] = _SELECTED_MARKER_RGB8 if name == vp.selected else _MARKER_RGB8
        touch(self._markers)
        if not np.array_equal(colors, self._marker_colors):
            self._marker_colors = colors
            set_colors(self._markers, colors)
