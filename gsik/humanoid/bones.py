"""The canonical humanoid vocabulary: the VRM 1.0 / Unity Humanoid body bones.

``leftShoulder`` is the clavicle (VRM's meaning); ``leftUpperArm`` is the arm.
Fingers, eyes and jaw are not recognised (their joints are listed as ignored).
"""

from __future__ import annotations

#: Bones of the trunk, from the hips up.
TRUNK_BONES = ("hips", "spine", "chest", "upperChest", "neck", "head")
#: One side's arm, from the clavicle out (without the side prefix).
ARM_PARTS = ("Shoulder", "UpperArm", "LowerArm", "Hand")
#: One side's leg, from the thigh down (without the side prefix).
LEG_PARTS = ("UpperLeg", "LowerLeg", "Foot", "Toes")
SIDES = ("left", "right")

#: Every canonical bone gsik recognises, trunk first, then arms, then legs.
HUMANOID_BONES: tuple[str, ...] = (
    TRUNK_BONES
    + tuple(f"{s}{p}" for s in SIDES for p in ARM_PARTS)
    + tuple(f"{s}{p}" for s in SIDES for p in LEG_PARTS)
)
#: The bones a rig must have to be read as a humanoid (VRM 1.0's required set).
REQUIRED_BONES: tuple[str, ...] = ("hips", "spine", "head") + tuple(
    f"{s}{p}" for s in SIDES for p in ("UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot"))

#: Pole name -> the canonical bone a pole target bends (the middle joint of a two-bone limb): knees and elbows.
POLE_BONES = {"left_knee": "leftLowerLeg", "right_knee": "rightLowerLeg", "left_elbow": "leftLowerArm",
              "right_elbow": "rightLowerArm"}

#: The bundled biped's frames by canonical bone (its ``left_shoulder`` is the arm; it has no clavicle).
BIPED_FRAMES = {
    "hips": "pelvis", "spine": "waist", "neck": "neck", "head": "atlas",
    **{f"{s}{p}": f"{s}_{f}" for s in SIDES for p, f in (
        ("UpperArm", "shoulder"), ("LowerArm", "elbow"), ("Hand", "hand"),
        ("UpperLeg", "hip"), ("LowerLeg", "knee"), ("Foot", "ankle"), ("Toes", "toe"))},
}

__all__ = ["HUMANOID_BONES", "REQUIRED_BONES", "BIPED_FRAMES", "TRUNK_BONES", "ARM_PARTS", "LEG_PARTS", "SIDES"]
