"""Pole targets on Blender-made glTF characters, no window: their recognised knees and elbows get poles.

Each naming's own joint names (``mixamorig:LeftLeg``, ``calf_l``, ``LeftLowerLeg``, ``DEF-shin.L``) are found by the
humanoid recognition; the poles rest and swing the limbs as the biped's do (tests/app/test_poles.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from blender.gltf_characters import NAMINGS, Spec
from test_poles import _expected_swing, settle

import gsik
from gsik.humanoid.bones import POLE_BONES
from gsik_studio.model import Document
from gsik_studio.model.characters import open_character
from gsik_studio.model.pins import is_pinned
from gsik_studio.model.pole_places import limb_of, pole_joints, swing_angle

#: Every naming, with A and T rests across them.
SPECS = {naming: Spec(naming, "A" if k % 2 else "T") for k, naming in enumerate(NAMINGS)}
SPECS_BY_NAME = {spec.stem: naming for naming, spec in SPECS.items()}


@pytest.fixture(params=list(SPECS), scope="module")
def crouched(request, blender_character):
    """(character, pose) of a character crouched 8 cm (its knees bend), settled."""
    character = open_character(blender_character(SPECS[request.param]))
    doc = Document(character.skeleton)
    settle(doc)
    pelvis = character.effectors["pelvis"]
    doc.move_target(pelvis, doc.targets[pelvis].position + (0.0, 0.0, -0.08))
    assert settle(doc)
    return character, doc.pose()


@pytest.fixture()
def doc(crouched):
    character, pose = crouched
    d = Document(character.skeleton)
    d.set_pose(pose)
    assert settle(d)
    return character, d


def test_the_recognised_knees_and_elbows_get_poles_in_front_of_the_knees_behind_the_elbows(doc):
    character, doc = doc
    name = NAMINGS[SPECS_BY_NAME[character.name]]
    expected = tuple(name(bone) for bone in POLE_BONES.values())
    assert doc.controls.pole_joints == expected == tuple(character.poles.values())
    P0 = doc.world_positions().copy()
    doc.controls.set_poles(True)
    assert set(doc.controls.poles) == set(expected)
    assert settle(doc)
    forward = np.asarray(character.recognition.forward)
    for joint, bone in zip(expected, POLE_BONES):
        limb = limb_of(doc.skeleton, joint)
        out = doc.controls.poles[joint].position - P0[limb.joint]
        # Knees bend forward, elbows back; an elbow's hinge is the rig's local axis nearest the vertical (Blender's
        # bone roll tilts it: on a straight T-pose arm the pole may rest behind and below the elbow).
        way, least = (1.0, 0.9) if "knee" in bone else (-1.0, 0.0)
        assert way * out @ forward > least * np.linalg.norm(out), (joint, out)
    knees = [doc.skeleton.frame_of(j) for j in expected[:2]]
    # Placing moves nothing, but the posture's settling may resume when the targets change (as on the biped)
    assert np.linalg.norm(doc.world_positions()[knees] - P0[knees], axis=1).max() < 2e-2


@pytest.mark.parametrize("sideways", [-0.12, 0.12])
def test_a_knee_pole_moved_sideways_swings_the_knee_and_nothing_pinned(doc, sideways):
    character, doc = doc
    doc.controls.set_poles(True)
    assert settle(doc)
    knee = doc.controls.pole_joints[0]
    limb = limb_of(doc.skeleton, knee)
    pinned = [character.effectors[n] for n in ("pelvis", "left_foot")]
    ends = {n: doc.effector_poses()[n][:3, 3].copy() for n in pinned}
    P0, pole0 = doc.world_positions(), doc.controls.poles[knee].position.copy()
    to = pole0 + (sideways, 0.0, 0.0)
    doc.controls.move_pole(knee, to)
    assert settle(doc)
    expected = _expected_swing(limb, P0, pole0, to)
    assert np.degrees(abs(expected)) > 8.0
    assert swing_angle(limb, P0, doc.world_positions()) == pytest.approx(expected, abs=np.radians(1.0))
    for n in pinned:
        assert np.linalg.norm(doc.effector_poses()[n][:3, 3] - ends[n]) < 1e-4


@pytest.mark.parametrize("naming", list(NAMINGS))
def test_every_naming_opens_with_its_pelvis_and_feet_pinned_by_name(naming, blender_character):
    """The studio pins ``pelvis`` and the feet by name: every naming's effectors carry the biped's names."""
    doc = Document(open_character(blender_character(Spec(naming, "A"))).skeleton)
    assert {n for n, t in doc.targets.items() if is_pinned(t)} == {"pelvis", "left_foot"}  # the right foot: root


def test_a_skeleton_that_is_no_humanoid_gets_no_poles():
    sk = gsik.skeleton_from_yaml("""
name: arm
root: base
effectors: [base, tip]
joints:
  - {name: shoulder, offset: [0, 0, 1], rotations: [{axis: x, limits: [-1, 1]}]}
  - {name: elbow, parent: shoulder, offset: [0, 0, 0.3], rotations: [{axis: x, limits: [0, 2]}]}
sites:
  - {name: base, parent: shoulder, offset: [0, 0, 0]}
  - {name: tip, parent: elbow, offset: [0, 0, 0.3]}
""")
    assert pole_joints(sk, ("left_knee",)) == ()
    assert Document(sk).controls.pole_joints == ()

