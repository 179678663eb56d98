"""Pole targets' geometry: where a pole rests (out in front of a knee, behind an elbow) and where it aims the joint.

Plain Python. A pole chooses the plane a limb bends in. With the limb's two
ends held (hip and ankle, shoulder and hand) its middle joint can only swing
about the line between them, on a circle; the solver gets a position-only
target on the joint at the point of that circle nearest the pole (its *aim*,
:func:`aim_point`), so the joint swings until the limb's plane holds the pole,
and the target is always within reach (an unreachable far point would leave a
large error that nothing can lower). A pole rests a good way out from its
joint, on the side the limb bends to (:func:`rest_place`): placing it moves
nothing, and dragging it sideways by a few centimetres swings the limb by a
visible angle.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

import gsik
from gsik.humanoid import recognise, rig_from_skeleton
from gsik.humanoid.bones import POLE_BONES

#: How far a pole rests from its joint, as a fraction of the limb's length (thigh + shin, upper arm + forearm).
POLE_DISTANCE = 0.5


class Limb(NamedTuple):
    """A two-bone limb around a pole joint, as frame indices of the skeleton.

    Attributes:
        start: The frame at the limb's upper end (the hip or shoulder joint).
        joint: The pole joint's frame (the knee or elbow).
        end: The frame at the limb's lower end (the ankle or wrist joint, else the hand site).
        hinge: The frame of the joint's first DOF (its bending axis).
        flex: +1 or -1: the sign of the hinge angle that bends the limb (the side of its range with more room).
    """

    start: int
    joint: int
    end: int
    hinge: int
    flex: float


def pole_joints(skeleton: gsik.Skeleton, named: tuple[str, ...]) -> tuple[str, ...]:
    """The joints that get pole targets: the ``named`` ones (the bundled skeletons' ``left_knee`` ...) where
    ``skeleton`` has any, else the knees and elbows that humanoid recognition finds (:data:`POLE_BONES`, in
    that order: a glTF character's or any imported rig's own joint names); none for a skeleton that is no humanoid.
    """
    have = tuple(n for n in named if n in skeleton.joint_names)
    if have:
        return have
    try:
        found = recognise(rig_from_skeleton(skeleton)).bones
    except gsik.GsikError:
        return ()
    return tuple(found[b] for b in POLE_BONES.values() if found.get(b) in skeleton.joint_names)


def limb_of(skeleton: gsik.Skeleton, joint: str) -> Limb:
    """The limb around ``joint``: its parent joint, its first child joint (else the first site on it), its hinge
    (the joint's DOF that turns furthest one way from rest: a knee's or elbow's bend, whichever local axis the rig
    bends it about, not its twist).

    Raises:
        TargetError: ``joint`` is not a joint with a DOF, a parent and something below it.
    """
    sk = skeleton
    if joint not in sk.joint_names:
        raise gsik.TargetError(f"no joint {joint!r} for a pole; joints: {', '.join(sk.joint_names)}")
    j = sk.joint_names.index(joint)
    frame = int(sk.joint_frame[j])
    children = [int(sk.joint_frame[c]) for c in range(sk.n_joints) if sk.joint_parent[c] == j]
    sites = [int(f) for f in sk.site_frame if sk.frame_parent[f] == frame]
    if sk.joint_parent[j] < 0 or not sk.joint_dofs[j] or not (children or sites):
        raise gsik.TargetError(f"joint {joint!r} is not the middle joint of a limb: it cannot have a pole")
    dof = max(sk.joint_dofs[j], key=lambda d: max(sk.upper[d] - sk.rest[d], sk.rest[d] - sk.lower[d]))
    flex = 1.0 if sk.upper[dof] - sk.rest[dof] >= sk.rest[dof] - sk.lower[dof] else -1.0
    return Limb(int(sk.joint_frame[sk.joint_parent[j]]), frame, (children or sites)[0], int(sk.dof_frame[dof]), flex)


def limbs(skeleton: gsik.Skeleton, joints) -> dict[str, Limb]:
    """``{joint: Limb}`` of the ``joints`` (names) that ``skeleton`` has as the middle joints of limbs, in order."""
    out = {}
    for name in joints:
        try:
            out[name] = limb_of(skeleton, name)
        except gsik.TargetError:
            continue
    return out


def bend_direction(limb: Limb, P: np.ndarray, R: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Unit vector (3,): the way the limb's joint sticks out from the line between the limb's ends.

    The joint moves that way when the limb bends more, whether the limb is bent
    or straight: it is the opposite of how the limb's end moves, across the
    line, when the hinge flexes with the upper bone held.

    Args:
        limb: The limb.
        P: World positions (n_frames, 3) [m]; R: world rotations (n_frames, 3, 3).
        axis: The skeleton's ``frame_axis`` (n_frames, 3).
    """
    start, joint, end = P[limb.start], P[limb.joint], P[limb.end]
    u = (end - start) / max(np.linalg.norm(end - start), 1e-12)
    end_moves = limb.flex * np.cross(R[limb.hinge] @ axis[limb.hinge], end - joint)
    d = -(end_moves - (end_moves @ u) * u)
    return d / max(np.linalg.norm(d), 1e-12)


def rest_place(skeleton: gsik.Skeleton, joint: str, P: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Where ``joint``'s pole rests (3,) [m] with the body at world positions P and rotations R.

    :data:`POLE_DISTANCE` times the limb's length from the joint along :func:`bend_direction`: the joint
    already points at it, so placing the pole moves nothing.
    """
    limb = limb_of(skeleton, joint)
    length = np.linalg.norm(P[limb.joint] - P[limb.start]) + np.linalg.norm(P[limb.end] - P[limb.joint])
    return P[limb.joint] + POLE_DISTANCE * length * bend_direction(limb, P, R, skeleton.frame_axis)


def aim_point(limb: Limb, P: np.ndarray, pole: np.ndarray) -> np.ndarray:
    """The point (3,) [m] of the joint's swing circle nearest ``pole`` (3,), at world positions P (n_frames, 3).

    The circle turns about the line between the limb's ends through the joint; on a straight limb (or a pole on
    that line) the aim is the joint itself: nothing to swing.
    """
    start, joint = P[limb.start], P[limb.joint]
    u = P[limb.end] - start
    u = u / max(np.linalg.norm(u), 1e-12)
    centre = start + ((joint - start) @ u) * u
    radius = np.linalg.norm(joint - centre)
    toward = pole - centre
    toward = toward - (toward @ u) * u
    norm = np.linalg.norm(toward)
    return joint.copy() if norm < 1e-9 else centre + radius / norm * toward


def swing_angle(limb: Limb, P0: np.ndarray, P1: np.ndarray) -> float:
    """How far [rad] the limb's joint swung about the line between its ends from positions P0 to P1 (n_frames, 3).

    Signed about the line from start to end at P1 (right hand); 0 when the joint lies on that line.
    """
    def across(P):
        u = P[limb.end] - P[limb.start]
        u = u / max(np.linalg.norm(u), 1e-12)
        v = P[limb.joint] - P[limb.start]
        return v - (v @ u) * u, u

    v0, _ = across(P0)
    v1, u = across(P1)
    v0 = v0 - (v0 @ u) * u  # the line may have turned a little: compare in P1's plane
    return float(np.arctan2(np.cross(v0, v1) @ u, v0 @ v1))
