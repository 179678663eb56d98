"""A tests-only stand-in for gsik.humanoid's contract (HUMANOID_API.md), used until the humanoid branch is merged:
recognises the four namings of tests/io/gltf_characters.py by their names only."""

from __future__ import annotations

import sys
import types
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from gsik.errors import GsikError


class HumanoidError(GsikError, ValueError):
    pass


@dataclass(frozen=True)
class Rig:
    names: tuple
    parents: tuple
    rest_positions: np.ndarray


@dataclass(frozen=True)
class Recognition:
    bones: Mapping
    confidence: Mapping = field(default_factory=dict)
    method: Mapping = field(default_factory=dict)
    ignored: Mapping = field(default_factory=dict)
    up: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    forward: np.ndarray = field(default_factory=lambda: np.array([0.0, -1.0, 0.0]))
    height: float = 1.8

    def joint(self, bone: str) -> str:
        if bone not in self.bones:
            raise HumanoidError(f"no {bone}")
        return self.bones[bone]


REQUIRED = ("hips", "spine", "head", "leftUpperArm", "leftLowerArm", "leftHand", "rightUpperArm", "rightLowerArm",
            "rightHand", "leftUpperLeg", "leftLowerLeg", "leftFoot", "rightUpperLeg", "rightLowerLeg", "rightFoot")


def recognise(rig: Rig, overrides=None) -> Recognition:
    from gltf_characters import LAYOUT, NAMINGS

    bones = {}
    for naming in NAMINGS.values():
        found = {b: naming(b) for b in LAYOUT if naming(b) in rig.names}
        if len(found) > len(bones):
            bones = found
    bones.update(overrides or {})
    missing = [b for b in REQUIRED if b not in bones]
    if missing:
        raise HumanoidError(f"not a humanoid: missing {missing}; joints: {list(rig.names)[:20]}")
    return Recognition(bones)


def install() -> None:
    """Put the stand-in at ``gsik.humanoid`` when the real module is not there."""
    try:
        import gsik.humanoid  # noqa: F401
    except ImportError:
        module = types.ModuleType("gsik.humanoid")
        module.Rig, module.Recognition, module.recognise, module.HumanoidError = Rig, Recognition, recognise, \
            HumanoidError
        sys.modules["gsik.humanoid"] = module
