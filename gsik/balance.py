"""Balance: the centre of mass, its Jacobian, and the support polygon of the feet.

Each massive segment is a rigid body carried by one frame (its *body*): the
frame all its points are fixed in. Its centre of mass is a point fixed in
that frame, so the whole body's centre of mass and its Jacobian follow from
the world frames and the frames' Jacobians::

    c = sum_s m_s (p_s + R_s l_s) / M
    dc/dq = sum_s m_s (Jv_s + Jw_s x R_s l_s) / M

The ground is the plane z = 0 seen from above (x, y); support polygons are
convex, counter-clockwise, (k, 2) [m].
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gsik.errors import SkeletonError


class MassModel(NamedTuple):
    """Where the mass of a skeleton sits. Read-only arrays.

    Attributes:
        body_frame: (s,) frame index carrying each massive segment.
        com_local: (s, 3) [m] each segment's centre of mass in its body frame.
        mass: (s,) [kg] each segment's mass (> 0).
    """

    body_frame: np.ndarray
    com_local: np.ndarray
    mass: np.ndarray

    @property
    def total_mass(self) -> float:
        """The whole body's mass [kg]."""
        return float(self.mass.sum())


def center_of_mass(model: MassModel, R: np.ndarray, p: np.ndarray) -> np.ndarray:
    """World centre of mass (3,) [m] given world rotations ``R`` (n_frames, 3, 3) and positions ``p`` (n_frames, 3)."""
    f = model.body_frame
    points = p[f] + np.einsum("sij,sj->si", R[f], model.com_local)
    return model.mass @ points / model.total_mass


def com_jacobian(model: MassModel, R: np.ndarray, frame_jacobian: np.ndarray) -> np.ndarray:
    """Jacobian (3, n_dofs) [m/rad] of the world centre of mass.

    Args:
        model: The :class:`MassModel`.
        R: World rotations (n_frames, 3, 3).
        frame_jacobian: (6 s, n_dofs) Jacobian of the body frames, in
            ``model.body_frame`` order: 3 position rows then 3 angular rows
            each (as :func:`gsik.kinematics.jacobian` gives).
    """
    s = model.mass.shape[0]
    Jf = frame_jacobian.reshape(s, 6, -1)
    arm = np.einsum("sij,sj->si", R[model.body_frame], model.com_local)  # (s, 3) body origin to segment COM
    # v_com = v_frame + omega x arm
    cross = np.cross(Jf[:, 3:], arm[:, :, None], axisa=1, axisb=1, axisc=1)
    return np.einsum("s,sin->in", model.mass, Jf[:, :3] + cross) / model.total_mass


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull (k, 2) of ``points`` (n, 2) (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.asarray(points, dtype=float)[:, :2])))
    if len(pts) < 3:
        return np.array(pts, dtype=float).reshape(-1, 2)

    def half(seq):
        out: list = []
        for pt in seq:
            while len(out) >= 2 and _cross(out[-2], out[-1], pt) <= 0:
                out.pop()
            out.append(pt)
        return out[:-1]

    return np.array(half(pts) + half(reversed(pts)), dtype=float)


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def support_polygon(world_from_feet: list[np.ndarray], soles: list[np.ndarray]) -> np.ndarray:
    """The convex hull (k, 2) [m] on the ground of the feet's soles.

    Args:
        world_from_feet: World transforms (4, 4) of the feet's frames.
        soles: For each foot, its sole's corners (c, 2) [m] in the foot
            frame's x-y plane.
    """
    corners = []
    for T, sole in zip(world_from_feet, soles):
        sole = np.asarray(sole, dtype=float)
        local = np.column_stack([sole, np.zeros(len(sole)), np.ones(len(sole))])
        corners.append((local @ np.asarray(T).T)[:, :2])
    return convex_hull(np.vstack(corners))


def signed_distance(polygon: np.ndarray, point: np.ndarray) -> float:
    """Distance [m] from ``point`` (2,) to a convex counter-clockwise ``polygon`` (k, 2): negative inside."""
    if len(polygon) == 1:
        return float(np.linalg.norm(np.asarray(point)[:2] - polygon[0]))
    return float(np.max(_edge_distances(polygon, point)))


