"""The 3D viewport: draws a :class:`gsik_studio.model.Document` with PyVista/VTK.

The scene is built once; every frame only overwrites point coordinates (and,
when they change, point colours) of a handful of PolyData objects:

- bones: one PolyData whose points are every skeleton frame, lines between them;
- joints: one glyph mapper drawing a sphere per joint, coloured per point
  (grey, orange when a DOF of the joint sits on a limit);
- DOF gizmos: per one-DOF rotation a small ring around its axis and a short
  stick along it, x red / y green / z blue, so the three rings of a ball
  joint stand apart like a gimbal;
- effectors: green glyph spheres with RGB axis triads at the achieved poses;
- targets: red sphere widgets (one per effector, drag to move), RGB triads
  showing the target orientations, and for the selected target a box widget
  to turn it (drag a face of the box) and a name label;
- thin lines from each target to its achieved effector; a ring on the floor
  marks the IK root; a floor grid.

Nothing here changes the document except through its commands.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonTransforms import vtkTransform
from vtkmodules.vtkInteractionWidgets import vtkBoxWidget
from vtkmodules.vtkRenderingCore import vtkBillboardTextActor3D, vtkTextActor

from gsik.rotations import quaternion_from_matrix, transform
from gsik_studio import camera
from gsik_studio.model import Document, Signal
from gsik_studio.scene import glyph_actor, line_cells, points_view, rgb8, set_colors, sphere_widget, touch

# Colours (RGB 0-1). Red / green / blue are reserved for targets, effectors and axes.
AXIS_COLORS = np.array([[0.93, 0.18, 0.16], [0.20, 0.80, 0.22], [0.20, 0.45, 1.00]])
TARGET_COLOR = (0.90, 0.08, 0.08)
TARGET_SELECTED_COLOR = (1.00, 0.40, 0.35)
EFFECTOR_COLOR = (0.15, 0.85, 0.25)
JOINT_COLOR = (0.80, 0.80, 0.84)
LIMIT_COLOR = (1.00, 0.55, 0.00)
BONE_COLOR = (0.86, 0.83, 0.76)
ROOT_COLOR = (1.00, 0.84, 0.15)
ERROR_LINE_COLOR = (1.00, 0.82, 0.45)
GRID_COLOR = (0.42, 0.45, 0.50)
FLOOR_COLOR = (44 / 255, 45 / 255, 51 / 255)
BACKGROUND_TOP = (0.24, 0.26, 0.31)
BACKGROUND_BOTTOM = (0.10, 0.11, 0.13)

RING_RADIUS = 0.045  # [m]
RING_POINTS = 24
STICK_LENGTH = 0.075  # [m]
TRIAD_EFFECTOR = 0.07  # [m]
TRIAD_TARGET = 0.11  # [m]
TARGET_RADIUS = 0.034  # [m]
TARGET_OPACITY = 0.6  # the achieved effector shows through its target
JOINT_RADIUS = 0.022  # [m]
EFFECTOR_RADIUS = 0.026  # [m]
BOX_SIZE = 0.16  # [m]
PICK_TOLERANCE_PX = 8  # a press this many pixels off a target's sphere still grabs it

def ring_and_stick(axis: np.ndarray) -> np.ndarray:
    """(RING_POINTS + 2, 3) points of a ring around ``axis`` and a stick along it, in the DOF's frame."""
    a = axis / np.linalg.norm(axis)
    u = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(a, u)
    t = np.linspace(0.0, 2 * np.pi, RING_POINTS, endpoint=False)
    ring = RING_RADIUS * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
    return np.vstack([ring, np.zeros(3), STICK_LENGTH * a])


