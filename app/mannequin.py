"""A body to look at: capsules and boxes around the bones, built once and moved in place every frame.

Each bone is a rigid solid in the frame that carries it (:func:`segment_shapes`):
its vertices and normals are stored once in that frame, and a frame's update
is one ``einsum`` writing world coordinates into the PolyData's own arrays
(no mesh is rebuilt, see /work/shared/VIEWPORT.md). Capsules and boxes are two
PolyData with one template each, so each updates with one vectorised product.

The bundled skeletons' segments get hand-set sizes (:data:`SEGMENT_SIZES`); bones
of any other skeleton are capsules whose radius follows their length.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper
from vtkmodules.util.numpy_support import vtk_to_numpy

import gsik
from gsik_studio.scene import rgb8, touch

BODY_COLOR = (0.74, 0.71, 0.66)
LEFT_COLOR = (0.60, 0.67, 0.78)  # the left side tinted, so a side view says which leg is which
AROUND = 18  # vertices around a capsule
CAP_RINGS = 5  # rings per hemisphere

#: ``{segment name: ("capsule", radius [m]) or ("box", half width [m], half depth [m])}`` for the bundled
#: skeletons (``left_``/``right_`` dropped): the biped's, and the humanoid's trunk in two parts, clavicles, hands.
SEGMENT_SIZES = {
    "pelvis": ("capsule", 0.075),
    "torso": ("box", 0.13, 0.085),
    "abdomen": ("box", 0.115, 0.08),
    "thorax": ("box", 0.13, 0.085),
    "clavicle": ("capsule", 0.045),
    "neck": ("capsule", 0.045),
    "head": ("capsule", 0.085),
    "upper_arm": ("capsule", 0.044),
    "forearm": ("capsule", 0.036),
    "hand": ("box", 0.014, 0.04),  # flat: the palm faces the thigh (the carrier's x)
    "thigh": ("capsule", 0.065),
    "shin": ("capsule", 0.048),
    "foot": ("box", 0.042, 0.028),
}
#: The skeletons whose segments :data:`SEGMENT_SIZES` sizes.
SIZED_SKELETONS = ("biped", "humanoid")
#: A box spans its segment's first bone only (the spine of a torso); the others are capsules this thick [m].
SHOULDER_RADIUS = 0.05


class Shape(NamedTuple):
    """One bone's solid, in the frame that carries it.

    Attributes:
        carrier: Frame index the solid is rigid in.
        start, end: (3,) [m] the bone's ends in the carrier's frame.
        kind: "capsule" or "box".
        size: (radius,) for a capsule, (half width, half depth) for a box [m].
        left: True for a segment of the left side (drawn tinted).
    """

    carrier: int
    start: np.ndarray
    end: np.ndarray
    kind: str
    size: tuple[float, ...]
    left: bool


def _carrier(sk: gsik.Skeleton, a: int, b: int) -> int:
    """The frame in which the bone between frames ``a`` and ``b`` is rigid.

    Walking up from the end that is not above the other, the first frame
    with a non-zero offset is where the bone's length lies: its parent carries
    the bone (the frames below it only turn about their point).
    """
    f = a if sk.ancestry[b, a] else b
    while f >= 0 and not np.any(sk.frame_offset[f]):
        f = int(sk.frame_parent[f])
    return int(sk.frame_parent[f]) if f >= 0 and sk.frame_parent[f] >= 0 else max(f, 0)


def _size(sk: gsik.Skeleton, bone: int, length: float) -> tuple[str, tuple[float, ...]]:
    segment = sk.bone_segment[bone]
    seg = sk.segment_names[segment]
    key = seg.split("_", 1)[1] if seg.startswith(("left_", "right_")) else seg
    spec = SEGMENT_SIZES.get(key) if sk.name in SIZED_SKELETONS else None
    if spec is None:
        return "capsule", (float(np.clip(0.14 * length, 0.02, 0.07)),)
    if spec[0] == "box" and bone != int(np.flatnonzero(sk.bone_segment == segment)[0]):
        return "capsule", (SHOULDER_RADIUS,)
    return spec[0], tuple(spec[1:])


def segment_shapes(sk: gsik.Skeleton) -> list[Shape]:
    """One :class:`Shape` per drawn bone of ``sk`` (zero-length bones skipped)."""
    solver = gsik.Solver(sk)
    P, R = solver.world_positions(), solver.world_rotations()
    shapes = []
    for bone, (a, b) in enumerate(np.asarray(sk.bone_frames)):
        c = _carrier(sk, int(a), int(b))
        start, end = R[c].T @ (P[a] - P[c]), R[c].T @ (P[b] - P[c])
        length = float(np.linalg.norm(end - start))
        if length < 1e-6:
            continue
        kind, size = _size(sk, bone, length)
        left = sk.segment_names[sk.bone_segment[bone]].startswith("left_")
        shapes.append(Shape(c, start, end, kind, size, left))
    return shapes


def _bone_axes(start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(3, 3) columns u, v, w: w along the bone, u as close to the carrier's x as it can be."""
    w = (end - start) / np.linalg.norm(end - start)
    u = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = u - (u @ w) * w
    u /= np.linalg.norm(u)
    return np.column_stack([u, np.cross(w, u), w])


