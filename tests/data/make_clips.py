"""Writes tests/data/wrap_channel.bvh and tests/data/up_misleading_first_frame.bvh: run from the repository root."""
import numpy as np
from gsik.io.bvh import BvhClip, BvhJoint, write_bvh

ROOT = ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
ZYX = ("Zrotation", "Yrotation", "Xrotation")

def body(spine, arm, hand, leg, foot, toe):
    return (
        BvhJoint("Hips", -1, (0, 0, 0), ROOT),
        BvhJoint("Spine", 0, spine, ZYX),
        BvhJoint("LeftArm", 1, arm, ZYX),
        BvhJoint("LeftHand", 2, hand, ZYX),
        BvhJoint("LeftHand_end", 3, (10, 0, 0) if hand[0] else (0, 0, 10), is_end_site=True),
        BvhJoint("LeftLeg", 0, leg, ZYX),
        BvhJoint("LeftFoot", 5, foot, ZYX),
        BvhJoint("LeftFoot_end", 6, toe, is_end_site=True),
    )

# A y-up clip whose spine turns about y back and forth across +-180 degrees: written wrapped, as exporters do.
F = 40
t = np.arange(F)
spine_y = 180.0 + 40.0 * np.sin(t / 4.0)
wrapped = np.remainder(spine_y + 180.0, 360.0) - 180.0
m = np.zeros((F, 6 + 5 * 3))
m[:, 0] = 2.0 * t
m[:, 1] = 95.0
m[:, 7] = wrapped                       # Spine Yrotation
m[:, 9] = 30.0 * np.sin(t / 5.0)        # LeftArm Zrotation
m[:, 13] = 20.0 + 10 * np.sin(t / 3.0)  # LeftHand Yrotation
m[:, 17] = 20.0 * np.sin(t / 6.0)       # LeftLeg Xrotation
joints = body((0, 40, 0), (15, 10, 0), (25, 0, 0), (10, -45, 0), (0, -45, 0), (0, -5, 12))
write_bvh("tests/data/wrap_channel.bvh", BvhClip(joints, 1 / 30, m), precision=4)

# A y-up clip modelled lying along +z (rest pose) whose first frame lies on the floor too; from frame 1 on the
# root's Xrotation -90 stands it up along +y and it walks along x.
F = 30
m = np.zeros((F, 6 + 5 * 3))
m[:, 0] = 3.0 * t[:F]
m[0, 1], m[1:, 1] = 10.0, 95.0
m[1:, 5] = -90.0                              # Hips Xrotation: z -> y
m[:, 17] = 25.0 * np.sin(t[:F] / 3.0)         # LeftLeg Xrotation
m[:, 9] = 20.0 * np.sin(t[:F] / 4.0)          # LeftArm Zrotation
joints = body((0, 0, 40), (15, 0, 10), (25, 0, 0), (10, 0, -45), (0, 0, -45), (0, 12, -5))
write_bvh("tests/data/up_misleading_first_frame.bvh", BvhClip(joints, 1 / 30, m), precision=4)
