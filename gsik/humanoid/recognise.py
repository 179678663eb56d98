"""Recognise a humanoid in any rig: names first, structure where names fail, a mapping's entries over both."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from gsik.errors import HumanoidError, choices
from gsik.humanoid.bones import HUMANOID_BONES, REQUIRED_BONES
from gsik.humanoid.chains import Found, bones_by_name
from gsik.humanoid.names import label
from gsik.humanoid.rig import Rig


@dataclass(frozen=True, eq=False)
class Recognition:
    """What was recognised in a rig.

    Attributes:
        bones: Canonical bone -> the rig's joint name (only the bones found), in :data:`HUMANOID_BONES` order.
        confidence: Canonical bone -> how sure the finding is, 0..1 (a name ~0.9, the structure ~0.6, a map 1).
        method: Canonical bone -> ``"name"``, ``"structure"`` or ``"map"``.
        ignored: Rig joint -> why it is no humanoid bone (``"twist"``, ``"roll"``, ``"share"``, ``"end"``,
            ``"finger"``, ``"face"``, ``"helper"``: named for a part another joint holds, ``"other"``).
        up: (3,) unit up axis of the rig's rest pose, in the rig's coordinates.
        forward: (3,) unit direction the rig faces in its rest pose.
        height: Rest height along ``up`` [rig units].
    """

    bones: Mapping[str, str]
    confidence: Mapping[str, float]
    method: Mapping[str, str]
    ignored: Mapping[str, str]
    up: np.ndarray = field(repr=False)
    forward: np.ndarray = field(repr=False)
    height: float = 0.0

    def joint(self, bone: str) -> str:
        """The rig's joint for canonical ``bone``; :class:`HumanoidError` naming it and what was found if missing."""
        if bone not in self.bones:
            what = "not a humanoid bone" if bone not in HUMANOID_BONES else "not found in the rig"
            raise HumanoidError(f"bone {bone!r} is {what}; recognised: "
                                + (choices([f"{b}={j}" for b, j in self.bones.items()]) or "nothing"))
        return self.bones[bone]


def _unit(v: np.ndarray) -> np.ndarray | None:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-9 else None


def _snap(v: np.ndarray, degrees: float = 25.0) -> np.ndarray:
    """``v`` (unit) turned onto the nearest axis when it is within ``degrees`` of it."""
    k = int(np.argmax(np.abs(v)))
    if abs(v[k]) >= np.cos(np.radians(degrees)):
        out = np.zeros(3)
        out[k] = np.sign(v[k])
        return out
    return v


def rest_axes(rig: Rig, found: Mapping[str, int]) -> tuple[np.ndarray, np.ndarray, float]:
    """``(up, forward, height)`` of the rest pose: up from the hips to the head, left from the right limbs to
    the left ones, forward = left x up; each snapped to an axis within 25 degrees. Defaults y up, +z forward."""
    p = rig.rest_positions
    at = {b: p[j] for b, j in found.items()}
    up = _unit(at["head"] - at["hips"]) if {"head", "hips"} <= at.keys() else None
    up = np.array([0.0, 1.0, 0.0]) if up is None else _snap(up)
    left = sum((at[f"left{b}"] - at[f"right{b}"] for b in ("UpperLeg", "UpperArm", "Hand", "Foot")
                if f"left{b}" in at and f"right{b}" in at), np.zeros(3))
    left = _unit(left - np.dot(left, up) * up)
    forward = _unit(np.cross(left, up)) if left is not None else None
    if forward is None:
        forward = _unit(np.cross(up, [1.0, 0.0, 0.0])) if abs(up[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    height = float(np.ptp(p @ up)) if len(p) else 0.0
    return up, _snap(forward), height


def _overridden(rig: Rig, found: dict[str, Found], method: dict[str, str],
                overrides: Mapping[str, str]) -> None:
    """Apply ``overrides`` (canonical bone -> joint name) to ``found``/``method``, each checked."""
    index = {n: k for k, n in enumerate(rig.names)}
    for bone, joint in overrides.items():
        if bone not in HUMANOID_BONES:
            raise HumanoidError(f"mapping names bone {bone!r}, which is no humanoid bone; valid: "
                                f"{choices(HUMANOID_BONES)}")
        if joint not in index:
            raise HumanoidError(f"mapping names joint {joint!r} for {bone!r}, which is not in the rig; valid: "
                                f"{choices(rig.names)}")
        found[bone] = Found(index[joint], 1.0)
        method[bone] = "map"


def _ignored(rig: Rig, labels, used: set[int]) -> dict[str, str]:
    """Why each joint no bone uses is not one."""
    out = {}
    for j, (name, lab) in enumerate(zip(rig.names, labels)):
        if j not in used:
            out[name] = lab.helper or ("helper" if lab.kind else "other")
    return out


def recognise(rig: Rig, overrides: Mapping[str, str] | None = None, *,
              required: Sequence[str] = REQUIRED_BONES) -> Recognition:
    """The humanoid bones of ``rig``: names first (every convention, :mod:`gsik.humanoid.names`), the
    structure where names fail (:mod:`gsik.humanoid.structure`), ``overrides`` (canonical bone -> joint) over both.
    ``required``: the bones the caller cannot do without (default VRM's required set).

    Raises:
        HumanoidError: a required bone (:data:`REQUIRED_BONES`) is not found (the message names the missing
            bones, what was found and the rig's joints), or an override names an unknown bone or joint.
    """
    from gsik.humanoid.structure import bones_by_structure

    labels = [label(n) for n in rig.names]
    found = bones_by_name(rig, labels)
    method = {b: "name" for b in found}
    if any(b not in found for b in REQUIRED_BONES + tuple(required)):
        for bone, f in bones_by_structure(rig, labels, found).items():
            if bone not in found:
                found[bone], method[bone] = f, "structure"
    _overridden(rig, found, method, overrides or {})
    missing = [b for b in required if b not in found]
    if missing:
        raise HumanoidError(
            f"cannot read the rig as a humanoid: no joint found for {choices(missing)}; found "
            + (choices([f"{b}={rig.names[f.joint]}" for b, f in found.items()]) or "nothing")
            + f"; the rig's joints: {choices(rig.names)} (name them in a mapping file)")
    order = [b for b in HUMANOID_BONES if b in found]
    up, forward, height = rest_axes(rig, {b: found[b].joint for b in order})
    up.flags.writeable = forward.flags.writeable = False
    return Recognition(
        bones={b: rig.names[found[b].joint] for b in order},
        confidence={b: found[b].confidence for b in order},
        method={b: method[b] for b in order},
        ignored=_ignored(rig, labels, {found[b].joint for b in order}),
        up=up, forward=forward, height=height)


__all__ = ["Recognition", "recognise", "rest_axes"]
