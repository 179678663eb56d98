"""``gsik export-gltf``: pose files and BVH clips out as glTF, checked by the validator and Blender's importer."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from blender.gltf_characters import Spec, blender_read
from gltf_validator import assert_valid

import gsik
from gsik.cli import main
from gsik.io.bvh import read_bvh
from gsik.io.bvh_skeleton import import_bvh
from gsik.io.gltf import read_character
from gsik.io.pose import Pose, read_pose, write_pose
from gsik.kinematics import world_frames

ROOT = Path(__file__).resolve().parents[2]
POSE = ROOT / "docs" / "studio_pose.yaml"
CLIP = ROOT / "tests" / "data" / "walk_zxy.bvh"


def _heads(sk, q, W, root):
    """(n_joints, 3) world positions of the joints [m]."""
    R, p = world_frames(sk, q, W, root)
    return p[sk.joint_frame]


def _assert_blender_on(got_heads, bones, sk, P, names=None):
    """Blender's bone heads on gsik's joints P (n_joints, 3); ``names``: the file's name of each joint."""
    assert bones and len(bones) == len(got_heads)
    for bone, head in zip(bones, got_heads):
        np.testing.assert_allclose(head, P[(names or sk.joint_names).index(bone)], atol=2e-5, err_msg=bone)


def test_a_biped_pose_file_exports_with_its_mannequin(tmp_path, capsys):
    out = tmp_path / "pose.glb"
    assert main(["export-gltf", str(POSE), "--out", str(out)]) == 0
    assert "the pose on 'biped'" in capsys.readouterr().out
    assert_valid(out)
    biped = gsik.load_skeleton("biped")
    pose = read_pose(POSE, biped).pose
    got = blender_read(out)
    assert got["meshes"]
    _assert_blender_on(got["pose_heads"], got["bones"], biped,
                       _heads(biped, pose.q(biped), pose.world_from_root, pose.root))


def test_a_bvh_clip_exports_as_an_animation_of_its_own_skeleton(tmp_path):
    out = tmp_path / "walk.gltf"
    assert main(["export-gltf", str(CLIP), "--out", str(out)]) == 0
    assert_valid(out)
    imported = import_bvh(read_bvh(CLIP))
    motion = imported.motion
    frames = [0, motion.n_frames // 2, motion.n_frames - 1]
    got = blender_read(out, times=[f * motion.frame_time for f in frames])
    for f in frames:
        P = _heads(imported.skeleton, motion.q[f], motion.world_from_root[f], motion.roots[f])
        _assert_blender_on(got["heads"][f * motion.frame_time], got["bones"], imported.skeleton, P)


def test_a_pose_of_a_gltf_character_exports_onto_that_character(tmp_path, blender_character):
    source = blender_character(Spec("mixamo", "A", True))
    character = read_character(source)
    sk = character.skeleton
    solver = gsik.Solver(sk)
    q = np.zeros(sk.n_dofs)
    q[sk.dof_index("mixamorig:LeftArm.x")] = 0.6  # a swing: Blender bones twist about y
    q = np.clip(q, sk.lower, sk.upper)
    W = solver.world_from_root
    pose = Pose(str(source), sk.root, tuple(W[:3, 3]), (1.0, 0.0, 0.0, 0.0) if np.allclose(W[:3, :3], np.eye(3))
                else tuple(gsik.rotations.quaternion_from_matrix(W[:3, :3])),
                dict(zip(sk.dof_names, q.tolist())),
                {n: gsik.Target.from_transform(T) for n, T in solver.effector_poses().items()})
    pose_file = tmp_path / "pose.yaml"
    write_pose(pose_file, pose)
    out = tmp_path / "posed.glb"
    assert main(["export-gltf", str(pose_file), "--out", str(out)]) == 0
    assert_valid(out)
    got = blender_read(out)
    _assert_blender_on(got["pose_heads"], got["bones"], sk, _heads(sk, q, W, sk.root), character.file_names)
    assert max(abs(np.array(h) - r).max() for h, r in zip(got["pose_heads"], got["rest_heads"])) > 0.05


def test_a_clip_of_another_rig_is_retargeted_onto_the_character(tmp_path, blender_character):
    from gsik.anim.retarget import Retargeter

    source = blender_character(Spec("unreal", "A", True))
    out = tmp_path / "walk_on_unreal.glb"
    assert main(["export-gltf", str(CLIP), "--character", str(source), "--out", str(out)]) == 0
    assert_valid(out)
    character = read_character(source)
    sk = character.skeleton
    clip = read_bvh(CLIP)
    motion = Retargeter(sk, clip, name=CLIP.name).retarget(clip).motion
    frames = [0, motion.n_frames - 1]
    got = blender_read(out, times=[f * motion.frame_time for f in frames])
    heads = []
    for f in frames:
        P = _heads(sk, motion.q[f], motion.world_from_root[f], motion.roots[f])
        _assert_blender_on(got["heads"][f * motion.frame_time], got["bones"], sk, P, character.file_names)
        heads.append(np.array(got["heads"][f * motion.frame_time]))
    assert np.abs(heads[1] - heads[0]).max() > 0.05  # the character walks
