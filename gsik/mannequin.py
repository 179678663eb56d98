"""The mannequin's geometry: capsules and boxes around a skeleton's bones, each rigid in the frame that carries it.

Plain NumPy, shared by the studio (which moves the solids in place every frame) and the glTF export (which writes
them as a skinned mesh, each vertex bound to its carrier's joint with weight 1).

The bundled skeletons' segments get hand-set sizes (:data:`SEGMENT_SIZES`); bones of any other skeleton are capsules whose
radius follows their length.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.skeleton import Skeleton

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


def _carrier(sk: Skeleton, a: int, b: int) -> int:
    """The frame in which the bone between frames ``a`` and ``b`` is rigid.

    Walking up from the end that is not above the other, the first frame
    with a non-zero offset is where the bone's length lies: its parent carries
    the bone (the frames below it only turn about their point).
    """
    f = a if sk.ancestry[b, a] else b
    while f >= 0 and not np.any(sk.frame_offset[f]):
        f = int(sk.frame_parent[f])
    return int(sk.frame_parent[f]) if f >= 0 and sk.frame_parent[f] >= 0 else max(f, 0)


def _size(sk: Skeleton, bone: int, length: float) -> tuple[str, tuple[float, ...]]:
    segment = sk.bone_segment[bone]
    seg = sk.segment_names[segment]
    key = seg.split("_", 1)[1] if seg.startswith(("left_", "right_")) else seg
    spec = SEGMENT_SIZES.get(key) if sk.name in SIZED_SKELETONS else None
    if spec is None:
        return "capsule", (float(np.clip(0.14 * length, 0.02, 0.07)),)
    if spec[0] == "box" and bone != int(np.flatnonzero(sk.bone_segment == segment)[0]):
        return "capsule", (SHOULDER_RADIUS,)
    return spec[0], tuple(spec[1:])


def segment_shapes(sk: Skeleton) -> list[Shape]:
    """One :class:`Shape` per drawn bone of ``sk`` (zero-length bones skipped)."""
    T = sk.frame_transforms(sk.rest)
    P, R = T[:, :3, 3], T[:, :3, :3]
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


def capsule_local(shape: Shape, template) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and normals (K, 3) of one capsule in its carrier's frame."""
    pts, normals, _ = template
    B = _bone_axes(shape.start, shape.end)
    n = normals @ B.T
    base = np.where(pts[:, 3:] > 0.5, shape.end, shape.start)
    return base + shape.size[0] * n, n


def box_local(shape: Shape) -> tuple[np.ndarray, np.ndarray]:
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


class SolidMesh(NamedTuple):
    """Every solid of the mannequin as one triangle mesh, each vertex rigid in its carrier frame.

    Attributes:
        carrier: (n_vertices,) frame index each vertex moves with.
        points: (n_vertices, 3) [m] vertices in their carrier's frame.
        normals: (n_vertices, 3) unit normals in their carrier's frame.
        triangles: (n_triangles, 3) vertex indices.
        colors: (n_vertices, 3) RGB in [0, 1] (the left side tinted).
    """

    carrier: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    triangles: np.ndarray
    colors: np.ndarray


def mannequin_mesh(sk: Skeleton) -> SolidMesh:
    """The mannequin of ``sk`` (:func:`segment_shapes`) as one triangle mesh."""
    template = capsule_template()
    carrier, points, normals, triangles, colors = [], [], [], [], []
    start = 0
    for shape in segment_shapes(sk):
        v, n = capsule_local(shape, template) if shape.kind == "capsule" else box_local(shape)
        quads = template[2] if shape.kind == "capsule" else box_faces(1)
        carrier.append(np.full(len(v), shape.carrier))
        points.append(v)
        normals.append(n)
        triangles.append(np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]) + start)
        colors.append(np.tile(LEFT_COLOR if shape.left else BODY_COLOR, (len(v), 1)))
        start += len(v)
    if not points:
        return SolidMesh(np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), np.int64),
                         np.zeros((0, 3)))
    return SolidMesh(np.concatenate(carrier), np.concatenate(points), np.concatenate(normals),
                     np.concatenate(triangles).astype(np.int64), np.concatenate(colors))
