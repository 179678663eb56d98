"""Human ranges of motion for a recognised humanoid's joints, on each joint's own local axes.

A glTF joint turns about its three local axes (x, y, z, in that order). Which of them is the bone's twist and which
bends a knee depends on how the rig was made, so each range is placed from the rest pose: the *twist* axis is the
local axis closest to the bone (towards its child), a knee's or an elbow's *hinge* axis the one closest to the
axis across the bone and the facing direction, signed so that it bends the right way (knees back, elbows forward). Every other axis gets
the bone's swing range. Angles in degrees below, radians in the results.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np


class BoneRange(NamedTuple):
    """A canonical bone's range: ``swing`` and ``twist`` half-ranges [deg], or a hinge's bend [deg]."""

    swing: float
    twist: float
    hinge: float = 0.0  # > 0: a hinge bending this far, the other two axes kept within ``swing``


#: Canonical (VRM) bone -> its range. Bones not listed keep a moderate default (:data:`DEFAULT_RANGE`).
HUMAN_RANGES: Mapping[str, BoneRange] = {
    "hips": BoneRange(180.0, 180.0),
    "spine": BoneRange(30.0, 30.0), "chest": BoneRange(25.0, 25.0), "upperChest": BoneRange(20.0, 20.0),
    "neck": BoneRange(40.0, 50.0), "head": BoneRange(40.0, 50.0),
    "leftShoulder": BoneRange(20.0, 10.0), "rightShoulder": BoneRange(20.0, 10.0),
    "leftUpperArm": BoneRange(120.0, 90.0), "rightUpperArm": BoneRange(120.0, 90.0),
    "leftLowerArm": BoneRange(5.0, 80.0, 150.0), "rightLowerArm": BoneRange(5.0, 80.0, 150.0),
    "leftHand": BoneRange(70.0, 20.0), "rightHand": BoneRange(70.0, 20.0),
    "leftUpperLeg": BoneRange(110.0, 45.0), "rightUpperLeg": BoneRange(110.0, 45.0),
    "leftLowerLeg": BoneRange(5.0, 5.0, 150.0), "rightLowerLeg": BoneRange(5.0, 5.0, 150.0),
    "leftFoot": BoneRange(45.0, 20.0), "rightFoot": BoneRange(45.0, 20.0),
    "leftToes": BoneRange(40.0, 5.0), "rightToes": BoneRange(40.0, 5.0),
}
DEFAULT_RANGE = BoneRange(30.0, 30.0)
#: How far a hinge may straighten past its rest angle [deg] (a knee locked straight still solves).
HINGE_BACK = 5.0


class RestFrame(NamedTuple):
    """What placing a range needs of one joint at rest, in world coordinates.

    Attributes:
        rotation: (3, 3) the joint's world rotation (columns: its local axes).
        bone: (3,) from the joint to its child (zero for a leaf).
        forward: (3,) unit facing direction of the body.
    """

    rotation: np.ndarray
    bone: np.ndarray
    forward: np.ndarray


def joint_limits(bone: str | None, rest: RestFrame) -> tuple[tuple[float, float], ...]:
    """``((lower, upper) [rad],) * 3`` of a joint's x, y, z rotations: ``bone``'s human range, zero for ``None``.

    An unrecognised joint (``bone`` None) gets zero ranges: it stays at its rest angles.
    """
    if bone is None:
        return ((0.0, 0.0),) * 3
    spec = HUMAN_RANGES.get(bone, DEFAULT_RANGE)
    swing, twist = math.radians(spec.swing), math.radians(spec.twist)
    limits = [(-swing, swing)] * 3
    length = float(np.linalg.norm(rest.bone))
    if length > 1e-9:
        k = int(np.argmax(np.abs(rest.rotation.T @ (rest.bone / length))))
        limits[k] = (-twist, twist)
    if spec.hinge > 0 and length > 1e-9:
        across = np.cross(rest.bone / length, rest.forward)  # the axis a bend towards or away from forward turns about
        closeness = np.abs(rest.rotation.T @ across)
        closeness[k] = -1.0
        h = int(np.argmax(closeness))
        limits[h] = _hinge(bone, rest, h, math.radians(spec.hinge))
    return tuple(limits)


def _hinge(bone: str, rest: RestFrame, axis: int, bend: float) -> tuple[float, float]:
    """A hinge's ``(lower, upper)`` [rad]: bending ``bend`` the way a knee (back) or an elbow (forward) bends."""
    a = rest.rotation[:, axis]
    moves = np.cross(a, rest.bone)  # where the child goes for a positive angle
    towards = -rest.forward if "Leg" in bone else rest.forward
    back = math.radians(HINGE_BACK)
    return (-back, bend) if float(moves @ towards) >= 0.0 else (-bend, back)
