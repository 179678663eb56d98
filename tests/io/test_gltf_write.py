"""Writing posed and animated characters as glTF, checked by real consumers: Khronos' validator and Blender."""

from __future__ import annotations

import json

import numpy as np
import pytest
from blender.gltf_characters import NAMINGS, Spec, blender_read
from gltf_validator import assert_valid

import gsik
from gsik.anim.motion import Motion
from gsik.io.gltf import character_from_skeleton, read_character, read_gltf, write_gltf
from gsik.io.gltf.axes import gsik_from_gltf, node_world
from gsik.io.gltf.binding import skin_binding
from gsik.skinning import skinned

SPECS = [Spec("mixamo", "T", True), Spec("unreal", "A", True), Spec("vrm", "T"), Spec("rigify", "A")]
IDS = [s.stem for s in SPECS]


def _posed(character, naming: str) -> np.ndarray:
    """Angles (n_dofs,) that crouch the character and reach its left hand forward, solved by gsik."""
    sk = character.skeleton
    solver = gsik.Solver(sk)
    targets = {n: gsik.Target.from_transform(T) for n, T in solver.effector_poses().items()}
    e = character.effectors
    targets[e["pelvis"]] = targets[e["pelvis"]].replace(position=targets[e["pelvis"]].position + [0, 0, -0.08])
    targets[e["left_hand"]] = gsik.Target(targets[e["left_hand"]].position + [-0.25, -0.3, -0.2], position_only=True)
    for _ in range(40):
        solver.step(targets)
    return solver.q, solver.world_from_root


def _motion(sk, qs, W, frame_time=0.25) -> Motion:
    qs = np.atleast_2d(qs)
    return Motion(sk, qs, (sk.root,) * len(qs), np.broadcast_to(W, (len(qs), 4, 4)), frame_time)


def _world(sk, q, W) -> np.ndarray:
    """(n_frames, 4, 4) every frame's world transform at a pose."""
    from gsik.kinematics import world_frames

    R, p = world_frames(sk, q, W, sk.root)
    T = np.zeros((sk.n_frames, 4, 4))
    T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = R, p, 1.0
    return T


def _assert_heads(blender_heads, bones, sk, T, names=None):
    """Blender's posed bone heads on gsik's forward kinematics (same world: both turn the file z up); ``names``:
    the file's name of each joint (a character's :attr:`file_names`), the joints' own by default."""
    P = T[sk.joint_frame][:, :3, 3]
    assert len(bones) == len(blender_heads) >= 13
    for bone, head in zip(bones, blender_heads):
        np.testing.assert_allclose(head, P[(names or sk.joint_names).index(bone)], atol=2e-5, err_msg=bone)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_a_posed_character_validates_and_blender_shows_gsiks_pose_and_skin(spec, blender_character, tmp_path):
    character = read_character(blender_character(spec))
    sk = character.skeleton
    q, W = _posed(character, spec.naming)
    assert np.abs(q).max() > 0.05
    out = tmp_path / "posed.glb"
    write_gltf(out, character, _motion(sk, q, W))
    assert_valid(out)
    got = blender_read(out)
    T = _world(sk, q, W)
    _assert_heads(got["pose_heads"], got["bones"], sk, T, character.file_names)
    # Blender's deformed mesh is gsik's linear blend skinning, vertex for vertex
    points, _ = skinned(skin_binding(character), T)
    np.testing.assert_allclose(np.array(got["mesh_points"]), points, atol=2e-5)


@pytest.mark.parametrize("spec", SPECS[:2], ids=IDS[:2])
def test_an_animation_plays_in_blender_as_gsik_solved_it(spec, blender_character, tmp_path):
    character = read_character(blender_character(spec))
    sk = character.skeleton
    q, W = _posed(character, spec.naming)
    qs = np.stack([np.zeros(sk.n_dofs), 0.5 * q, q])
    out = tmp_path / "anim.glb"
    write_gltf(out, character, _motion(sk, qs, W, 0.5))
    assert_valid(out)
    got = blender_read(out, times=[0.0, 0.5, 1.0])
    for f, t in enumerate((0.0, 0.5, 1.0)):
        _assert_heads(got["heads"][t], got["bones"], sk, _world(sk, qs[f], W), character.file_names)


