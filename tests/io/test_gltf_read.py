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
    assert set(skin_names) <= set(character.file_names)
    for name in skin_names:
        joint = sk.joint_names[character.file_names.index(name)]
        assert joint == (f"{name}_joint" if name in EFFECTOR_BONES else name)  # Unreal's head and pelvis
        dofs = sk.joint_dofs[sk.joint_names.index(joint)]
        assert [sk.dof_names[d] for d in dofs] == [f"{joint}.x", f"{joint}.y", f"{joint}.z"]
    # the rest pose (all angles 0) puts every joint where Blender's importer puts the bone's head
    blender = blender_read(path)
    at_rest = sk.frame_transforms(np.zeros(sk.n_dofs))[sk.joint_frame][:, :3, 3]
    heads = dict(zip(blender["bones"], blender["rest_heads"]))
    for j, name in enumerate(character.file_names):
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
        assert sk.joint_frame[character.file_names.index(name(bone))] == parent, effector
    assert character.poles == {pole: name(bone) for pole, bone in POLE_BONES.items()}


@pytest.mark.parametrize("spec", SPECS[:2], ids=IDS[:2])
def test_recognised_joints_get_human_ranges_and_the_rest_stay_at_rest(spec, blender_character):
    character = read_character(blender_character(spec))
    sk = character.skeleton
    name = NAMINGS[spec.naming]
    recognised = {name(b) for b in LAYOUT}
    for j, joint in enumerate(character.file_names[1:], start=1):
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


@pytest.mark.parametrize("naming", list(NAMINGS))
def test_every_naming_has_the_biped_s_effector_names(naming, blender_character):
    """Unreal's ``head`` and ``pelvis`` bones once gave ``head_site``/``pelvis_site``: now every naming's effectors
    are the biped's (``head``, ``pelvis``, ``left_hand`` ...); a bone named so is the joint ``<name>_joint``."""
    character = read_character(blender_character(Spec(naming, "A")))
    sk = character.skeleton
    assert dict(character.effectors) == {e: e for e in EFFECTOR_BONES}
    assert set(sk.effector_sites) == set(EFFECTOR_BONES)
    renamed = {f: j for f, j in zip(character.file_names, sk.joint_names) if f != j}
    assert renamed == ({"pelvis": "pelvis_joint", "head": "head_joint"} if naming == "unreal" else {})
    assert character.recognition.bones["head"] == renamed.get("head", NAMINGS[naming]("head"))


def test_a_pose_file_with_the_old_unreal_names_still_reads(blender_character, tmp_path):
    """A pose (with a clip) saved when the Unreal character's effectors were ``head_site``/``pelvis_site`` and its
    joints ``head``/``pelvis`` reads as the same pose on today's names; a name that is neither is still refused."""
    from gsik.io.pose import Clip, Pose, pose_to_yaml, read_pose

    character = read_character(blender_character(Spec("unreal", "A")))
    sk = character.skeleton
    solver = gsik.Solver(sk)
    q = np.clip(np.linspace(-0.3, 0.3, sk.n_dofs), sk.lower, sk.upper)
    W = solver.world_from_root
    targets = {n: gsik.Target.from_transform(T) for n, T in solver.effector_poses().items()}
    pose = Pose(sk.name, sk.root, tuple(W[:3, 3]), (1.0, 0.0, 0.0, 0.0), dict(zip(sk.dof_names, q.tolist())),
                targets)
    clip = Clip("c", Motion(sk, np.stack([q, q]), (sk.root,) * 2, np.stack([W, W]), 1 / 30))
    text = pose_to_yaml(pose, clip=clip, skeleton=sk)
    old = text
    for name in ("head", "pelvis"):
        old = old.replace(f"{name}_joint.", f"{name}.").replace(f"  {name}:", f"  {name}_site:")
    assert old != text and "head_site:" in old and "pelvis.x" in old and "head_joint" not in old
    (tmp_path / "old.yaml").write_text(old, encoding="utf-8")
    got = read_pose(tmp_path / "old.yaml", sk)
    assert got.pose == read_pose_text(text, sk, tmp_path).pose
    np.testing.assert_array_equal(got.clip.motion.q, clip.motion.q)
    (tmp_path / "bad.yaml").write_text(old.replace("head_site:", "neck_site:"), encoding="utf-8")
    with pytest.raises(gsik.PoseError, match="unknown effector 'neck_site'"):
        read_pose(tmp_path / "bad.yaml", sk)


def read_pose_text(text, sk, folder):
    from gsik.io.pose import read_pose

    (folder / "new.yaml").write_text(text, encoding="utf-8")
    return read_pose(folder / "new.yaml", sk)
