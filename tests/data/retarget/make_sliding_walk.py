"""Writes tests/data/retarget/long_shin_walk.bvh: run from the repository root.

The biped's own walk (the root swaps feet, so planted feet do not move), on a biped whose shins are 8 cm longer
and thighs 8 cm shorter, exported at 30 fps with Mixamo-style joint names. Retargeted onto the plain biped by bone
directions at the biped's lengths, its planted feet slide: the case contact pinning is for.
"""
import dataclasses
import re

from gsik import load_skeleton
from gsik.anim.gait import WalkParameters, walk
from gsik.io.bvh import BvhClip, write_bvh
from gsik.io.bvh_skeleton import motion_to_bvh

NAMES = {"hips": "Hips", "waist": "Spine", "neck": "Neck", "atlas": "Head", "head_top": "HeadTop"}
for side, s in (("left", "Left"), ("right", "Right")):
    NAMES.update({f"{side}_hip": f"{s}UpLeg", f"{side}_knee": f"{s}Leg", f"{side}_ankle": f"{s}Foot",
                  f"{side}_toe": f"{s}ToeBase", f"{side}_shoulder": f"{s}Arm", f"{side}_elbow": f"{s}ForeArm",
                  f"{side}_hand": f"{s}Hand"})

text = open("skeletons/biped.yaml").read()
text = re.sub(r"(name: (left|right)_knee\n    parent: \w+\n    offset: \[0.0, 0.0, )-0.42", r"\1-0.34", text)
text = re.sub(r"(name: (left|right)_ankle\n    parent: \w+\n    offset: \[0.0, 0.0, )-0.40", r"\1-0.48", text)
open("/tmp/long_shin_biped.yaml", "w").write(text)
sk = load_skeleton("/tmp/long_shin_biped.yaml")
motion = walk(sk, WalkParameters(n_steps=4, fps=30.0)).motion
clip = motion_to_bvh(motion, units="cm", up="y")
names = [NAMES.get(j.name, j.name) for j in clip.joints]
names = [f"{names[j.parent]}_end" if j.is_end_site else n for j, n in zip(clip.joints, names)]  # as a reader names them
joints = tuple(dataclasses.replace(j, name=n) for j, n in zip(clip.joints, names))
write_bvh("tests/data/retarget/long_shin_walk.bvh", BvhClip(joints, clip.frame_time, clip.motion), precision=4)
