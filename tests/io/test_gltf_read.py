"""Reading skinned glTF characters that Blender made (several namings, T- and A-pose, extra bones) into gsik."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
from blender.gltf_characters import LAYOUT, NAMINGS, Spec, blender_read

import gsik
from gsik.io.gltf import read_character, read_gltf, write_gltf
from gsik.humanoid.bones import POLE_BONES
from gsik.io.gltf.character import EFFECTOR_BONES
from gsik.anim.motion import Motion

SPECS = [Spec("mixamo", "T", True), Spec("unreal", "A", True), Spec("vrm", "T"), Spec("rigify", "A"),
         Spec("vrm", "A", True, ending=".gltf")]
IDS = [s.stem + s.ending for s in SPECS]


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_skin_joints_become_ball_joints_at_the_files_rest(spec, blender_character):
    path = blender_character(spec)
    character = read_character(path)
    sk = character.skeleton
    skin_names = [character.file.nodes[n].name for n in character.file.skins[character.skin].joints]
    assert set(skin_names) <= set(sk.joint_names)
    for name in skin_names:
        dofs = sk.joint_dofs[sk.joint_names.index(name)]
        assert [sk.dof_names[d] for d in dofs] == [f"{name}.x", f"{name}.y", f"{name}.z"]
    # the rest pose (all angles 0) puts every joint where Blender's importer puts the bone's head
    blender = blender_read(path)
    at_rest = sk.frame_transforms(np.zeros(sk.n_dofs))[sk.joint_frame][:, :3, 3]
    heads = dict(zip(blender["bones"], blender["rest_heads"]))
    for j, name in enumerate(sk.joint_names):
        if name in heads:
            np.testing.assert_allclose(at_rest[j], heads[name], atol=1e-5, err_msg=name)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_recognition_places_effectors_root_and_poles(spec, blender_character):
    character = read_character(blender_character(spec))
    sk = character.skeleton
    name = NAMINGS[spec.naming]
    assert set(character.effectors) == set(EFFECTOR_BONES)
    assert sk.root == character.effectors["right_foot"]
    for effector, bone in EFFECTOR_BONES.items():
        site = character.effectors[effector]
        assert site in sk.effector_sites
        parent = sk.frame_parent[sk.site_frame[sk.site_names.index(site)]]
        assert sk.joint_frame[sk.joint_names.index(name(bone))] == parent, effector
    assert character.poles == {pole: name(bone) for pole, bone in POLE_BONES.items()}


@pytest.mark.parametrize("spec", SPECS[:2], ids=IDS[:2])
def test_recognised_joints_get_human_ranges_and_the_rest_stay_at_rest(spec, blender_character):
    character = read_character(blender_character(spec))
    sk = character.skeleton
    name = NAMINGS[spec.naming]
    recognised = {name(b) for b in LAYOUT}
    for j, joint in enumerate(sk.joint_names[1:], start=1):
        ranges = sk.upper[list(sk.joint_dofs[j])] - sk.lower[list(sk.joint_dofs[j])]
        if joint in recognised:
            assert np.all(ranges > 0) and np.all(ranges <= 2 * math.pi), joint
        else:  # twist, fingers, props, Unreal's root
            assert np.all(ranges == 0), joint
    # a knee bends one way only: its hinge range is lopsided, the foot goes back when it bends
    knee = sk.joint_names.index(name("leftLowerLeg"))
    lo, hi = sk.lower[list(sk.joint_dofs[knee])], sk.upper[list(sk.joint_dofs[knee])]
    hinge = int(np.argmax(hi - lo))
    assert hi[hinge] - lo[hinge] > math.radians(140)
    q = np.zeros(sk.n_dofs)
    q[sk.joint_dofs[knee][hinge]] = hi[hinge] if hi[hinge] > -lo[hinge] else lo[hinge]
    foot = sk.joint_frame[sk.joint_names.index(name("leftFoot"))]
    bent = sk.frame_transforms(q)[foot][:3, 3] - sk.frame_transforms(np.zeros(sk.n_dofs))[foot][:3, 3]
    assert bent[1] > 0.1  # Blender's character faces -y: the foot swings to +y, behind it


@pytest.mark.parametrize("spec", SPECS[:1] + SPECS[-1:], ids=IDS[:1] + IDS[-1:])
def test_meshes_keep_vertices_normals_weights_and_colours(spec, blender_character):
    path = blender_character(spec)
    file = read_gltf(path)
    skinned = [(n, p) for n in file.nodes if n.mesh >= 0 and n.skin >= 0 for p in file.meshes[n.mesh].primitives]
    assert skinned
    for node, prim in skinned:
        n = len(prim.positions)
        assert n > 100 and prim.normals.shape == (n, 3) and prim.triangles.max() < n
        np.testing.assert_allclose(np.linalg.norm(prim.normals, axis=1), 1.0, atol=1e-3)
        np.testing.assert_allclose(prim.weights.sum(axis=1), 1.0, atol=1e-9)
        assert prim.joints.max() < len(file.skins[node.skin].joints)
        assert prim.base_color.shape == (4,)
    skin = file.skins[0]
    assert skin.inverse_bind.shape == (len(skin.joints), 4, 4)
    # inverse bind matrices undo each joint's rest world transform (Blender binds at rest)
    from gsik.io.gltf.axes import node_world

    world = node_world(file.nodes)
    for s, node in enumerate(skin.joints):
        np.testing.assert_allclose(world[node] @ skin.inverse_bind[s], np.eye(4), atol=1e-4)


def test_a_gltf_with_its_buffer_embedded_reads_as_the_glb(blender_character, tmp_path):
    glb = blender_character(Spec("vrm", "T"))
    character = read_character(glb)
    sk = character.skeleton
    rest = Motion(sk, np.zeros((1, sk.n_dofs)), (sk.root,), gsik.Solver(sk).world_from_root[None], 1 / 30)
    embedded = tmp_path / "embedded.gltf"
    write_gltf(embedded, character, rest)
    assert b'"uri":"data:application/octet-stream;base64,' in embedded.read_bytes().replace(b" ", b"")
    again = read_character(embedded)
    assert again.skeleton.dof_names == sk.dof_names
    np.testing.assert_allclose(again.skeleton.frame_offset, sk.frame_offset, atol=1e-6)


def test_an_external_buffer_is_read_from_the_files_folder(blender_character, tmp_path):
    source = blender_character(Spec("vrm", "A", True, ending=".gltf"))
    for f in source.parent.glob(source.stem + ".*"):
        shutil.copy(f, tmp_path / f.name)
    assert (tmp_path / (source.stem + ".bin")).exists()
    file = read_gltf(tmp_path / source.name)
    assert file.buffers and len(file.buffers[0]) == file.document.buffers[0].byteLength