class Viewport:
    """Draws a document in a pyvista plotter (a ``pyvistaqt.QtInteractor`` in the app).

    Args:
        plotter: The plotter to draw into; the scene is added once.
        doc: The document.

    Attributes:
        selection_changed: Signal(name or None) when a target is selected.
        drag_finished: Signal(name) when a target gizmo drag ends.
        layers: More drawings (the body, balance): each one's ``refresh(P, R)`` runs in :meth:`refresh`.
    """

    def __init__(self, plotter: pv.Plotter, doc: Document):
        self.plotter = plotter
        self.doc = doc
        self.selection_changed = Signal()
        self.drag_finished = Signal()
        self.selected: str | None = None
        self._drag_counter = itertools.count(1)
        self._drag: int | None = None
        self._drag_kind: str | None = None  # "move" (a sphere) or "rotate" (the box) while the mouse drags
        self._syncing = False
        sk = doc.skeleton
        self._sites = tuple(sk.effector_sites)
        self._site_frames = np.array([sk.frame_of(n) for n in self._sites])
        self._limit_state: np.ndarray | None = None
        self.layers: list = []
        #: Callables giving more points (k, 3) [m] that framing keeps in view: the drawn body's extent.
        self.extents: list[Callable[[], np.ndarray]] = []
        self._build()
        self.refresh()
        self.sync_targets()
        self.set_view("perspective")

    # -- building ----------------------------------------------------------------
    def _build(self) -> None:
        pl = self.plotter
        sk = self.doc.skeleton
        pl.set_background(BACKGROUND_BOTTOM, top=BACKGROUND_TOP)
        pl.enable_lightkit()
        self.actors: dict[str, object] = {}

        # Floor grid, 4 m x 4 m, 25 cm cells, and a faint floor.
        ticks = np.arange(-2.0, 2.0001, 0.25)
        pts, pairs = [], []
        for t in ticks:
            pts += [(t, -2.0, 0.0), (t, 2.0, 0.0), (-2.0, t, 0.0), (2.0, t, 0.0)]
        pairs = np.arange(len(pts)).reshape(-1, 2)
        grid = pv.PolyData(np.array(pts), lines=line_cells(pairs))
        self.actors["grid"] = pl.add_mesh(grid, color=GRID_COLOR, line_width=1, lighting=False, pickable=False,
                                          reset_camera=False)
        floor = pv.Plane(center=(0, 0, -0.002), direction=(0, 0, 1), i_size=4.0, j_size=4.0)
        # Unlit: the lit floor was this one colour from every view (no specular, camera-following directional
        # lights), and lighting it cost about a quarter of a render under software GL.
        self.actors["floor"] = pl.add_mesh(floor, color=FLOOR_COLOR, opacity=1.0, pickable=False,
                                           reset_camera=False, lighting=False)

        # Bones: all frames as points, bones as lines between them.
        n_frames = sk.n_frames
        self._bones = pv.PolyData(np.zeros((n_frames, 3)), lines=line_cells(sk.bone_frames))
        self.actors["bones"] = pl.add_mesh(self._bones, color=BONE_COLOR, line_width=7, render_lines_as_tubes=True,
                                           pickable=False, reset_camera=False)

        # Joints: a glyph sphere per primary joint, coloured per point.
        self._joint_frames = np.asarray(sk.joint_frame)
        self._joints = pv.PolyData(np.zeros((len(self._joint_frames), 3)))
        self._joint_colors = np.tile(rgb8(JOINT_COLOR), (len(self._joint_frames), 1))
        self.actors["joints"] = glyph_actor(self._joints, JOINT_RADIUS, self._joint_colors)
        pl.add_actor(self.actors["joints"], reset_camera=False, pickable=False)
        # Which joint each DOF belongs to.
        self._dof_joint = np.zeros(sk.n_dofs, dtype=np.int64)
        for j, dofs in enumerate(sk.joint_dofs):
            self._dof_joint[list(dofs)] = j

        # DOF gizmos: a ring + stick per DOF in its own frame, axis-coloured.
        self._dof_frames = np.asarray(sk.dof_frame)
        local = np.stack([ring_and_stick(np.asarray(sk.frame_axis[f])) for f in self._dof_frames])
        self._gizmo_local = local  # (n_dofs, K, 3)
        K = local.shape[1]
        cells = []
        for d in range(sk.n_dofs):
            base = d * K
            ring = [base + i for i in range(RING_POINTS)] + [base]
            cells += [len(ring)] + ring
            cells += [2, base + RING_POINTS, base + RING_POINTS + 1]
        self._gizmos = pv.PolyData(np.zeros((sk.n_dofs * K, 3)), lines=np.array(cells, dtype=np.int64))
        axis_index = np.argmax(np.abs(np.asarray(sk.frame_axis)[self._dof_frames]), axis=1)
        self._dof_base_colors = rgb8(AXIS_COLORS[axis_index])
        self._gizmo_colors = np.repeat(self._dof_base_colors, K, axis=0)
        self._gizmos.point_data.set_array(self._gizmo_colors, "colors")
        self.actors["gizmos"] = pl.add_mesh(self._gizmos, scalars="colors", rgb=True, line_width=2, lighting=False,
                                            pickable=False, reset_camera=False)

        # Achieved effectors: green glyph spheres; triads for effectors and targets.
        m = len(self._sites)
        self._effectors = pv.PolyData(np.zeros((m, 3)))
        self.actors["effectors"] = glyph_actor(self._effectors, EFFECTOR_RADIUS, None, EFFECTOR_COLOR)
        pl.add_actor(self.actors["effectors"], reset_camera=False, pickable=False)
        # 2 triads (achieved, target) x 3 axes x 2 points per site.
        self._triads = pv.PolyData(np.zeros((m * 12, 3)), lines=line_cells(np.arange(m * 12).reshape(-1, 2)))
        self._triads.point_data.set_array(np.tile(np.repeat(rgb8(AXIS_COLORS), 2, axis=0), (2 * m, 1)), "colors")
        self.actors["triads"] = pl.add_mesh(self._triads, scalars="colors", rgb=True, line_width=3, lighting=False,
                                            pickable=False, reset_camera=False)

        # Thin lines target <-> achieved.
        self._errors = pv.PolyData(np.zeros((m * 2, 3)), lines=line_cells(np.arange(m * 2).reshape(-1, 2)))
        self.actors["errors"] = pl.add_mesh(self._errors, color=ERROR_LINE_COLOR, line_width=1.5, lighting=False,
                                            pickable=False, reset_camera=False)

        # Root marker: a ring on the sole of the root, moved with a user matrix.
        disc = pv.Disc(center=(0, 0, 0.003), inner=0.075, outer=0.105, normal=(0, 0, 1), c_res=40)
        self.actors["root"] = pl.add_mesh(disc, color=ROOT_COLOR, lighting=False, pickable=False, reset_camera=False)

        self._dynamic = (self._bones, self._joints, self._gizmos, self._effectors, self._triads, self._errors)
        self._bones_xyz, self._joints_xyz, self._gizmos_xyz, self._effectors_xyz, self._triads_xyz, \
            self._errors_xyz = (points_view(pd) for pd in self._dynamic)

        # Target gizmos: one sphere widget per effector site.
        self.target_widgets = []
        for i, name in enumerate(self._sites):
            w = sphere_widget(pl, TARGET_RADIUS, TARGET_COLOR, TARGET_SELECTED_COLOR, opacity=TARGET_OPACITY)
            w.AddObserver("StartInteractionEvent", self._make_callback(self._on_drag_start, name))
            w.AddObserver("InteractionEvent", self._make_callback(self._on_drag_move, name))
            w.AddObserver("EndInteractionEvent", self._make_callback(self._on_drag_end, name))
            w.On()
            self.target_widgets.append(w)

        # Orientation handle for the selected target: a rotate-only box widget.
        box = vtkBoxWidget()
        box.SetInteractor(pl.iren.interactor)
        box.SetCurrentRenderer(pl.renderer)
        box.SetPlaceFactor(1.0)
        h = BOX_SIZE / 2
        box.PlaceWidget(-h, h, -h, h, -h, h)
        box.SetHandleSize(0.002)
        box.HandlesOff()
        box.ScalingEnabledOff()
        box.TranslationEnabledOff()
        box.RotationEnabledOn()
        box.SetPriority(0.5)
        box.GetOutlineProperty().SetColor(TARGET_SELECTED_COLOR)
        box.GetOutlineProperty().SetLineWidth(1.5)
        box.GetSelectedOutlineProperty().SetColor(1.0, 1.0, 1.0)
        box.GetSelectedFaceProperty().SetOpacity(0.15)
        box.AddObserver("StartInteractionEvent", lambda *_: self._on_rotate_start())
        box.AddObserver("InteractionEvent", lambda *_: self._on_rotate_move())
        box.AddObserver("EndInteractionEvent", lambda *_: self._on_rotate_end())
        self.box_widget = box

        # Label of the selected target, and the root / status text.
        self._label = vtkBillboardTextActor3D()
        self._label.GetTextProperty().SetFontSize(16)
        self._label.GetTextProperty().SetColor(1.0, 0.85, 0.85)
        self._label.GetTextProperty().SetBold(True)
        self._label.SetDisplayOffset(14, 10)
        self._label.VisibilityOff()
        pl.add_actor(self._label, reset_camera=False, pickable=False)
        self._corner = vtkTextActor()
        tp = self._corner.GetTextProperty()
        tp.SetFontSize(15)
        tp.SetColor(0.88, 0.90, 0.93)
        tp.SetVerticalJustificationToTop()
        self._corner.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        self._corner.SetPosition(0.012, 0.975)
        pl.add_actor(self._corner, reset_camera=False, pickable=False)
        self.plotter.add_axes(line_width=3, labels_off=False)

    @staticmethod
    def _make_callback(fn: Callable, name: str) -> Callable:
        return lambda widget, _event: fn(name, widget)

    # -- input -----------------------------------------------------------------
    def _on_drag_start(self, name: str, widget) -> None:
        self._drag = next(self._drag_counter)
        self._drag_kind = "move"
        self.select(name)

    def _on_drag_move(self, name: str, widget) -> None:
        if self._syncing or name not in self.doc.targets:
            return
        self.doc.move_target(name, widget.GetCenter(), drag=self._drag)

    def _on_drag_end(self, name: str, widget) -> None:
        self.doc.end_drag()
        self._drag = None
        self._drag_kind = None
        self.sync_targets()
        self.drag_finished.emit(name)

    def _on_rotate_start(self) -> None:
        self._drag = next(self._drag_counter)
        self._drag_kind = "rotate"

    def _on_rotate_move(self) -> None:
        name = self.selected
        if self._syncing or name is None or name not in self.doc.targets:
            return
        t = vtkTransform()
        self.box_widget.GetTransform(t)
        M = pv.array_from_vtkmatrix(t.GetMatrix())
        u, _, vt = np.linalg.svd(M[:3, :3])
        R = u @ vt
        if np.linalg.det(R) < 0:
            return
        self.doc.orient_target(name, quaternion_from_matrix(R), drag=self._drag)

    def _on_rotate_end(self) -> None:
        self.doc.end_drag()
        self._drag = None
        self._drag_kind = None
        self.sync_targets()

    def select(self, name: str | None) -> None:
        """Select a target (shows its rotate box and label); ``None`` clears."""
        if name is not None and name not in self._sites:
            raise ValueError(f"no effector {name!r}; effectors: {self._sites}")
        if name == self.selected:
            return
        self.selected = name
        self.sync_targets()
        self.selection_changed.emit(name)

    # -- updating ----------------------------------------------------------------
    def refresh(self) -> None:
        """Redraw the skeleton, effectors, triads and error lines from the document (no render)."""
        doc = self.doc
        P = doc.world_positions()
        R = doc.world_rotations()
        self._bones_xyz[:] = P
        self._joints_xyz[:] = P[self._joint_frames]

        # DOF rings and sticks.
        Rd = R[self._dof_frames]
        g = np.einsum("dij,dkj->dki", Rd, self._gizmo_local) + P[self._dof_frames][:, None, :]
        self._gizmos_xyz[:] = g.reshape(-1, 3)

        # Joint limits: recolour only when the set of joints on a limit changes.
        at_limit = doc.limit_mask()
        if self._limit_state is None or not np.array_equal(at_limit, self._limit_state):
            self._limit_state = at_limit
            joint_hit = np.zeros(len(self._joint_frames), dtype=bool)
            joint_hit[self._dof_joint[at_limit]] = True
            set_colors(self._joints, np.where(joint_hit[:, None], rgb8(LIMIT_COLOR), rgb8(JOINT_COLOR)))
            K = self._gizmo_local.shape[1]
            dof_colors = np.where(at_limit[:, None], rgb8(LIMIT_COLOR), self._dof_base_colors)
            set_colors(self._gizmos, np.repeat(dof_colors, K, axis=0))

        # Effectors (achieved) and targets.
        Pe = P[self._site_frames]
        Re = R[self._site_frames]
        self._effectors_xyz[:] = Pe
        targets = doc.targets
        tri = np.empty((len(self._sites), 2, 3, 2, 3))
        err = np.empty((len(self._sites), 2, 3))
        for i, name in enumerate(self._sites):
            p = Pe[i]
            tri[i, 0, :, 0] = p
            tri[i, 0, :, 1] = p + TRIAD_EFFECTOR * Re[i].T
            t = targets.get(name)
            if t is None or not t.enabled:
                tri[i, 1] = p
                err[i] = p
                continue
            tp = np.array(t.position)
            tri[i, 1, :, 0] = tp
            tri[i, 1, :, 1] = tp + (0.0 if t.position_only else TRIAD_TARGET) * t.rotation.T
            err[i, 0] = tp
            err[i, 1] = p
        self._triads_xyz[:] = tri.reshape(-1, 3)
        self._errors_xyz[:] = err.reshape(-1, 3)
        for pd in self._dynamic:
            touch(pd)

        # Root marker.
        f = doc.skeleton.frame_of(doc.root)
        self.actors["root"].user_matrix = transform(R[f], P[f])
        for layer in self.layers:
            layer.refresh(P, R)

    def sync_targets(self) -> None:
        """Move the target widgets to the document's targets (no callbacks fire)."""
        targets = self.doc.targets
        self._syncing = True
        try:
            for name, w in zip(self._sites, self.target_widgets):
                self._sync_sphere(name, w, targets.get(name))
            t = targets.get(self.selected) if self.selected else None
            self._sync_box(t if t is not None and t.enabled else None)
        finally:
            self._syncing = False
        self._corner.SetInput(f"IK root: {self.doc.root.replace('_', ' ')}")

    def _sync_sphere(self, name: str, w, t) -> None:
        """One target's sphere widget: hidden without an enabled target, else at the target."""
        if t is None or not t.enabled:
            if w.GetEnabled():
                w.Off()
            return
        if not w.GetEnabled():
            w.On()
        if not (self._drag_kind == "move" and name == self.selected):  # the dragged one moves itself
            w.SetCenter(*t.position)
        w.GetSphereProperty().SetColor(TARGET_SELECTED_COLOR if name == self.selected else TARGET_COLOR)

    def _sync_box(self, t) -> None:
        """The rotate box and label on the selected enabled target ``t``; hidden when None."""
        if t is None:
            if self.box_widget.GetEnabled():
                self.box_widget.Off()
            self._label.VisibilityOff()
            return
        if self._drag_kind != "rotate":  # the box being turned turns itself
            tr = vtkTransform()
            tr.SetMatrix(transform(t.rotation, np.array(t.position)).ravel())
            self.box_widget.SetTransform(tr)
        if not self.box_widget.GetEnabled():
            self.box_widget.On()
        self._label.SetInput(self.selected)
        self._label.SetPosition(*t.position)
        self._label.VisibilityOn()

    def set_targets_visible(self, visible: bool) -> None:
        """Show or hide every target gizmo (for pictures of the bare pose)."""
        for name, w in zip(self._sites, self.target_widgets):
            enabled = visible and name in self.doc.targets and self.doc.targets[name].enabled
            w.SetEnabled(int(enabled))
        if not visible:
            self.box_widget.Off()
            self._label.VisibilityOff()
        else:
            self.sync_targets()

    def render(self) -> None:
        """Render once (through Qt's repaint, so one render per frame)."""
        self.plotter.update()

    # -- camera ------------------------------------------------------------------
    def character_points(self) -> np.ndarray:
        """(k, 3) every frame of the character, every target and the points of :attr:`extents` [m]."""
        T = np.array([t.position for t in self.doc.targets.values()]).reshape(-1, 3)
        more = [np.asarray(extent(), dtype=float).reshape(-1, 3) for extent in self.extents]
        return np.vstack([self.doc.world_positions(), T, *more])

    def character_bounds(self) -> tuple[float, ...]:
        pts = self.character_points()
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        return (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])

    def set_view(self, name: str) -> None:
        """Look from a preset direction (see :data:`gsik_studio.camera.VIEWS`) and frame the character."""
        camera.set_view(self.plotter, name, self.character_points())

    def frame_all(self, extra: np.ndarray | None = None) -> None:
        """Fit the character, its targets and ``extra`` points (m, 3) [m] in the view, keeping the viewing
        direction (no render)."""
        pts = self.character_points()
        if extra is not None:
            pts = np.vstack([pts, np.asarray(extra, dtype=float).reshape(-1, 3)])
        camera.frame_points(self.plotter, pts)

    def frame_selected(self, radius: float = 0.15) -> None:
        """Fit the selected target and its effector, ``radius`` [m] around them (all when none is selected)."""
        t = self.doc.targets.get(self.selected) if self.selected else None
        if t is None:
            self.frame_all()
            return
        achieved = self.doc.effector_poses()[self.selected][:3, 3]
        pts = np.vstack([t.position, achieved])
        box = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * radius
        camera.frame_points(self.plotter, (pts[:, None, :] + box[None]).reshape(-1, 3), least=0.2)

    # -- helpers for tests and tools --------------------------------------------------
    def world_to_display(self, point) -> tuple[float, float]:
        """Display coordinates (pixels, origin bottom-left) of a world point."""
        ren = self.plotter.renderer
        ren.SetWorldPoint(*point, 1.0)
        ren.WorldToDisplay()
        x, y, _ = ren.GetDisplayPoint()
        return x, y

    def snap_offset(self, x: float, y: float) -> tuple[float, float]:
        """Display offset (dx, dy) [px] that moves a press at (x, y) onto the nearest target sphere it misses by
        at most :data:`PICK_TOLERANCE_PX`; (0, 0) for a direct hit or nothing near (display pixels, origin
        bottom-left). The selected target is left out: its rotate box surrounds it."""
        cam = self.plotter.camera
        right = np.cross(np.array(cam.GetDirectionOfProjection()), np.array(cam.up))
        right /= max(np.linalg.norm(right), 1e-12)
        best, offset = np.inf, (0.0, 0.0)
        for name, w in zip(self._sites, self.target_widgets):
            if not w.GetEnabled():
                continue
            c = np.array(w.GetCenter())
            cx, cy = self.world_to_display(c)
            rx, ry = self.world_to_display(c + TARGET_RADIUS * right)
            d, r = np.hypot(cx - x, cy - y), np.hypot(rx - cx, ry - cy)
            if d <= r:
                return 0.0, 0.0
            if name != self.selected and d <= r + PICK_TOLERANCE_PX and d < best:
                best, offset = d, (cx - x, cy - y)
        return offset

    def n_scene_objects(self) -> dict[str, int]:
        """How many actors and widgets the scene holds (for the benchmark's bare scene)."""
        return {"actors": len(self.actors) + 1, "sphere_widgets": len(self.target_widgets), "box_widgets": 1}
