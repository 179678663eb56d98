"""Humanoid recognition: which joint of any rig is the hips, the spine, each arm's and leg's bones.

Plain data in (:class:`Rig`: names, parents, rest positions) and out
(:class:`Recognition`: canonical VRM 1.0 / Unity Humanoid bone -> joint, with
confidence and method). Names first (Mixamo, Character Creator, Unreal,
Unity/VRM, Rigify, 3ds Max Biped, Daz, MakeHuman, CMU ASF, mocap
``Collar``/``Shoulder`` rigs), the tree's structure where names fail, a
mapping over both.
"""

from gsik.humanoid.bones import HUMANOID_BONES, REQUIRED_BONES
from gsik.humanoid.recognise import Recognition, recognise
from gsik.humanoid.rig import Rig, rig_from_clip, rig_from_skeleton

__all__ = ["Rig", "Recognition", "recognise", "HUMANOID_BONES", "REQUIRED_BONES", "rig_from_clip",
           "rig_from_skeleton"]