def capsule_template(around: int = AROUND, cap_rings: int = CAP_RINGS):
    """A unit capsule as ``(points, normals, faces)``: points (K, 4) = (unit direction (3,), 0 or 1 for the end).

    A vertex lies at ``start + radius * direction`` (end flag 0) or ``end + radius * direction`` (flag 1).
    """
    polar = np.concatenate([np.linspace(np.pi, np.pi / 2, cap_rings + 1), np.linspace(np.pi / 2, 0, cap_rings + 1)])
    end_flag = np.concatenate([np.zeros(cap_rings + 1), np.ones(cap_rings + 1)])
    t = np.linspace(0.0, 2 * np.pi, around, endpoint=False)
    d = np.stack([np.sin(polar)[:, None] * np.cos(t), np.sin(polar)[:, None] * np.sin(t),
                  np.repeat(np.cos(polar)[:, None], around, axis=1)], axis=-1)  # (rings, around, 3)
    pts = np.concatenate([d, np.repeat(end_flag[:, None, None], around, axis=1)], axis=-1).reshape(-1, 4)
    rings = len(polar)
    faces = []
    for r in range(rings - 1):
        for k in range(around):
            a, b = r * around + k, r * around + (k + 1) % around
            faces.append((a, b, b + around, a + around))
    return pts, d.reshape(-1, 3), np.array(faces)


def _capsule_local(shape: Shape, template) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and normals (K, 3) of one capsule in its carrier's frame."""
    pts, normals, _ = template
    B = _bone_axes(shape.start, shape.end)
    n = normals @ B.T
    base = np.where(pts[:, 3:] > 0.5, shape.end, shape.start)
    return base + shape.size[0] * n, n


def _box_local(shape: Shape) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and normals (24, 3) of one box (4 vertices per face, flat normals) in its carrier's frame."""
    B = _bone_axes(shape.start, shape.end)
    hw, hd = shape.size
    length = float(np.linalg.norm(shape.end - shape.start))
    pad = hd  # the box overhangs both ends a little, like a capsule's caps
    corners = np.array([[x, y, z] for x in (-hw, hw) for y in (-hd, hd) for z in (-pad, length + pad)])
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    normals = [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)]
    v = np.array([corners[i] for f in faces for i in f]) @ B.T + shape.start
    n = np.repeat(np.array(normals, dtype=float), 4, axis=0) @ B.T
    return v, n


def box_faces(n_boxes: int) -> np.ndarray:
    return np.arange(n_boxes * 24).reshape(-1, 4)


