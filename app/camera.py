"""The 3D view's camera: preset views, framing a set of points, and the orbit style.

Front, side and top are orthographic, as in Blender's numpad views; the
perspective view is the default three-quarter view. Framing keeps the viewing
direction and fits the points with a margin, in perspective and orthographic
alike. Orbit is a turntable by default (z stays up, the horizon never rolls:
VTK's terrain style); a trackball is the option.
"""

from __future__ import annotations

import numpy as np

VIEWS = {
    # name: (direction from the focal point to the camera, view up, orthographic)
    "front": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), True),
    "back": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0), True),
    "side": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0), True),
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), True),
    "perspective": ((0.5, 0.8, 0.3), (0.0, 0.0, 1.0), False),
}
ORBITS = ("turntable", "trackball")
FRAME_MARGIN = 0.14  # fraction of the view left free around framed points


def set_view(plotter, name: str, points: np.ndarray) -> None:
    """Look from the preset ``name`` (see :data:`VIEWS`) at ``points`` (k, 3) [m] and frame them."""
    try:
        direction, up, ortho = VIEWS[name]
    except KeyError:
        raise ValueError(f"unknown view {name!r}; views: {', '.join(VIEWS)}") from None
    cam = plotter.camera
    center = (points.min(axis=0) + points.max(axis=0)) / 2
    cam.focal_point = center
    cam.position = center + np.asarray(direction) / np.linalg.norm(direction)
    cam.up = up
    cam.parallel_projection = ortho
    frame_points(plotter, points)


def box_corners(bounds) -> np.ndarray:
    """The 8 corners (8, 3) of an axis-aligned box given as VTK bounds ``(xmin, xmax, ymin, ymax, zmin, zmax)``."""
    x0, x1, y0, y1, z0, z1 = (float(b) for b in bounds)
    return np.array([(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)])


def body_extent(body) -> np.ndarray:
    """The corners (k, 3) [m] of the boxes of a drawn body's meshes (each with a ``polydata``); none while the
    body is hidden (sticks), none of an empty mesh."""
    boxes = [box_corners(m.polydata.bounds) for m in body.meshes if m.polydata.n_points] if body.visible else []
    return np.vstack(boxes) if boxes else np.zeros((0, 3))  # an empty mesh's VTK bounds are +-1e299


def _camera_axes(cam) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit (right, up, back) of the camera; ``back`` points from the focal point to the camera."""
    back = np.array(cam.position, dtype=float) - np.array(cam.focal_point, dtype=float)
    back /= np.linalg.norm(back)
    up = np.array(cam.up, dtype=float)
    up = up - (up @ back) * back
    if np.linalg.norm(up) < 1e-9:
        up = np.array([0.0, 1.0, 0.0]) if abs(back[2]) > 0.9 else np.array([0.0, 0.0, 1.0])
        up = up - (up @ back) * back
    up /= np.linalg.norm(up)
    return np.cross(up, back), up, back


def frame_points(plotter, points: np.ndarray, margin: float = FRAME_MARGIN, least: float = 0.02) -> None:
    """Fit ``points`` (k, 3) [m] in the view, keeping the viewing direction; ``least`` [m] is the
    smallest camera distance (and, halved, the smallest orthographic half-height)."""
    cam = plotter.camera
    right, up, back = _camera_axes(cam)
    center = (points.min(axis=0) + points.max(axis=0)) / 2
    rel = points - center
    x, y, z = np.abs(rel @ right), np.abs(rel @ up), rel @ back
    w, h = plotter.window_size
    aspect = max(w, 1) / max(h, 1)
    tan_v = np.tan(np.radians(cam.view_angle) / 2) * (1.0 - margin)
    distance = float(np.max(np.maximum(x / (tan_v * aspect), y / tan_v) + z))
    cam.focal_point = center
    cam.position = center + max(distance, least) * back
    half_height = float(max(np.max(y), np.max(x) / aspect)) / (1.0 - margin)
    cam.parallel_scale = max(half_height, least / 2)
    plotter.renderer.ResetCameraClippingRange()


def _level(cam) -> None:
    """View-up along world z, the horizon level, unless the camera looks (almost) straight up or down."""
    back = np.array(cam.position, dtype=float) - np.array(cam.focal_point, dtype=float)
    if abs(back[2]) < 0.999 * np.linalg.norm(back):
        cam.up = (0.0, 0.0, 1.0)


def set_orbit(plotter, orbit: str) -> None:
    """Left-drag orbit: ``"turntable"`` (z up, no roll; shift-drag pans, wheel zooms) or ``"trackball"``."""
    if orbit == "turntable":
        plotter.enable_terrain_style(mouse_wheel_zooms=True, shift_pans=True)
        # The terrain style turns about the camera's view-up: make it the world's z (unless looking straight
        # down, where z cannot be the view-up; the top view keeps y up until the first tilt).
        plotter.iren.interactor.GetInteractorStyle().AddObserver("StartInteractionEvent",
                                                                 lambda *_: _level(plotter.camera))
    elif orbit == "trackball":
        plotter.enable_trackball_style()
    else:
        raise ValueError(f"unknown orbit {orbit!r}; orbits: {', '.join(ORBITS)}")