def test_an_animation_has_one_channel_per_moved_joint_and_the_roots_translation(blender_character, tmp_path):
    character = read_character(blender_character(Spec("vrm", "T")))
    sk = character.skeleton
    q = np.zeros(sk.n_dofs)
    q[sk.dof_index("LeftLowerArm.x")] = 0.4
    q[sk.dof_index("Head.y")] = 0.2
    out = tmp_path / "anim.gltf"
    write_gltf(out, character, _motion(sk, [np.zeros(sk.n_dofs), q], gsik.Solver(sk).world_from_root))
    assert_valid(out)
    doc = json.loads(out.read_text(encoding="utf-8"))
    channels = {(doc["nodes"][c["target"]["node"]]["name"], c["target"]["path"]) for c in doc["animations"][-1]["channels"]}
    assert channels == {("LeftLowerArm", "rotation"), ("Head", "rotation"), ("Hips", "translation")}


@pytest.mark.parametrize("spec", SPECS[:2], ids=IDS[:2])
def test_everything_but_the_joints_transforms_is_kept(spec, blender_character, tmp_path):
    source = blender_character(spec)
    character = read_character(source)
    sk = character.skeleton
    q, W = _posed(character, spec.naming)
    out = tmp_path / "kept.glb"
    write_gltf(out, character, _motion(sk, q, W))
    before, after = read_gltf(source), read_gltf(out)
    joints = set(before.skins[0].joints)
    assert [n.name for n in after.nodes] == [n.name for n in before.nodes]
    for a, b in zip(before.nodes, after.nodes):
        assert (a.parent, a.mesh, a.skin) == (b.parent, b.mesh, b.skin)
    for i, (a, b) in enumerate(zip(before.nodes, after.nodes)):
        if i not in joints:  # the armature, the mesh node: untouched
            np.testing.assert_array_equal(a.translation, b.translation)
            np.testing.assert_array_equal(a.rotation, b.rotation)
        np.testing.assert_allclose(a.scale, b.scale)
    for ma, mb in zip(before.meshes, after.meshes):
        for pa, pb in zip(ma.primitives, mb.primitives):
            for field in ("positions", "normals", "triangles", "joints", "weights", "base_color"):
                np.testing.assert_array_equal(getattr(pa, field), getattr(pb, field), err_msg=field)
    np.testing.assert_array_equal(before.skins[0].inverse_bind, after.skins[0].inverse_bind)
    assert after.document.materials == before.document.materials
    # and the posed joints are where gsik's forward kinematics has them
    world = gsik_from_gltf(node_world(after.nodes))
    T = _world(sk, q, W)
    for node in joints:
        j = character.joint_nodes.index(node)
        np.testing.assert_allclose(world[node][:3, 3], T[sk.joint_frame[j]][:3, 3], atol=1e-6)
    # the prop bone (an extra node under the right hand) moved with the hand
    name = NAMINGS[spec.naming]
    prop = [i for i, n in enumerate(after.nodes) if n.name == "prop_sword"][0]
    hand = sk.joint_frame[sk.joint_names.index(name("rightHand"))]
    rest_hand = sk.frame_transforms(np.zeros(sk.n_dofs))[hand]
    expected = T[hand] @ np.linalg.inv(rest_hand) @ gsik_from_gltf(node_world(before.nodes))[prop]
    np.testing.assert_allclose(world[prop], expected, atol=1e-6)


def test_the_biped_exports_with_its_mannequin_as_a_skinned_body(tmp_path):
    biped = gsik.load_skeleton("biped")
    character = character_from_skeleton(biped)
    assert character.file.n_vertices > 1000
    solver = gsik.Solver(biped)
    q = np.clip(biped.rest + 0.3, biped.lower, biped.upper)
    out = tmp_path / "biped.glb"
    write_gltf(out, character, _motion(biped, [biped.rest, q], solver.world_from_root))
    assert_valid(out)
    got = blender_read(out, times=[0.0, 0.25])
    assert got["meshes"] and len(got["mesh_points"]) == character.file.n_vertices
    for f, qf in enumerate((biped.rest, q)):
        _assert_heads(got["heads"][0.25 * f], got["bones"], biped, _world(biped, qf, solver.world_from_root))
    points, _ = skinned(skin_binding(character), _world(biped, q, solver.world_from_root))
    np.testing.assert_allclose(np.array(got["mesh_points"]), points, atol=2e-5)