class BodyMesh:
    """One PolyData of same-template solids: local vertices and normals per solid, moved by its carrier."""

    def __init__(self, carriers: list[int], local: list[tuple[np.ndarray, np.ndarray]], faces_per_solid: np.ndarray,
                 colors: np.ndarray):
        self.carriers = np.array(carriers, dtype=np.int64)
        self.local_points = np.stack([v for v, _ in local]) if local else np.zeros((0, 0, 3))
        self.local_normals = np.stack([n for _, n in local]) if local else np.zeros((0, 0, 3))
        s, k = self.local_points.shape[:2]
        faces = (faces_per_solid[None] + (np.arange(s) * k)[:, None, None]).reshape(-1, faces_per_solid.shape[1])
        cells = np.hstack([np.full((len(faces), 1), faces.shape[1]), faces]).ravel() if len(faces) else []
        self.polydata = pv.PolyData(self.local_points.reshape(-1, 3).copy(), faces=np.asarray(cells, dtype=np.int64))
        if not s:  # a skeleton with no solid of this kind: an empty mesh, nothing to move
            return
        self.polydata.point_data.set_array(self.local_normals.reshape(-1, 3).copy(), "Normals")
        self.polydata.point_data.active_normals_name = "Normals"
        self.polydata.point_data.set_array(np.repeat(colors, k, axis=0), "colors")
        self._xyz = vtk_to_numpy(self.polydata.GetPoints().GetData())
        self._normals = vtk_to_numpy(self.polydata.GetPointData().GetArray("Normals"))

    def update(self, P: np.ndarray, R: np.ndarray) -> None:
        """Move every solid with its carrier: world positions P (n_frames, 3) [m], rotations R (n_frames, 3, 3)."""
        if not len(self.carriers):
            return
        Rc = R[self.carriers]
        self._xyz[:] = (np.einsum("sij,skj->ski", Rc, self.local_points) + P[self.carriers][:, None, :]).reshape(-1, 3)
        self._normals[:] = np.einsum("sij,skj->ski", Rc, self.local_normals).reshape(-1, 3)
        touch(self.polydata)
        self.polydata.GetPointData().GetArray("Normals").Modified()


def _solid_actor(pd: pv.PolyData) -> vtkActor:
    """A plain mapper and actor (no pyvista pipeline in between): per-point RGB, the PolyData's own normals."""
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(pd)
    mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray("colors")
    mapper.SetColorModeToDirectScalars()
    mapper.ScalarVisibilityOn()
    actor = vtkActor()
    actor.SetMapper(mapper)
    prop = actor.GetProperty()
    prop.SetSpecular(0.25)
    prop.SetSpecularPower(18)
    return actor


class Mannequin:
    """The body: capsules and boxes added to a plotter once; :meth:`update` moves them in place.

    Args:
        plotter: The pyvista plotter to draw into.
        skeleton: The skeleton whose bones get solids.
    """

    def __init__(self, plotter: pv.Plotter, skeleton: gsik.Skeleton):
        shapes = segment_shapes(skeleton)
        template = capsule_template()
        caps = [s for s in shapes if s.kind == "capsule"]
        boxes = [s for s in shapes if s.kind == "box"]

        def colors(group):
            return rgb8([LEFT_COLOR if s.left else BODY_COLOR for s in group]).reshape(-1, 3)

        self.meshes = (
            BodyMesh([s.carrier for s in caps], [_capsule_local(s, template) for s in caps], template[2],
                     colors(caps)),
            BodyMesh([s.carrier for s in boxes], [_box_local(s) for s in boxes], box_faces(1), colors(boxes)),
        )
        self.actors = [_solid_actor(m.polydata) for m in self.meshes]
        for a in self.actors:
            plotter.add_actor(a, reset_camera=False, pickable=False)

    @property
    def n_solids(self) -> int:
        return sum(len(m.carriers) for m in self.meshes)

    def update(self, P: np.ndarray, R: np.ndarray) -> None:
        """Move the body to world positions P (n_frames, 3) [m] and rotations R (n_frames, 3, 3)."""
        for m in self.meshes:
            m.update(P, R)

    def set_visible(self, visible: bool) -> None:
        for a in self.actors:
            a.SetVisibility(bool(visible))

    @property
    def visible(self) -> bool:
        return bool(self.actors[0].GetVisibility())