def _edge_distances(polygon, point):
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    edge = b - a
    outward = np.column_stack([edge[:, 1], -edge[:, 0]]) / np.linalg.norm(edge, axis=1)[:, None]
    return np.einsum("ki,ki->k", np.asarray(point)[None, :2] - a, outward)


def shrink(polygon: np.ndarray, margin: float) -> np.ndarray:
    """The convex ``polygon`` (k, 2) with every edge moved ``margin`` [m] inwards (its centroid if it vanishes)."""
    a = polygon
    edge = np.roll(polygon, -1, axis=0) - a
    inward = np.column_stack([-edge[:, 1], edge[:, 0]]) / np.linalg.norm(edge, axis=1)[:, None]
    a2 = a + margin * inward
    out = []
    for k in range(len(a)):
        # Corner k is where the moved edges k - 1 and k meet.
        p0, d0 = a2[k - 1], edge[k - 1]
        p1, d1 = a2[k], edge[k]
        t = np.linalg.solve(np.column_stack([d0, -d1]), p1 - p0)[0]
        out.append(p0 + t * d0)
    out = np.array(out)
    if signed_distance(polygon, out.mean(axis=0)) > -margin + 1e-12 or _area(out) <= 0.0:
        return polygon.mean(axis=0, keepdims=True)
    return out


def _area(polygon) -> float:
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def nearest_point_inside(polygon: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The point (2,) of the convex ``polygon`` (k, 2) nearest to ``point`` (2,): itself when inside."""
    point = np.asarray(point, dtype=float)[:2]
    if len(polygon) == 1:
        return polygon[0].copy()
    if signed_distance(polygon, point) <= 0.0:
        return point.copy()
    a = polygon
    edge = np.roll(polygon, -1, axis=0) - a
    t = np.clip(np.einsum("ki,ki->k", point - a, edge) / np.einsum("ki,ki->k", edge, edge), 0.0, 1.0)
    candidates = a + t[:, None] * edge
    return candidates[np.argmin(np.linalg.norm(candidates - point, axis=1))]


def body_frame(skeleton, frames) -> int:
    """The frame (index) that all of ``frames`` (joint end frames or sites) are fixed in, or -1 if none.

    A joint's position is fixed both in its own frame (it turns about itself)
    and in its parent joint's frame; a site's only in its joint's frame.
    """
    first = {int(f): int(skeleton.dof_frame[d[0]]) if d else int(f)
             for f, d in zip(skeleton.joint_frame, skeleton.joint_dofs)}
    common = None
    for f in map(int, frames):
        if f in first:
            carriers = {f, int(skeleton.frame_parent[first[f]])} - {-1}
        else:
            carriers = {int(skeleton.frame_parent[f])}
        common = carriers if common is None else common & carriers
    if not common:
        return -1
    # Several candidates only when the points lie on one joint's axis line: take the deepest.
    return max(common)


def mass_model(skeleton, segment_mass, com_fraction, R_rest: np.ndarray, p_rest: np.ndarray) -> MassModel:
    """The :class:`MassModel` of a skeleton's segments.

    Args:
        skeleton: A :class:`gsik.Skeleton`.
        segment_mass: (n_segments,) [kg] per segment; 0 for none.
        com_fraction: (n_segments,) where each centre of mass lies along the
            segment's first bone, from its start (0) to its first end (1).
        R_rest, p_rest: World frames at the rest pose (n_frames, 3, 3), (n_frames, 3).
    """
    frames, com, mass = [], [], []
    for s, m in enumerate(np.asarray(segment_mass, dtype=float)):
        if m <= 0.0:
            continue
        bones = skeleton.bone_frames[skeleton.bone_segment == s]
        start, ends = int(bones[0, 0]), bones[:, 1]
        body = body_frame(skeleton, [start, *ends])
        if body < 0:
            raise SkeletonError(f"segment {skeleton.segment_names[s]!r} has a mass but its points are not fixed in "
                                f"one joint's frame (they span a moving joint); give the mass to rigid segments")
        point = p_rest[start] + com_fraction[s] * (p_rest[ends[0]] - p_rest[start])
        frames.append(body)
        com.append(R_rest[body].T @ (point - p_rest[body]))
        mass.append(m)
    arrays = (np.array(frames, dtype=np.int64), np.array(com, dtype=float).reshape(-1, 3), np.array(mass, dtype=float))
    for a in arrays:
        a.flags.writeable = False
    return MassModel(*arrays)
